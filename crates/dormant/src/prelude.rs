//! What a program needs to render a physics scene, in one `use dormant::prelude::*`: load a
//! scene file, simulate it into a [`Sequence`], keep an accelerator in step with it through a
//! [`SceneManager`], render its frames with an integrator and write them.
//!
//! ```no_run
//! use dormant::prelude::*;
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

pub use crate::accel::Backend;
pub use crate::physics::SimulateOptions;
pub use crate::render::PathTracer;
pub use crate::residency::{IntegrationSettings, SceneManager};
pub use crate::scene::file::SceneFile;
pub use crate::sequence::output::{FrameWriter, OutputLayout};
pub use crate::sequence::{FrameRenderer, Sequence, SequenceSource};
