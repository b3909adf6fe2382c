//! The scene manager: keeps one accelerator in step with a simulation, frame by frame.
//!
//! - Prototypes: one bottom-level structure per mesh, shared by all its bodies.
//! - Awake bodies (and sleeping ones not integrated) are instances in the per-frame top level.
//! - Integrated islands are held in one of two forms ([`IntegrationForm`]): baked into the
//!   static scene (the pristine environment plus baked islands), or as instances in the
//!   resting scene, which the accelerator rebuilds on a schedule (`accel/resting.rs`).
//!
//! Per rendered frame ([`SceneManager::prepare`]), in stages with their own timers:
//! 1. **reactivate**: integrated islands that woke leave: baked ones by removal or by a cached
//!    static scene without them, whichever the accelerator says is cheaper; resting ones by
//!    moving their instances back to the top level;
//! 2. **integrate**: sleeping islands the policy accepts are integrated (`admit.rs`);
//! 3. **update**: instances follow the awake bodies (added, moved, removed);
//! 4. **commit**: skipped when nothing changed.
//!
//! The caller then traces and reports it ([`SceneManager::record_trace`]): the fifth stage.
//! Island events reach the manager for every simulated frame ([`SceneManager::observe`]), so
//! frames can be skipped between renders; an island that slept and woke in between never
//! touches the accelerator.

mod admit;
mod probe;
mod reactivate;
mod slots;
#[cfg(test)]
mod tests;
mod update;

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use bit_set::BitSet;
use glam::Mat3;

use super::cache::{CacheBudget, CacheOutcome, CacheStats, GeometryCache};
use super::cost_model::{CostEstimate, CostModel, CostModelState};
use super::lookahead::Lookahead;
use super::policy::IntegrationPolicy;
use super::stage_times::StageTimes;
use super::{IntegrationForm, TraceKind};
use crate::accel::{mesh_triangle, HitTriangle, MeshRef, ObjectMap, ResolvedHit};
use crate::accel::{AccelError, Accelerator, HitObject, PrototypeId, SceneQuery, StaticSceneSnapshot};
use crate::geometry::{Ray, TriangleMesh};
use crate::physics::trajectory::ReplayFrame;
use crate::physics::{BodyId, BodyInfo, IslandEvent, IslandId};
use crate::scene::SceneDescription;
use probe::Probe;
use slots::{
    BodySlot, CachedScene, InstanceOwners, Integrated, Placement, SleepingIsland, StaticOwner, StaticOwners,
};

/// How a reactivation leaves the static scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReactivationStrategy {
    /// Whichever the accelerator says builds fewer triangles: removal from the live scene, or
    /// a cached scene plus the missing islands.
    Cheapest,
    /// A cached scene (or the pristine one) plus the missing islands whenever the backend can
    /// restore one, as the paper does; removal otherwise.
    CacheFirst,
}

/// How the manager integrates.
#[derive(Clone, Debug)]
pub struct ManagerOptions {
    pub policy: IntegrationPolicy,
    pub form: IntegrationForm,
    /// Use the geometry cache to serve reactivations (baked islands).
    pub cache: bool,
    pub reactivation: ReactivationStrategy,
    pub cache_budget: CacheBudget,
    /// Rendered frames the run will have, if known: caps expected sleep in the cost model.
    pub planned_frames: Option<u32>,
    /// The run's future (rendered frames, island wakes): the cost model uses each island's
    /// true remaining sleep instead of an estimate.
    pub lookahead: Option<Arc<Lookahead>>,
    /// Motion blur: the camera shutter in frame intervals, centred on each frame (0: off).
    /// Instances of bodies moving within it move over it (`update.rs`); integrated bodies
    /// never do.
    pub shutter: f32,
}

impl Default for ManagerOptions {
    fn default() -> Self {
        Self {
            policy: IntegrationPolicy::Auto,
            form: IntegrationForm::default(),
            cache: true,
            reactivation: ReactivationStrategy::Cheapest,
            cache_budget: CacheBudget::DEFAULT,
            planned_frames: None,
            lookahead: None,
            shutter: 0.0,
        }
    }
}

