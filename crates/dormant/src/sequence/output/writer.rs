//! [`FrameWriter`]: a rendered frame's files, written atomically; a reused frame's are copies
//! of the frame it repeats. Writing is in two steps so that a caller can write one frame's
//! files while it renders the next: [`FrameWriter::prepare`] does what needs the writer (the
//! denoiser, which one thread drives) and returns the [`FrameFiles`], owned and `Send`, which
//! [`FrameFiles::write`] encodes and writes on any thread.

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

/// A frame's files, ready to be written: the images to encode (denoised already), or the
/// files of the frame it repeats to copy.
#[derive(Debug)]
pub struct FrameFiles {
    written: WrittenFrame,
    content: Content,
}

#[derive(Debug)]
enum Content {
    /// The files of the frame a reused frame repeats, in the same order.
    Copies(Vec<PathBuf>),
    /// Each image (the pass it is, `None` for the image and the noisy image) with its tone
    /// mapping's exposure, and whether an EXR follows each PNG.
    Images { images: Vec<(Option<Aov>, Film)>, exposure: f32, exr: bool },
}

impl FrameWriter<'_> {
    /// Writes `frame`'s files.
    pub fn write(&self, frame: &RenderedFrame) -> Result<WrittenFrame, OutputError> {
        self.prepare(frame)?.write()
    }

    /// What writing `frame` takes: its image denoised when there is a denoiser (here, on the
    /// caller's thread), the noisy image (`keep_noisy`) and the layout's AOVs, each copied
    /// out of the frame; or, for a reused frame, the files to copy.
    pub fn prepare(&self, frame: &RenderedFrame) -> Result<FrameFiles, OutputError> {
        let files = self.layout.frame_files(frame.index);
        if let Some(source) = frame.reused_from {
            let content = Content::Copies(self.layout.frame_files(source));
            return Ok(FrameFiles { written: WrittenFrame { files, denoise_seconds: None }, content });
        }
        let (image, denoise_seconds) = self.denoised(frame)?;
        let noisy = self.layout.keep_noisy.then(|| frame.film.clone());
        // The layout's passes come first; a denoiser's extra guides are not written.
        let aovs =
            frame.aovs.iter().take(self.layout.aovs.len()).map(|(aov, film)| (Some(*aov), film.clone()));
        let images = std::iter::once(image).chain(noisy).map(|film| (None, film)).chain(aovs).collect();
        let content = Content::Images { images, exposure: self.exposure, exr: self.layout.exr };
        Ok(FrameFiles { written: WrittenFrame { files, denoise_seconds }, content })
    }

    /// The frame's image, denoised when there is a denoiser, and the seconds that took.
    fn denoised(&self, frame: &RenderedFrame) -> Result<(Film, Option<f64>), OutputError> {
        let Some(denoiser) = self.denoiser else {
            return Ok((frame.film.clone(), None));
        };
        let guide = |kind: Aov| {
            frame.aovs.iter().find(|(a, _)| *a == kind).map(|(_, f)| f).expect("--denoise renders its guides")
        };
        let (film, seconds) = denoiser.denoise(&frame.film, guide(Aov::Albedo), guide(Aov::Normal))?;
        Ok((film, Some(seconds)))
    }
}

impl FrameFiles {
    /// The files it writes, in [`OutputLayout::frame_files`] order; the image first.
    pub fn paths(&self) -> &[PathBuf] {
        &self.written.files
    }

    /// Seconds the denoiser took (`None` without one, or for a reused frame).
    pub fn denoise_seconds(&self) -> Option<f64> {
        self.written.denoise_seconds
    }

    /// Encodes and writes the files, each atomically.
    pub fn write(self) -> Result<WrittenFrame, OutputError> {
        let mut files = self.written.files.iter();
        match &self.content {
            Content::Copies(sources) => {
                for (from, to) in sources.iter().zip(files) {
                    copy_atomic(from, to)?;
                }
            }
            Content::Images { images, exposure, exr } => {
                let mut next = || files.next().expect("frame_files lists every file");
                for (aov, film) in images {
                    match aov {
                        None => write_png_atomic(film, *exposure, next())?,
                        Some(aov) => write_aov_png_atomic(film, *aov, next())?,
                    }
                    if *exr {
                        write_exr_atomic(film, next())?;
                    }
                }
            }
        }
        Ok(self.written)
    }
}

/// Copies `from` to `to` atomically (temporary file, then rename).
fn copy_atomic(from: &Path, to: &Path) -> Result<(), OutputError> {
    let copy_error = |source| OutputError::Copy { from: from.to_path_buf(), to: to.to_path_buf(), source };
    let bytes = std::fs::read(from).map_err(copy_error)?;
    crate::atomic_file::write_atomic(to, &bytes).map_err(copy_error)
}
