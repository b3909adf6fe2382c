//! Residency of sleeping bodies: from simulated frames to the scenes the accelerators hold,
//! deciding where each body resides (the per-frame top level while awake; once its island
//! sleeps, the resting scene or the static scene, "integrated").
//!
//! - [`SceneManager`] keeps one accelerator in step with a simulation: awake bodies are
//!   instances; sleeping islands the [`IntegrationPolicy`] accepts are integrated in an
//!   [`IntegrationForm`]: baked into the static scene, or resting (instances in a scene
//!   rebuilt on a schedule); woken ones leave, baked ones through the geometry
//!   cache or by removal.
//! - The cost model decides, under the `auto` policy, whether integrating pays off, with the
//!   run's future when it is known ([`Lookahead`]).
//! - [`StageTimes`]: the per-frame stage times every record and report is made of.

mod baked;
mod cache;
mod cost_model;
mod form;
mod lookahead;
mod manager;
mod policy;
mod stage_times;
mod trace_kind;

pub use cache::{CacheBudget, CacheStats};
pub use cost_model::CostModelState;
pub use form::IntegrationForm;
pub(crate) use lookahead::Lookahead;
pub(crate) use manager::Decision;
pub use manager::{FrameStats, ManagerOptions, ReactivationPath, ReactivationStrategy, SceneManager};
pub use policy::{IntegrationPolicy, IntegrationSettings};
pub use stage_times::StageTimes;
pub use trace_kind::TraceKind;