/// How a reactivation was served.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReactivationPath {
    /// Removed the woken islands from the live static scene (or the resting scene).
    Removal,
    /// Restored a cached scene and added the missing islands.
    Cache(CacheOutcome),
}

/// One integration decision, with the numbers behind it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Decision {
    pub island: IslandId,
    pub bodies: usize,
    pub triangles: usize,
    /// Rendered frames it has slept so far.
    pub(crate) age: u32,
    pub integrate: bool,
    /// `None` under the `never` and `always` policies.
    pub(crate) estimate: Option<CostEstimate>,
}

/// Per-frame statistics, stage by stage.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    pub frame: u32,
    /// Milliseconds per stage; the trace once [`SceneManager::record_trace`] reported it.
    #[serde(flatten)]
    pub stages: StageTimes,
    pub rays: u64,
    /// Whether the frame committed (false: nothing changed since the last frame).
    pub(crate) committed: bool,
    /// Instances in the per-frame top level.
    pub instances: usize,
    /// Integrated islands (baked and resting).
    pub integrated_islands: usize,
    pub(crate) baked_bodies: usize,
    /// Bodies in the resting scene.
    pub resting_bodies: usize,
    pub(crate) sleeping_islands: usize,
    pub(crate) islands_slept: u32,
    pub islands_woke: u32,
    pub islands_integrated: u32,
    pub islands_reactivated: u32,
    pub(crate) instances_added: u32,
    pub(crate) instances_moved: u32,
    pub(crate) instances_removed: u32,
    /// Triangles built into the static scene (integration and reactivation).
    pub(crate) built_triangles: usize,
    /// Whether the resting scene was rebuilt.
    pub rest_rebuilt: bool,
    /// Milliseconds of trace-penalty probes (part of the integrate stage).
    pub(crate) probe_ms: f64,
    pub reactivation_path: Option<ReactivationPath>,
    pub cache_full: u64,
    pub cache_partial: u64,
    pub cache_miss: u64,
    pub decisions: Vec<Decision>,
    /// Whether the frame reused an earlier frame's image (nothing visible changed): no stage
    /// ran.
    pub reused: bool,
}

impl FrameStats {
    /// The statistics of frame `index`, which reuses this frame's image: the same scene
    /// state, no work, no events.
    pub(crate) fn reused_as(&self, index: u32) -> FrameStats {
        FrameStats {
            frame: index,
            instances: self.instances,
            integrated_islands: self.integrated_islands,
            baked_bodies: self.baked_bodies,
            resting_bodies: self.resting_bodies,
            sleeping_islands: self.sleeping_islands,
            reused: true,
            ..FrameStats::default()
        }
    }

    /// Every stage, the trace included: the per-frame time the integration policies compete on.
    pub fn frame_ms(&self) -> f64 {
        self.stages.frame_ms()
    }
}

/// Keeps an accelerator in step with a simulation; see the module docs.
pub struct SceneManager {
    accel: Box<dyn Accelerator>,
    options: ManagerOptions,
    prototypes: Vec<Arc<TriangleMesh>>,
    prototype_ids: Vec<PrototypeId>,
    bodies: Vec<BodySlot>,
    instance_owner: InstanceOwners,
    static_owner: StaticOwners,
    sleeping: BTreeMap<IslandId, SleepingIsland>,
    /// Baked islands.
    integrated: BTreeMap<IslandId, Integrated>,
    /// Resting islands and their bodies.
    resting: BTreeMap<IslandId, Vec<BodyId>>,
    /// Integrated islands (either form) that woke since the last frame.
    woken: Vec<IslandId>,
    pristine: CachedScene,
    cache: Option<GeometryCache<CachedScene>>,
    cost: CostModel,
    probe: Probe,
    rendered: u32,
    /// Index of the frame being prepared.
    frame: u32,
    last: FrameStats,
    pending_events: (u32, u32),
    last_commit_ms: Option<f64>,
    /// Bodies whose instances moved over the last prepared frame's shutter, ascending.
    blurred: Vec<u32>,
    /// Bodies whose placement integration or reactivation changed in the frame being
    /// prepared (the replay's changed bodies do not show them): the update stage visits them
    /// with those the frame changed, then empties the set.
    touched: BitSet,
    /// The update stage's set of bodies to visit, kept to reuse its memory.
    visit: BitSet,
}

