//! Denoising a rendered frame with Intel Open Image Denoise 2 (`render --denoise`): the HDR
//! beauty image with the first-hit albedo and shading normal AOVs as guides, through OIDN's
//! `RT` filter on its CPU device. The library comes in with the cargo feature `oidn`
//! (`ffi/oidn-sys`, installed by `scripts/setup.sh`); without it [`Denoiser::new`] returns
//! [`DenoiseError::NotCompiled`], which names what is missing and how to get it.
//!
//! OIDN's expectations, and how the inputs meet them: the beauty image is linear HDR radiance
//! (`hdr = true`; OIDN picks the exposure scale itself), non-negative and finite (anything
//! else is set to 0); the albedo is the textured base colour at the first hit, clamped to
//! [0, 1] (for metals that is their reflectivity at normal incidence, as OIDN recommends);
//! normals are world-space shading normals in [-1, 1]; both guides average the same pixel
//! samples as the beauty image (the same tent filter, importance-sampled), and pixels whose
//! camera ray escapes have albedo and normal 0. By default the guides are passed as they are,
//! noisy where a pixel's samples straddle an edge (`cleanAux` false, OIDN's fast path);
//! [`Denoiser::prefilter`] denoises them first and sets `cleanAux`.

#[cfg(feature = "oidn")]
mod oidn;

#[cfg(feature = "oidn")]
use std::time::Instant;

use glam::Vec3;

use super::{Aov, Film};
use crate::names::named_enum;

/// What can go wrong when denoising.
#[derive(Debug, thiserror::Error)]
pub enum DenoiseError {
    /// This build has no OIDN (cargo feature `oidn` off).
    #[error(
        "--denoise needs Intel Open Image Denoise 2, which this dormant was built without (cargo \
         feature `oidn`): run `scripts/setup.sh` (installs OIDN {OIDN_VERSION} into .deps/oidn), \
         then build with the default features"
    )]
    NotCompiled,
    /// The library loaded but could not make a CPU device (its CPU device module
    /// `libOpenImageDenoise_device_cpu` is missing, or the CPU is unsupported).
    #[error(
        "Intel Open Image Denoise could not create a CPU device: {message}. Its CPU device \
         module libOpenImageDenoise_device_cpu.so.{OIDN_VERSION} (and libtbb.so.12) must sit \
         beside libOpenImageDenoise_core in {lib_dir}: run `scripts/setup.sh` to reinstall it"
    )]
    NoDevice { message: String, lib_dir: String },
    /// The library is not OIDN 2.
    #[error("Intel Open Image Denoise {found} is linked, but dormant's bindings are for OIDN 2.x")]
    Version { found: String },
    /// An OIDN call failed: `oidnGetDeviceError`'s code and message.
    #[error("Intel Open Image Denoise: {call} failed ({code}): {message}")]
    Oidn { call: &'static str, code: &'static str, message: String },
}

impl DenoiseError {
    /// Whether the error is about the installation (the library or a part of it missing)
    /// rather than a failure while denoising.
    pub fn is_missing_library(&self) -> bool {
        matches!(
            self,
            DenoiseError::NotCompiled | DenoiseError::NoDevice { .. } | DenoiseError::Version { .. }
        )
    }
}

/// The OIDN version `scripts/setup.sh` installs.
pub(crate) const OIDN_VERSION: &str = "2.5.1";

/// The AOVs the denoiser takes as guides, rendered whenever a frame is denoised.
pub const GUIDE_AOVS: [Aov; 2] = [Aov::Albedo, Aov::Normal];

named_enum! {
    /// OIDN's filter quality (`--denoise-quality`, Cycles' "Denoising Quality"): which of its
    /// networks filters the image. Prefiltered guides are filtered at `balanced` when `fast` is
    /// asked for (OIDN has no fast guide filter).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum DenoiseQuality {
        /// The largest network: for final frames.
        #[default]
        High = "high",
        /// OIDN's middle setting (for interactive rendering). On the CPU device it gives `high`'s
        /// result unless the guides are prefiltered, where `high` takes a larger network.
        Balanced = "balanced",
        /// The smallest: fastest, for previews.
        Fast = "fast",
    }
}

/// An OIDN CPU device, made once and used for every frame of a run. Not `Sync`: OIDN reports
/// errors per thread, so one thread drives it.
pub struct Denoiser {
    /// Denoise the guides first and tell the filter they are clean (see [`Denoiser::prefilter`]).
    #[cfg_attr(not(feature = "oidn"), allow(dead_code))]
    prefilter: bool,
    #[cfg_attr(not(feature = "oidn"), allow(dead_code))]
    quality: DenoiseQuality,
    #[cfg(feature = "oidn")]
    device: oidn::OidnDevice,
    #[cfg(not(feature = "oidn"))]
    never: std::convert::Infallible,
}

impl Denoiser {
    /// Creates and commits a CPU device with `threads` worker threads (default: all cores).
    pub fn new(threads: Option<usize>) -> Result<Self, DenoiseError> {
        #[cfg(feature = "oidn")]
        {
            Ok(Self {
                prefilter: false,
                quality: DenoiseQuality::High,
                device: oidn::OidnDevice::new(threads)?,
            })
        }
        #[cfg(not(feature = "oidn"))]
        {
            let _ = threads;
            Err(DenoiseError::NotCompiled)
        }
    }

