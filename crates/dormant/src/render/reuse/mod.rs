//! Exact temporal reuse (`--reuse exact`, the default with one seed for every frame): a frame
//! traces only the samples that can see something that changed since they were last traced,
//! and takes every other sample, bit for bit, from a store.
//!
//! Why it is exact: a sample is traced as a full frame traces it (its camera ray in the same
//! packet with the same neighbours, the same sampler dimensions), and its horizon is the
//! earliest later frame whose changes any of its rays' segments meets. Until then every
//! segment sees the same geometry, so with the camera, lights and seed unchanged the sample
//! computes the same bits; a pixel is the sum of its samples in index order, so it is the
//! pixel a full render computes. A frame where that cannot hold is traced in full
//! ([`FullFrame`]: the first, a moving camera or emitter, islands baked or unbaked).
//!
//! Where each part lives, in the order a run meets them:
//!
//! - `decision.rs`: whether a run reuses at all and whether exact reuse fits its memory
//!   budget ([`ReuseMode::decide`](decision::ReuseMode::decide)), for the command line and
//!   `Sequence::render` alike.
//! - `changes.rs`: what changes between consecutive rendered frames, found from the
//!   trajectory before they are rendered: [`RunMotion`], the facts the sequence hands over,
//!   and the change stream that turns them, a window of frames at a time, into the boxes of a
//!   [`ChangeIndex`](crate::accel::bvh::ChangeIndex) (a BVH type, in
//!   `accel/bvh/change_index/`).
//! - `run.rs`: exact reuse over one run ([`ExactReuse`]): the change index's window, which
//!   frames must be traced in full and why, the store, and each frame rendered through them.
//! - `store.rs`: the [`ReuseStore`](store::ReuseStore) of every sample's (or pixel's) last
//!   traced value and horizon, and the AOV passes; one frame rendered through it, which merges
//!   what was traced back in.
//! - `plan.rs`: what the tile loop is asked to trace ([`FramePlan`], [`Due`]) and gives back
//!   ([`PlannedFrame`]), and the tile loop bound to a frame as reuse sees it ([`PlanTracer`]).
//!   The tile loop (`render/tiles/tile_loop.rs`) carries the plans out: a due sample is traced
//!   in its place in the camera packets, the others kept from the store.
//! - `horizon.rs`: a traced sample's horizon, found ray by ray against the change index
//!   ([`HorizonProbe`]); the integrators' [`RayLog`](crate::render::RayLog)
//!   (`render/integrator/ray_log.rs`) counts their rays and hands each to its probe.
//!
//! The tracing reads this module's plans and horizons, so this module does not import the
//! tracing back: its caller hands it a [`PlanTracer`]. That caller is the sequence
//! (`sequence/render.rs`), whose part is the decision, the run's facts, and one call per
//! frame.

mod changes;
pub(crate) mod decision;
mod horizon;
mod plan;
mod run;
mod store;

pub(crate) use changes::{FullFrame, RunMotion};
pub(crate) use horizon::HorizonProbe;
pub(crate) use plan::{traced_passes, Due, FramePlan, PlanTracer, PlannedFrame, StoredSamples, TracedSample};
pub(crate) use run::{ExactFrame, ExactReuse};
pub(crate) use store::ReuseGranularity;