impl SceneManager {
    /// Loads `template`'s static meshes and prototypes (its bodies are ignored: they come
    /// from the frames) into `accel` and commits the pristine scene.
    pub fn new(
        mut accel: Box<dyn Accelerator>,
        template: &SceneDescription,
        bodies: &[BodyInfo],
        options: ManagerOptions,
    ) -> Result<Self, AccelError> {
        let mut static_owner = StaticOwners::default();
        for (i, s) in template.statics.iter().enumerate() {
            static_owner.insert(accel.add_static(&s.mesh)?, StaticOwner::Environment(i as u32));
        }
        let mut prototype_ids = Vec::with_capacity(template.prototypes.len());
        for p in &template.prototypes {
            prototype_ids.push(accel.add_prototype(&p.mesh)?);
        }
        for b in bodies {
            if b.prototype as usize >= prototype_ids.len() {
                return Err(AccelError::UnknownId { kind: "prototype", id: b.prototype });
            }
        }
        accel.commit_static()?;
        accel.commit()?;
        let pristine = CachedScene { snapshot: accel.snapshot_static_scene(), ids: BTreeMap::new() };
        Ok(Self {
            accel,
            prototypes: template.prototypes.iter().map(|p| Arc::new(p.mesh.clone())).collect(),
            prototype_ids,
            bodies: bodies
                .iter()
                .map(|b| BodySlot { prototype: b.prototype, placement: Placement::Absent })
                .collect(),
            instance_owner: InstanceOwners::default(),
            static_owner,
            sleeping: BTreeMap::new(),
            integrated: BTreeMap::new(),
            resting: BTreeMap::new(),
            woken: Vec::new(),
            pristine,
            cache: options.cache.then(|| GeometryCache::new(options.cache_budget)),
            cost: CostModel::new(),
            probe: Probe::new(template.sun.direction),
            options,
            rendered: 0,
            frame: 0,
            last: FrameStats::default(),
            pending_events: (0, 0),
            last_commit_ms: None,
            blurred: Vec::new(),
            touched: BitSet::new(),
            visit: BitSet::new(),
        })
    }

    pub fn options(&self) -> &ManagerOptions {
        &self.options
    }

    /// The committed scene, for tracing.
    pub fn query(&self) -> Result<&dyn SceneQuery, AccelError> {
        self.accel.query()
    }

    pub fn cache_stats(&self) -> CacheStats {
        self.cache.as_ref().map(|c| c.stats().clone()).unwrap_or_default()
    }

    pub fn cost_model(&self) -> CostModelState {
        self.cost.state()
    }

    /// Camera rays of the coming frames, for the probes that measure what integration costs
    /// the trace (a small image's worth is enough), and the camera samples of a rendered frame
    /// (pixels times samples per pixel), to estimate a frame's trace before one is measured.
    pub(crate) fn set_probe_rays(&mut self, rays: Vec<Ray>, frame_samples: u64) {
        self.probe.set_rays(rays, frame_samples);
    }

    /// The static scene as it stands (environment and baked islands), as the accelerator
    /// snapshots it; `None` where the backend has no snapshots.
    pub fn static_snapshot(&self) -> Option<StaticSceneSnapshot> {
        self.accel.snapshot_static_scene()
    }