    /// With `on`, [`Denoiser::denoise`] first denoises the albedo and normal guides (OIDN's
    /// prefiltering, Cycles' "Accurate" prefilter) and then filters the image with `cleanAux`:
    /// OIDN's recommendation for final frames, at three filter runs instead of one (measured:
    /// docs/performance.md#denoising-render---denoise).
    pub fn prefilter(mut self, on: bool) -> Self {
        self.prefilter = on;
        self
    }

    /// Filters with OIDN's `quality` network (high by default).
    pub fn quality(mut self, quality: DenoiseQuality) -> Self {
        self.quality = quality;
        self
    }

    /// How frames are denoised, as stats and bench reports name it: `oidn`, `-prefilter` added
    /// with [`Denoiser::prefilter`] and `-balanced` or `-fast` with that [`Denoiser::quality`].
    pub fn label(&self) -> &'static str {
        match (self.prefilter, self.quality) {
            (false, DenoiseQuality::High) => "oidn",
            (false, DenoiseQuality::Balanced) => "oidn-balanced",
            (false, DenoiseQuality::Fast) => "oidn-fast",
            (true, DenoiseQuality::High) => "oidn-prefilter",
            (true, DenoiseQuality::Balanced) => "oidn-prefilter-balanced",
            (true, DenoiseQuality::Fast) => "oidn-prefilter-fast",
        }
    }

    /// The linked library's version, `major.minor.patch`.
    pub fn version(&self) -> String {
        #[cfg(feature = "oidn")]
        {
            self.device.version()
        }
        #[cfg(not(feature = "oidn"))]
        match self.never {}
    }

    /// Directory of the linked library.
    pub fn library_dir() -> Option<&'static str> {
        #[cfg(feature = "oidn")]
        {
            Some(oidn_sys::LIB_DIR)
        }
        #[cfg(not(feature = "oidn"))]
        None
    }

    /// Denoises `beauty` (linear HDR radiance) guided by the `albedo` and `normal` AOVs of the
    /// same frame; returns the denoised image and the seconds the filter took (setup,
    /// network and copies).
    pub fn denoise(&self, beauty: &Film, albedo: &Film, normal: &Film) -> Result<(Film, f64), DenoiseError> {
        for guide in [albedo, normal] {
            assert_eq!((guide.width, guide.height), (beauty.width, beauty.height), "guides match the image");
        }
        #[cfg(feature = "oidn")]
        {
            let start = Instant::now();
            let size = (beauty.width as usize, beauty.height as usize);
            let color = packed(&beauty.pixels, |p| p.max(Vec3::ZERO));
            let mut albedo = packed(&albedo.pixels, |p| p.clamp(Vec3::ZERO, Vec3::ONE));
            let mut normal = packed(&normal.pixels, |p| p.clamp(-Vec3::ONE, Vec3::ONE));
            let filter = |inputs: &[(&'static std::ffi::CStr, &[f32])], hdr, clean_aux| {
                let options = oidn::FilterOptions { hdr, clean_aux, quality: self.quality };
                self.device.filter_rt(size, inputs, options)
            };
            if self.prefilter {
                albedo = filter(&[(c"albedo", &albedo)], false, false)?;
                normal = filter(&[(c"normal", &normal)], false, false)?;
            }
            let output = filter(
                &[(c"color", &color), (c"albedo", &albedo), (c"normal", &normal)],
                true,
                self.prefilter,
            )?;
            let pixels =
                output.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2]).max(Vec3::ZERO)).collect();
            Ok((Film { width: beauty.width, height: beauty.height, pixels }, start.elapsed().as_secs_f64()))
        }
        #[cfg(not(feature = "oidn"))]
        match self.never {}
    }
}

/// Pixels as packed RGB floats brought into OIDN's range by `fix`; non-finite pixels become 0.
#[cfg_attr(not(feature = "oidn"), allow(dead_code))]
fn packed(pixels: &[Vec3], fix: impl Fn(Vec3) -> Vec3) -> Vec<f32> {
    pixels.iter().flat_map(|&p| if p.is_finite() { fix(p) } else { Vec3::ZERO }.to_array()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_are_brought_into_oidn_ranges() {
        let pixels = [Vec3::new(-0.5, 0.5, 2.0), Vec3::new(1.0, f32::NAN, 5.0)];
        let fixed = packed(&pixels, |p| p.clamp(Vec3::ZERO, Vec3::ONE));
        assert_eq!(fixed, vec![0.0, 0.5, 1.0, 0.0, 0.0, 0.0]);
    }

    #[cfg(not(feature = "oidn"))]
    #[test]
    fn without_the_feature_the_error_says_how_to_get_oidn() {
        let e = Denoiser::new(None).err().expect("no OIDN without the feature");
        assert!(e.is_missing_library());
        let text = e.to_string();
        assert!(text.contains("oidn") && text.contains("scripts/setup.sh"), "{text}");
    }
}
