//! Turning a committed scene into pixels: camera rays, shading, tiles over rayon, the film and
//! image output. Talks to geometry only through [`crate::accel::SceneQuery`] and the scene
//! manager's hit mapping; image sequences of simulations are `crate::sequence`'s.

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
mod ray_log;
mod render_scene;
mod reuse;
mod sampler;
mod texture_sampling;
mod tiles;

pub use adaptive::AdaptiveSampling;
pub(crate) use adaptive::SppStats;
pub(crate) use aov::AovPasses;
pub use aov::{Aov, AovIntegrator};
pub use bsdf::{sample_cone, sample_cosine};
pub use camera::PinholeCamera;
pub(crate) use emitters::Emitters;
pub use film::Film;
pub use image_file::write_exr_atomic;
pub(crate) use image_file::{write_aov_png_atomic, write_png_atomic};
pub use image_size::ImageSize;
pub use integrator::path::PathTracer;
pub use integrator::preview::{AmbientOcclusion, DirectLighting};
pub use integrator::{FrameContext, FrameIntegrator, Integrator};
pub use pixel_filter::{FilterKind, PixelFilter, MAX_FILTER_WIDTH};
pub use ray_log::RayLog;
pub use render_scene::RenderScene;
pub(crate) use render_scene::{SurfaceHit, SurfaceKind};
pub(crate) use reuse::{render_reusing, FrameReuse, ReuseStore};
pub(crate) use reuse::{ReuseGranularity, ReuseStats};
pub(crate) use sampler::PixelSampler;
pub use tiles::{render_frame, render_with_aovs, RenderSettings, RenderStats};

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
    #[error("scene '{scene}': {what}")]
    Scene { scene: String, what: String },
    #[error(transparent)]
    Accel(#[from] AccelError),
}