    /// The world-space meshes of the baked islands in the static scene now.
    pub fn integrated_meshes(&self) -> impl Iterator<Item = &TriangleMesh> + '_ {
        self.integrated.values().map(|i| &i.baked.mesh)
    }

    /// The islands integrated now (either form).
    pub(crate) fn integrated_islands(&self) -> impl Iterator<Item = IslandId> + '_ {
        self.integrated.keys().chain(self.resting.keys()).copied()
    }

    fn is_integrated(&self, island: &IslandId) -> bool {
        self.integrated.contains_key(island) || self.resting.contains_key(island)
    }

    /// Applies one simulated frame's island events (every frame, rendered or not).
    pub fn observe(&mut self, events: &[IslandEvent]) {
        for e in events {
            match e {
                IslandEvent::Slept { island, bodies, poses } => {
                    self.pending_events.0 += 1;
                    let s = SleepingIsland {
                        bodies: bodies.clone(),
                        poses: poses.clone(),
                        slept_at: self.rendered,
                        decided: false,
                    };
                    self.sleeping.insert(*island, s);
                }
                IslandEvent::Woke { island } => {
                    self.pending_events.1 += 1;
                    let Some(s) = self.sleeping.remove(island) else {
                        debug_assert!(false, "woke unknown island {island:?}");
                        continue;
                    };
                    let integrated = self.is_integrated(island);
                    self.cost.record_sleep(f64::from(self.rendered - s.slept_at), integrated);
                    if integrated {
                        self.woken.push(*island);
                    }
                    if let Some(cache) = &mut self.cache {
                        cache.invalidate(*island);
                    }
                }
            }
        }
    }

    /// Zeroes the island events counted for the next prepared frame's `islands_slept` and
    /// `islands_woke` (the events themselves stay applied).
    pub(crate) fn forget_event_counts(&mut self) {
        self.pending_events = (0, 0);
    }

    /// Brings the accelerator to `frame` (see the module docs) and commits. Events up to and
    /// including this frame must have been [`observe`](Self::observe)d.
    pub fn prepare(&mut self, frame: &ReplayFrame<'_>) -> Result<&FrameStats, AccelError> {
        self.prepare_with(frame, None)
    }

    /// [`prepare`](Self::prepare), making the decisions an earlier run recorded for this frame
    /// instead of asking the policy: each island decided on, and whether it was integrated
    /// (`render --resume` brings the manager through frames that run finished, so that the
    /// frames after them start from the state it had).
    pub(crate) fn prepare_decided(
        &mut self,
        frame: &ReplayFrame<'_>,
        decisions: &[(IslandId, bool)],
    ) -> Result<&FrameStats, AccelError> {
        self.prepare_with(frame, Some(decisions))
    }

    fn prepare_with(
        &mut self,
        frame: &ReplayFrame<'_>,
        decided: Option<&[(IslandId, bool)]>,
    ) -> Result<&FrameStats, AccelError> {
        debug_assert_eq!(frame.states.len(), self.bodies.len());
        let previous = (self.rendered > 0).then_some(self.frame);
        self.frame = frame.index;
        let mut stats = FrameStats {
            frame: frame.index,
            islands_slept: self.pending_events.0,
            islands_woke: self.pending_events.1,
            ..FrameStats::default()
        };
        self.pending_events = (0, 0);
        let cache_before = self.cache_stats();

        let t = Instant::now();
        let reactivated = self.reactivate(&mut stats)?;
        stats.stages.reactivate_ms = ms(t);

        let t = Instant::now();
        let integrated = self.integrate(frame, decided, &mut stats)?;
        stats.stages.integrate_ms = ms(t);

        let t = Instant::now();
        let moved = self.update(frame, previous, &mut stats)?;
        stats.stages.update_ms = ms(t);

        let t = Instant::now();
        if reactivated || integrated || moved || self.accel.query().is_err() {
            self.accel.commit()?;
            stats.committed = true;
        }
        stats.stages.commit_ms = ms(t);
        stats.instances = self.instance_owner.awake();
        self.last_commit_ms = stats.committed.then_some(stats.stages.commit_ms);
        if reactivated || integrated {
            // The live static scene moved on: cached scenes share less of it now.
            if let Some(cache) = &mut self.cache {
                cache.remeasure(|e| e.snapshot.as_ref().map_or(0, |s| s.unique_bytes()));
            }
        }
        // A probe started before an integration measures the scene after it now.
        let t = Instant::now();
        if self.probe.finish(self.accel.query()?, &mut self.cost) {
            stats.probe_ms += ms(t);
            stats.stages.integrate_ms += ms(t);
        }

        let cache = self.cache_stats();
        stats.cache_full = cache.full - cache_before.full;
        stats.cache_partial = cache.partial - cache_before.partial;
        stats.cache_miss = cache.miss - cache_before.miss;
        stats.integrated_islands = self.integrated.len() + self.resting.len();
        stats.baked_bodies = self.integrated.values().map(|i| i.baked.parts.len()).sum();
        stats.resting_bodies = self.resting.values().map(Vec::len).sum();
        stats.sleeping_islands = self.sleeping.len();
        self.rendered += 1;
        self.last = stats;
        Ok(&self.last)
    }

    /// The statistics of the frame last prepared (trace included once recorded).
    pub fn last_frame(&self) -> &FrameStats {
        &self.last
    }

    /// Records the trace stage of the frame just prepared, of `kind` for the cost model;
    /// returns its complete statistics.
    pub fn record_trace(&mut self, trace_ms: f64, rays: u64, kind: TraceKind) -> &FrameStats {
        self.last.stages.trace_ms = trace_ms;
        self.last.rays = rays;
        self.cost.record_frame(self.last.instances, self.last_commit_ms, trace_ms, kind);
        &self.last
    }

    /// Builds staged static and resting changes now (timed by the caller's stage); a rebuild
    /// of the resting scene is recorded for the cost model.
    fn commit_static_timed(&mut self, stats: &mut FrameStats) -> Result<(), AccelError> {
        let t = Instant::now();
        let report = self.accel.commit_static()?;
        if report.resting_rebuilt {
            stats.rest_rebuilt = true;
            self.cost.record_rest_build(report.resting_instances, ms(t));
        }
        Ok(())
    }
}

