use serde::Serialize;

use super::CliError;
use dormant::accel::bvh::SimdPath;
use dormant::accel::Backend;

/// What `dormant info` prints.
#[derive(Debug, Serialize)]
pub struct InfoReport {
    pub dormant_version: &'static str,
    pub backends: Vec<Backend>,
    /// The BVH backend's SIMD path (`DORMANT_SIMD`, else the fastest this CPU runs).
    pub simd_path: SimdPath,
    /// Every SIMD path this CPU runs.
    pub simd_paths_supported: Vec<SimdPath>,
    pub embree: Option<EmbreeInfo>,
    /// Intel Open Image Denoise (`render --denoise`), when compiled in.
    pub oidn: Option<OidnInfo>,
}

#[derive(Debug, Serialize)]
pub struct OidnInfo {
    /// Version of the library loaded at run time (from a CPU device).
    pub library_version: String,
    /// Directory of the library the build linked against.
    pub library_dir: &'static str,
}

#[derive(Debug, Serialize)]
pub struct EmbreeInfo {
    /// Version of the library loaded at run time.
    pub library_version: String,
    /// Version of the headers the bindings were generated from.
    pub header_version: String,
    /// Where the build found the headers.
    pub header_origin: &'static str,
    pub include_dir: &'static str,
}

impl InfoReport {
    pub fn collect(threads: Option<usize>) -> Result<Self, CliError> {
        Ok(Self {
            dormant_version: env!("CARGO_PKG_VERSION"),
            backends: Backend::compiled(),
            simd_path: SimdPath::current(),
            simd_paths_supported: SimdPath::supported(),
            embree: embree_info(threads)?,
            oidn: oidn_info(threads)?,
        })
    }
}

#[cfg(feature = "embree")]
fn embree_info(threads: Option<usize>) -> Result<Option<EmbreeInfo>, CliError> {
    use dormant_embree::{Device, Version};
    let device = Device::new(threads).map_err(|e| CliError::Runtime(e.to_string()))?;
    Ok(Some(EmbreeInfo {
        library_version: device.library_version().to_string(),
        header_version: Version::header().to_string(),
        header_origin: embree4_sys::HEADER_ORIGIN,
        include_dir: embree4_sys::HEADER_INCLUDE_DIR,
    }))
}

#[cfg(not(feature = "embree"))]
fn embree_info(_threads: Option<usize>) -> Result<Option<EmbreeInfo>, CliError> {
    Ok(None)
}

/// The OIDN version from a CPU device; `None` without the `oidn` feature.
fn oidn_info(threads: Option<usize>) -> Result<Option<OidnInfo>, CliError> {
    let Some(library_dir) = dormant::render::denoise::Denoiser::library_dir() else {
        return Ok(None);
    };
    let device =
        dormant::render::denoise::Denoiser::new(threads).map_err(|e| CliError::Runtime(e.to_string()))?;
    Ok(Some(OidnInfo { library_version: device.version(), library_dir }))
}

/// Prints the report as JSON, or writes it where `--json FILE` says.
pub(super) fn run(threads: Option<usize>, json: &super::JsonOutput) -> Result<(), CliError> {
    let report = serde_json::to_value(InfoReport::collect(threads)?).expect("info report serialises");
    if json.is_requested() {
        json.emit(&report)
    } else {
        println!("{report:#}");
        Ok(())
    }
}
