//! Turning a committed scene into pixels: camera rays, shading, tiles over rayon, the film and
//! image output. Talks to geometry only through [`crate::accel::SceneQuery`] and the scene
//! manager's hit mapping; image sequences of simulations are `crate::sequence`'s.
//!
//! A frame is rendered by `tiles/` (the entry points and the tile loop) with the settings of
//! `settings.rs` and an integrator of `integrator/`; exact temporal reuse, which traces only
//! the samples that can see a change, is `reuse/`.

mod adaptive;
mod aov;
mod bsdf;
mod camera;
pub mod denoise;
mod emitters;
mod film;
mod image_file;
mod image_size;
mod integrator;
mod pixel_filter;
mod render_scene;
pub(crate) mod reuse;
mod sampler;
mod settings;
mod texture_sampling;
mod tiles;

pub use adaptive::AdaptiveSampling;
pub(crate) use adaptive::SppStats;
pub use aov::Aov;
pub(crate) use aov::AovPasses;
pub use bsdf::{sample_cone, sample_cosine};
pub use camera::PinholeCamera;
pub(crate) use emitters::Emitters;
pub use film::Film;
pub use image_file::write_exr_atomic;
pub(crate) use image_file::{write_aov_png_atomic, write_png_atomic};
pub use image_size::ImageSize;
pub use integrator::aov_pass::AovIntegrator;
pub use integrator::path::PathTracer;
pub use integrator::preview::{AmbientOcclusion, DirectLighting};
pub use integrator::ray_log::RayLog;
pub use integrator::{FrameContext, FrameIntegrator, Integrator};
pub(crate) use pixel_filter::MAX_FILTER_WIDTH;
pub use pixel_filter::{FilterKind, PixelFilter};
pub use render_scene::RenderScene;
pub(crate) use render_scene::{SurfaceHit, SurfaceKind};
pub(crate) use sampler::PixelSampler;
pub use settings::{RenderSettings, RenderStats};
pub(crate) use tiles::FrameTracer;
pub use tiles::{render_frame, render_with_aovs};

use std::path::PathBuf;

use crate::accel::AccelError;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("image size {0}")]
    InvalidSize(String),
    #[error("samples per pixel must be from 1 to {}", crate::scene::limits::MAX_SAMPLES_PER_PIXEL)]
    InvalidSpp,
    #[error("noise threshold {0}: must be a number, 0 (off) or more")]
    InvalidNoiseThreshold(f32),
    #[error("pixel filter width {0}: must be a number above 0 and at most {max} pixels", max = MAX_FILTER_WIDTH)]
    InvalidFilterWidth(f32),
    #[error("minimum samples per pixel {min}: must be from 1 to the samples per pixel ({spp})")]
    InvalidMinSpp { min: u32, spp: u32 },
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {source}")]
    Encode {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    /// Exact temporal reuse needs more memory than its budget allows (callers name the flag).
    #[error(
        "{budget_mib} MiB is too small for exact reuse of {width}x{height} frames with these passes: \
         it needs {needed_mib} MiB (one value per pixel and pass); raise the budget or turn reuse off"
    )]
    ReuseBudget { budget_mib: usize, needed_mib: usize, width: u32, height: u32 },
    #[error("scene '{scene}': {what}")]
    Scene { scene: String, what: String },
    #[error(transparent)]
    Accel(#[from] AccelError),
}