impl ObjectMap for SceneManager {
    fn resolve(&self, object: HitObject, prim: u32) -> Option<ResolvedHit> {
        match object {
            HitObject::Instance(id) => {
                let owner = self.instance_owner.get(id)?;
                Some(ResolvedHit {
                    mesh: MeshRef::Prototype(owner.prototype),
                    prim,
                    body: Some(owner.body),
                    normal_matrix: owner.normal_matrix,
                    integrated: owner.resting,
                })
            }
            HitObject::Static(id) => match self.static_owner.get(id)? {
                StaticOwner::Environment(i) => Some(ResolvedHit {
                    mesh: MeshRef::Static(*i),
                    prim,
                    body: None,
                    normal_matrix: Mat3::IDENTITY,
                    integrated: false,
                }),
                StaticOwner::Island(baked) => {
                    let (part, local) = baked.part_of(prim)?;
                    Some(ResolvedHit {
                        mesh: MeshRef::Prototype(part.prototype),
                        prim: local,
                        body: Some(part.body),
                        normal_matrix: part.normal_matrix,
                        integrated: true,
                    })
                }
            },
        }
    }

    /// Instances at their frame pose: `time` is ignored (`dormant verify` checks motion blur
    /// on loaded descriptions, [`crate::accel::LoadedObjectMap`]).
    fn hit_triangle(
        &self,
        desc: &SceneDescription,
        object: HitObject,
        prim: u32,
        _time: f32,
    ) -> Option<HitTriangle> {
        match object {
            HitObject::Instance(id) => {
                let owner = self.instance_owner.get(id)?;
                let mesh = MeshRef::Prototype(owner.prototype).mesh(desc)?;
                Some(HitTriangle { vertices: mesh_triangle(mesh, prim)?, transform: Some(owner.transform) })
            }
            HitObject::Static(id) => {
                let vertices = match self.static_owner.get(id)? {
                    StaticOwner::Environment(i) => mesh_triangle(MeshRef::Static(*i).mesh(desc)?, prim)?,
                    StaticOwner::Island(baked) => mesh_triangle(&baked.mesh, prim)?,
                };
                Some(HitTriangle { vertices, transform: None })
            }
        }
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
