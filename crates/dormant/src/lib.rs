//! dormant: an offline renderer for physics-simulated scenes that takes sleeping islands out
//! of the per-frame acceleration build.
//!
//! Data flows one way: [`geometry`] → [`scene`] (descriptions) → [`physics`] (the simulated
//! trajectory) → [`accel`] (one interface, Embree and BVH backends, and what a hit means in
//! scene terms) → [`residency`] (where sleeping bodies reside: awake instances, the resting
//! scene, baked into the static scene) and [`render`] (pixels), which do not know each other →
//! [`sequence`] (the replay that drives both frame by frame, and its output files).
//!
//! Rendering a physics scene: load a scene file, simulate it into a [`sequence::Sequence`],
//! keep an accelerator in step with it through a [`residency::SceneManager`], render its frames
//! with an integrator and write them.
//!
//! ```no_run
//! use dormant::accel::Backend;
//! use dormant::physics::SimulateOptions;
//! use dormant::render::PathTracer;
//! use dormant::residency::IntegrationSettings;
//! use dormant::scene::file::SceneFile;
//! use dormant::sequence::output::{FrameWriter, OutputLayout};
//! use dormant::sequence::{FrameRenderer, Sequence, SequenceSource};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let file = SceneFile::load("scenes/tiny.toml")?;
//! let source = SequenceSource::scene(file, SimulateOptions::default(), None);
//! let sequence = Sequence::load(source, &mut |_| {})?;
//! let frames = sequence.select(Some("0..120".parse()?), None)?;
//! let options = sequence.manager_options(&frames, IntegrationSettings::default());
//! let mut manager = sequence.manager(Backend::Embree, None, options)?;
//! let integrator = PathTracer::default();
//! let renderer = FrameRenderer::new(&integrator, 960, 540, 16);
//! let layout = OutputLayout { dir: "out/tiny".into(), exr: false, keep_noisy: false, aovs: Vec::new() };
//! let writer = FrameWriter { layout: &layout, exposure: 1.0, denoiser: None };
//! sequence.render(&frames, &mut manager, &renderer, &[], &mut |frame, _stats, _manager| {
//!     writer.write(frame)?;
//!     Ok::<(), Box<dyn std::error::Error>>(())
//! })?;
//! # Ok(())
//! # }
//! ```

pub mod accel;
pub mod atomic_file;
pub mod geometry;
pub mod names;
pub mod physics;
pub mod render;
pub mod residency;
pub mod rng;
pub mod scene;
pub mod sequence;
