//! Integration: from simulated frames to the scenes the accelerators hold.
//!
//! - [`SceneManager`] keeps one accelerator in step with a simulation: awake bodies are
//!   instances, sleeping islands the [`IntegrationPolicy`] accepts are baked into the static
//!   scene ([`BakedIsland`]), woken ones leave it through the [`GeometryCache`] or by removal.
//! - [`CostModel`] decides, under the `auto` policy, whether integrating pays off.
//! - [`ObjectMap`] maps hits back to bodies, prototypes and triangles for shading.

mod baked;
mod cache;
mod cost_model;
mod lookahead;
mod manager;
mod object_map;
mod policy;
mod stage_times;

pub use baked::{BakedIsland, BakedPart};
pub use cache::{CacheBudget, CacheHit, CacheOutcome, CacheStats, GeometryCache, FRACTION_BUCKETS};
pub use cost_model::{
    choose_batch, Candidate, CostEstimate, CostModel, CostModelState, IntegrationForm, Outlook, Penalties,
    Situation,
};
pub use lookahead::Lookahead;
pub use manager::{
    Decision, FrameStats, ManagerOptions, ReactivationPath, ReactivationStrategy, SceneManager,
};
pub use object_map::{normal_matrix, LoadedObjectMap, MeshRef, ObjectMap, ResolvedHit};
pub use policy::{IntegrationPolicy, IntegrationSettings};
pub use stage_times::{StageColumn, StageTimes};
