//! Sequences: a simulation replayed into rendered frames. This module owns the way from a
//! scene file (or a trajectory) to frames:
//!
//! - [`Sequence`]: the trajectory (simulated now, or read from a file and checked against its
//!   scene), the scene file's render assets and the frame template;
//! - [`FrameSelection`]: which frames are rendered (a range and a step, or a list);
//! - [`Sequence::replay`]: the one replay loop, which feeds every frame's island events to
//!   the scene managers and hands each selected frame to the caller;
//! - [`Sequence::render_frame`] and [`Sequence::render`]: the per-frame call into the
//!   renderer through a [`SceneManager`](crate::residency::SceneManager), whose trace time
//!   goes back to its cost model; exact temporal reuse, which lives in `render/reuse/` and is
//!   called from there once per frame ([`ReuseMode`], [`ReuseRequest`] and
//!   [`DEFAULT_REUSE_BYTES`] are re-exported here from it);
//! - [`KeptFrame`]: a frame an earlier run finished (`render --resume`), which the driver
//!   brings the manager through as that run did instead of rendering it;
//! - [`Sequence::describe_frame`]: a frame with every present body an instance, the
//!   reference integrated scenes are checked against;
//! - [`Sequence::export`]: the selected frames' poses, camera, lights and mesh sources as
//!   plain data for another renderer (`dormant export`, `scripts/compare-cycles.py`);
//! - [`Sequence::write_gltf`]: every frame as one animated glTF binary (`dormant export
//!   --gltf`, module `gltf_export`).
//!
//! The CLI, `dormant verify` and the integration benchmarks all replay through here.

mod describe;
mod error;
pub mod export;
mod frame_renderer;
pub mod gltf_export;
mod kept;
pub mod output;
mod render;
mod replay_loop;
mod selection;
mod source;
pub mod stats;

pub use crate::render::reuse::decision::{ReuseMode, ReuseRequest, DEFAULT_REUSE_BYTES};
pub use error::SequenceError;
pub use frame_renderer::{FrameRenderer, SeedMode};
pub(crate) use kept::KeptFrame;
pub(crate) use render::trace_kind;
pub use render::RenderedFrame;
pub use selection::{FrameRange, FrameSelection};
pub(crate) use source::PhysicsSource;
pub use source::{Sequence, SequenceSource};
