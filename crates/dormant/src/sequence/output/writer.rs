//! [`FrameWriter`]: a rendered frame's files, written atomically; a reused frame's are copies
//! of the frame it repeats.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use super::{OutputError, OutputLayout};
use crate::render::denoise::Denoiser;
use crate::render::{write_aov_png_atomic, write_exr_atomic, write_png_atomic, Aov, Film};
use crate::sequence::RenderedFrame;

/// Writes each frame's files as its [`OutputLayout`] names them.
pub struct FrameWriter<'a> {
    pub layout: &'a OutputLayout,
    /// Exposure applied before tone mapping the PNGs.
    pub exposure: f32,
    /// With `--denoise`: the device every traced frame's image goes through (its albedo and
    /// normal guides are among the frame's AOVs).
    pub denoiser: Option<&'a Denoiser>,
}

/// What writing a frame did.
#[derive(Clone, Debug, PartialEq)]
pub struct WrittenFrame {
    /// Every file written, in [`OutputLayout::frame_files`] order; the image first.
    pub files: Vec<PathBuf>,
    /// Seconds the denoiser took (`None` without one, or for a reused frame).
    pub denoise_seconds: Option<f64>,
}

impl FrameWriter<'_> {
    /// Writes `frame`'s files.
    pub fn write(&self, frame: &RenderedFrame) -> Result<WrittenFrame, OutputError> {
        let files = self.layout.frame_files(frame.index);
        let denoise_seconds = match frame.reused_from {
            Some(source) => {
                for (from, to) in self.layout.frame_files(source).iter().zip(&files) {
                    copy_atomic(from, to)?;
                }
                None
            }
            None => self.write_images(frame, &files)?,
        };
        Ok(WrittenFrame { files, denoise_seconds })
    }

    /// Encodes the image (denoised with a denoiser), the noisy image (`keep_noisy`) and the
    /// layout's AOVs of a traced frame to `files`; returns the seconds denoising took.
    fn write_images(&self, frame: &RenderedFrame, files: &[PathBuf]) -> Result<Option<f64>, OutputError> {
        let mut files = files.iter();
        let mut next = || files.next().expect("frame_files lists every file");
        let exr = self.layout.exr;
        let (image, denoise_seconds) = self.denoised(frame)?;
        let noisy = self.layout.keep_noisy.then_some(&frame.film);
        for film in std::iter::once(image.as_ref()).chain(noisy) {
            write_png_atomic(film, self.exposure, next())?;
            if exr {
                write_exr_atomic(film, next())?;
            }
        }
        // The layout's passes come first; a denoiser's extra guides are not written.
        for (aov, film) in frame.aovs.iter().take(self.layout.aovs.len()) {
            write_aov_png_atomic(film, *aov, next())?;
            if exr {
                write_exr_atomic(film, next())?;
            }
        }
        Ok(denoise_seconds)
    }

    /// The frame's image, denoised when there is a denoiser, and the seconds that took.
    fn denoised<'f>(&self, frame: &'f RenderedFrame) -> Result<(Cow<'f, Film>, Option<f64>), OutputError> {
        let Some(denoiser) = self.denoiser else {
            return Ok((Cow::Borrowed(&frame.film), None));
        };
        let guide = |kind: Aov| {
            frame.aovs.iter().find(|(a, _)| *a == kind).map(|(_, f)| f).expect("--denoise renders its guides")
        };
        let (film, seconds) = denoiser.denoise(&frame.film, guide(Aov::Albedo), guide(Aov::Normal))?;
        Ok((Cow::Owned(film), Some(seconds)))
    }
}

/// Copies `from` to `to` atomically (temporary file, then rename).
fn copy_atomic(from: &Path, to: &Path) -> Result<(), OutputError> {
    let copy_error = |source| OutputError::Copy { from: from.to_path_buf(), to: to.to_path_buf(), source };
    let bytes = std::fs::read(from).map_err(copy_error)?;
    crate::atomic_file::write_atomic(to, &bytes).map_err(copy_error)
}
