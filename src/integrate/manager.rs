//! The scene manager: keeps one accelerator in step with a simulation, frame by frame.
//!
//! - Prototypes: one bottom-level structure per mesh, shared by all its bodies.
//! - Awake bodies (and sleeping ones not integrated) are instances in the top level.
//! - The static scene is the pristine environment plus the integrated islands.
//!
//! Per rendered frame ([`SceneManager::prepare`]), in stages with their own timers:
//! 1. **reactivate**: integrated islands that woke leave the static scene, by removal or by a
//!    cached static scene without them, whichever the accelerator says is cheaper;
//! 2. **integrate**: sleeping islands the policy accepts are baked into the static scene;
//! 3. **update**: instances follow the awake bodies (added, moved, removed);
//! 4. **commit**: skipped when nothing changed.
//!
//! The caller then traces and reports it ([`SceneManager::record_trace`]): the fifth stage.
//! Island events reach the manager for every simulated frame ([`SceneManager::observe`]), so
//! frames can be skipped between renders; an island that slept and woke in between never
//! touches the accelerator.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Instant;

use glam::Mat3;

use super::baked::BakedIsland;
use super::cache::{CacheBudget, CacheOutcome, CacheStats, GeometryCache};
use super::cost_model::{choose_batch, CostEstimate, CostModel, CostModelState};
use super::object_map::{normal_matrix, MeshRef, ObjectMap, ResolvedHit};
use super::policy::IntegrationPolicy;
use super::stage_times::StageTimes;
use crate::accel::{
    AccelError, Accelerator, HitObject, InstanceId, PrototypeId, SceneQuery, StaticId, StaticSceneSnapshot,
};
use crate::geometry::TriangleMesh;
use crate::physics::{BodyId, BodyInfo, BodyPose, IslandEvent, IslandId, ReplayFrame};
use crate::scene::SceneDescription;

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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManagerOptions {
    pub policy: IntegrationPolicy,
    /// Use the geometry cache to serve reactivations.
    pub cache: bool,
    pub reactivation: ReactivationStrategy,
    pub cache_budget: CacheBudget,
    /// Rendered frames the run will have, if known: caps expected sleep in the cost model.
    pub planned_frames: Option<u32>,
}

impl Default for ManagerOptions {
    fn default() -> Self {
        Self {
            policy: IntegrationPolicy::Auto,
            cache: true,
            reactivation: ReactivationStrategy::Cheapest,
            cache_budget: CacheBudget::DEFAULT,
            planned_frames: None,
        }
    }
}

/// A body's place in the accelerator.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Placement {
    Absent,
    Instance { id: InstanceId, pose: BodyPose },
    Baked(IslandId),
}

struct BodySlot {
    prototype: u32,
    placement: Placement,
}

struct SleepingIsland {
    bodies: Vec<BodyId>,
    poses: Vec<BodyPose>,
    /// Rendered-frame counter when it fell asleep.
    slept_at: u32,
    /// Whether a decision about it was logged.
    decided: bool,
}

/// An integrated island in the static scene.
#[derive(Clone)]
struct Integrated {
    id: StaticId,
    baked: Arc<BakedIsland>,
}

/// What the static scene belonged to.
#[derive(Clone)]
enum StaticOwner {
    Environment(u32),
    Island(Arc<BakedIsland>),
}

/// Owners by static id: a dense table, because every hit on static geometry looks here.
#[derive(Default)]
struct StaticOwners(Vec<Option<StaticOwner>>);

impl StaticOwners {
    fn insert(&mut self, id: StaticId, owner: StaticOwner) {
        let i = id.0 as usize;
        if self.0.len() <= i {
            self.0.resize(i + 1, None);
        }
        self.0[i] = Some(owner);
    }

    fn remove(&mut self, id: StaticId) {
        if let Some(slot) = self.0.get_mut(id.0 as usize) {
            *slot = None;
        }
    }

    fn get(&self, id: StaticId) -> Option<&StaticOwner> {
        self.0.get(id.0 as usize)?.as_ref()
    }

    fn retain_environment(&mut self) {
        for slot in &mut self.0 {
            if matches!(slot, Some(StaticOwner::Island(_))) {
                *slot = None;
            }
        }
    }
}

/// A cache entry: a saved static scene and the static ids its islands had in it.
#[derive(Clone)]
struct CachedScene {
    snapshot: Option<StaticSceneSnapshot>,
    ids: BTreeMap<IslandId, StaticId>,
}

/// How a reactivation was served.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReactivationPath {
    /// Removed the woken islands from the live static scene.
    Removal,
    /// Restored a cached scene and added the missing islands.
    Cache(CacheOutcome),
}

/// One integration decision, with the numbers behind it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Decision {
    pub island: IslandId,
    pub bodies: usize,
    pub triangles: usize,
    /// Rendered frames it has slept so far.
    pub age: u32,
    pub integrate: bool,
    /// `None` under the `never` and `always` policies.
    pub estimate: Option<CostEstimate>,
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
    pub committed: bool,
    pub instances: usize,
    pub integrated_islands: usize,
    pub baked_bodies: usize,
    pub sleeping_islands: usize,
    pub islands_slept: u32,
    pub islands_woke: u32,
    pub islands_integrated: u32,
    pub islands_reactivated: u32,
    pub instances_added: u32,
    pub instances_moved: u32,
    pub instances_removed: u32,
    /// Triangles built into the static scene (integration and reactivation).
    pub built_triangles: usize,
    pub reactivation_path: Option<ReactivationPath>,
    pub cache_full: u64,
    pub cache_partial: u64,
    pub cache_miss: u64,
    pub decisions: Vec<Decision>,
}

impl FrameStats {
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
    /// Body, prototype and normal matrix per instance id.
    instance_owner: Vec<Option<(BodyId, u32, Mat3)>>,
    static_owner: StaticOwners,
    sleeping: BTreeMap<IslandId, SleepingIsland>,
    integrated: BTreeMap<IslandId, Integrated>,
    /// Integrated islands that woke since the last frame.
    woken: Vec<IslandId>,
    pristine: CachedScene,
    cache: Option<GeometryCache<CachedScene>>,
    cost: CostModel,
    rendered: u32,
    last: FrameStats,
    pending_events: (u32, u32),
    last_commit_ms: Option<f64>,
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
            options,
            prototypes: template.prototypes.iter().map(|p| Arc::new(p.mesh.clone())).collect(),
            prototype_ids,
            bodies: bodies
                .iter()
                .map(|b| BodySlot { prototype: b.prototype, placement: Placement::Absent })
                .collect(),
            instance_owner: Vec::new(),
            static_owner,
            sleeping: BTreeMap::new(),
            integrated: BTreeMap::new(),
            woken: Vec::new(),
            pristine,
            cache: options.cache.then(|| GeometryCache::new(options.cache_budget)),
            cost: CostModel::new(),
            rendered: 0,
            last: FrameStats::default(),
            pending_events: (0, 0),
            last_commit_ms: None,
        })
    }

    pub fn options(&self) -> &ManagerOptions {
        &self.options
    }

    /// The committed scene, for tracing.
    pub fn query(&self) -> Result<&dyn SceneQuery, AccelError> {
        self.accel.query()
    }

    pub fn accel(&self) -> &dyn Accelerator {
        self.accel.as_ref()
    }

    pub fn cache_stats(&self) -> CacheStats {
        self.cache.as_ref().map(|c| c.stats().clone()).unwrap_or_default()
    }

    pub fn cost_model(&self) -> CostModelState {
        self.cost.state()
    }

    /// The world-space meshes of the islands in the static scene now.
    pub fn integrated_meshes(&self) -> impl Iterator<Item = &TriangleMesh> + '_ {
        self.integrated.values().map(|i| &i.baked.mesh)
    }

    /// The islands in the static scene now.
    pub fn integrated_islands(&self) -> impl Iterator<Item = IslandId> + '_ {
        self.integrated.keys().copied()
    }

    /// Applies one simulated frame's island events (every frame, rendered or not).
    pub fn observe(&mut self, events: &[IslandEvent]) {
        for e in events {
            match e {
                IslandEvent::Slept { island, bodies, poses } => {
                    self.pending_events.0 += 1;
                    self.sleeping.insert(
                        *island,
                        SleepingIsland {
                            bodies: bodies.clone(),
                            poses: poses.clone(),
                            slept_at: self.rendered,
                            decided: false,
                        },
                    );
                }
                IslandEvent::Woke { island } => {
                    self.pending_events.1 += 1;
                    let Some(s) = self.sleeping.remove(island) else {
                        debug_assert!(false, "woke unknown island {island:?}");
                        continue;
                    };
                    let integrated = self.integrated.contains_key(island);
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

    /// Brings the accelerator to `frame` (see the module docs) and commits. Events up to and
    /// including this frame must have been [`observe`](Self::observe)d.
    pub fn prepare(&mut self, frame: &ReplayFrame<'_>) -> Result<&FrameStats, AccelError> {
        debug_assert_eq!(frame.states.len(), self.bodies.len());
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
        let integrated = self.integrate(&mut stats)?;
        stats.stages.integrate_ms = ms(t);

        let t = Instant::now();
        let moved = self.update(frame, &mut stats)?;
        stats.stages.update_ms = ms(t);

        let t = Instant::now();
        if reactivated || integrated || moved || self.accel.query().is_err() {
            let report = self.accel.commit()?;
            stats.committed = true;
            stats.instances = report.instances;
        } else {
            stats.instances = self.instance_owner.iter().flatten().count();
        }
        stats.stages.commit_ms = ms(t);
        self.last_commit_ms = stats.committed.then_some(stats.stages.commit_ms);

        let cache = self.cache_stats();
        stats.cache_full = cache.full - cache_before.full;
        stats.cache_partial = cache.partial - cache_before.partial;
        stats.cache_miss = cache.miss - cache_before.miss;
        stats.integrated_islands = self.integrated.len();
        stats.baked_bodies = self.integrated.values().map(|i| i.baked.parts.len()).sum();
        stats.sleeping_islands = self.sleeping.len();
        self.rendered += 1;
        self.last = stats;
        Ok(&self.last)
    }

    /// The statistics of the frame last prepared (trace included once recorded).
    pub fn last_frame(&self) -> &FrameStats {
        &self.last
    }

    /// Records the trace stage of the frame just prepared; returns its complete statistics.
    pub fn record_trace(&mut self, trace_ms: f64, rays: u64) -> &FrameStats {
        self.last.stages.trace_ms = trace_ms;
        self.last.rays = rays;
        self.cost.record_frame(self.last.instances, self.last_commit_ms, trace_ms);
        &self.last
    }

    fn reactivate(&mut self, stats: &mut FrameStats) -> Result<bool, AccelError> {
        if self.woken.is_empty() {
            return Ok(false);
        }
        let woken = std::mem::take(&mut self.woken);
        let request: BTreeSet<IslandId> =
            self.integrated.keys().copied().filter(|i| !woken.contains(i)).collect();
        // Removing from the live scene costs what the accelerator says (a detach or an unlink
        // is free; removing from a shared structure rebuilds it) ...
        let removal_cost =
            woken.iter().map(|i| self.accel.static_removal_cost(self.integrated[i].id)).max().unwrap_or(0);
        // ... restoring a saved scene costs building the requested islands it lacks.
        let mut restore: Option<(CachedScene, usize, CacheOutcome)> = None;
        if let Some(cache) = &mut self.cache {
            let hit = cache.lookup(&request);
            if let Some(entry) = hit.snapshot.filter(|e| e.snapshot.is_some()) {
                let missing = triangles_in(&self.integrated, request.difference(hit.held));
                restore = Some((entry.clone(), missing, hit.outcome));
            } else if self.pristine.snapshot.is_some() {
                let all = triangles_in(&self.integrated, request.iter());
                restore = Some((self.pristine.clone(), all, CacheOutcome::Miss));
            }
        }
        let t = Instant::now();
        let cache_first = self.options.reactivation == ReactivationStrategy::CacheFirst;
        match restore.filter(|(_, cost, _)| cache_first || *cost < removal_cost) {
            Some((entry, _, outcome)) => {
                let snapshot = entry.snapshot.as_ref().expect("restorable entries only");
                self.accel.restore_static_scene(snapshot)?;
                // The scene is now the environment plus the entry's islands, under the ids
                // they had in it; the other requested islands are added again.
                self.static_owner.retain_environment();
                for island in &request {
                    let baked = self.integrated[island].baked.clone();
                    let id = match entry.ids.get(island) {
                        Some(id) => *id,
                        None => {
                            stats.built_triangles += baked.triangle_count();
                            self.accel.add_static(&baked.mesh)?
                        }
                    };
                    self.static_owner.insert(id, StaticOwner::Island(baked.clone()));
                    self.integrated.insert(*island, Integrated { id, baked });
                }
                for island in &woken {
                    self.integrated.remove(island);
                }
                stats.reactivation_path = Some(ReactivationPath::Cache(outcome));
            }
            None => {
                for island in &woken {
                    let gone = self.integrated.remove(island).expect("woken islands are integrated");
                    self.accel.remove_static(gone.id)?;
                    self.static_owner.remove(gone.id);
                }
                stats.built_triangles += removal_cost;
                stats.reactivation_path = Some(ReactivationPath::Removal);
            }
        }
        stats.islands_reactivated += woken.len() as u32;
        self.accel.commit_static()?;
        if stats.built_triangles > 0 {
            self.cost.record_build(stats.built_triangles, ms(t));
        }
        Ok(true)
    }

    /// The static scene now, for the cache.
    fn current_scene(&self) -> CachedScene {
        CachedScene {
            snapshot: self.accel.snapshot_static_scene(),
            ids: self.integrated.iter().map(|(i, x)| (*i, x.id)).collect(),
        }
    }

    fn integrate(&mut self, stats: &mut FrameStats) -> Result<bool, AccelError> {
        let policy = self.options.policy;
        if policy == IntegrationPolicy::Never {
            return Ok(false);
        }
        let frames_left =
            self.options.planned_frames.map_or(f64::INFINITY, |n| f64::from(n.saturating_sub(self.rendered)));
        let outlook = self
            .cost
            .outlook(self.sleeping.values().map(|s| f64::from(self.rendered - s.slept_at)), frames_left);
        let mut candidates = Vec::new();
        for (island, s) in &mut self.sleeping {
            if self.integrated.contains_key(island) {
                continue;
            }
            // Baking waits until the island is chosen: the decision only needs its size.
            let triangles: usize = s
                .bodies
                .iter()
                .map(|b| self.prototypes[self.bodies[b.0 as usize].prototype as usize].triangle_count())
                .sum();
            let age = self.rendered - s.slept_at;
            let estimate = (policy == IntegrationPolicy::Auto)
                .then(|| outlook.estimate(s.bodies.len(), triangles, f64::from(age)));
            candidates.push((*island, triangles, age, estimate));
        }
        let accept = match policy {
            IntegrationPolicy::Auto => {
                let estimates: Vec<CostEstimate> = candidates.iter().filter_map(|c| c.3).collect();
                choose_batch(&estimates)
            }
            _ => vec![true; candidates.len()],
        };
        let mut chosen = Vec::new();
        for ((island, triangles, age, estimate), integrate) in candidates.into_iter().zip(accept) {
            let s = self.sleeping.get_mut(&island).expect("candidate is asleep");
            if integrate || !s.decided {
                stats.decisions.push(Decision {
                    island,
                    bodies: s.bodies.len(),
                    triangles,
                    age,
                    integrate,
                    estimate,
                });
                s.decided = true;
            }
            if integrate {
                let bodies: Vec<_> = s
                    .bodies
                    .iter()
                    .zip(&s.poses)
                    .map(|(b, p)| (*b, self.bodies[b.0 as usize].prototype, *p))
                    .collect();
                let baked = Arc::new(BakedIsland::bake(island, &bodies, &self.prototypes));
                chosen.push((island, baked));
            }
        }
        if chosen.is_empty() {
            return Ok(false);
        }
        self.insert_islands(chosen, stats)?;
        Ok(true)
    }

    /// Bakes `chosen` into the static scene and takes their bodies out of the top level.
    fn insert_islands(
        &mut self,
        chosen: Vec<(IslandId, Arc<BakedIsland>)>,
        stats: &mut FrameStats,
    ) -> Result<(), AccelError> {
        // With snapshots, each island goes in with its own static build, so the cache can
        // record the scene before it; without (Embree), one build takes them all and the cache
        // records key-only entries: it answers lookups but never restores (docs/design.md).
        let per_island = self.pristine.snapshot.is_some() && self.cache.is_some();
        let (mut batch, mut t) = (0, Instant::now());
        for (island, baked) in chosen {
            let scene = self.cache.is_some().then(|| self.current_scene());
            if let (Some(cache), Some(scene)) = (&mut self.cache, scene) {
                let triangles = triangles_in(&self.integrated, scene.ids.keys());
                let key = scene.ids.keys().copied().collect();
                cache.record(&key, scene, triangles, |e| e.snapshot.as_ref().map_or(0, |s| s.unique_bytes()));
                if per_island {
                    t = Instant::now();
                }
            }
            let id = self.accel.add_static(&baked.mesh)?;
            for part in &baked.parts {
                let slot = &mut self.bodies[part.body.0 as usize];
                if let Placement::Instance { id, .. } = slot.placement {
                    self.accel.remove_instance(id)?;
                    self.instance_owner[id.0 as usize] = None;
                }
                slot.placement = Placement::Baked(island);
            }
            self.static_owner.insert(id, StaticOwner::Island(baked.clone()));
            stats.built_triangles += baked.triangle_count();
            batch += baked.triangle_count();
            self.integrated.insert(island, Integrated { id, baked });
            stats.islands_integrated += 1;
            if per_island {
                self.accel.commit_static()?;
                self.cost.record_build(batch, ms(t));
                batch = 0;
            }
        }
        if !per_island {
            self.accel.commit_static()?;
            self.cost.record_build(batch, ms(t));
        }
        Ok(())
    }

    /// Instances follow the frame: returns whether any changed.
    fn update(&mut self, frame: &ReplayFrame<'_>, stats: &mut FrameStats) -> Result<bool, AccelError> {
        let mut changed = false;
        for (b, slot) in self.bodies.iter_mut().enumerate() {
            let present = frame.is_present(b);
            let pose = frame.poses[b];
            match slot.placement {
                Placement::Baked(island) if self.integrated.contains_key(&island) => {}
                Placement::Instance { id, pose: old } if present => {
                    if old != pose {
                        self.accel.set_instance_transform(id, pose.to_affine())?;
                        self.instance_owner[id.0 as usize] =
                            Some((BodyId(b as u32), slot.prototype, normal_matrix(&pose.to_affine())));
                        slot.placement = Placement::Instance { id, pose };
                        stats.instances_moved += 1;
                        changed = true;
                    }
                }
                Placement::Instance { id, .. } => {
                    self.accel.remove_instance(id)?;
                    self.instance_owner[id.0 as usize] = None;
                    slot.placement = Placement::Absent;
                    stats.instances_removed += 1;
                    changed = true;
                }
                Placement::Absent | Placement::Baked(_) if present => {
                    let xf = pose.to_affine();
                    let id = self.accel.add_instance(self.prototype_ids[slot.prototype as usize], xf)?;
                    let i = id.0 as usize;
                    if self.instance_owner.len() <= i {
                        self.instance_owner.resize(i + 1, None);
                    }
                    self.instance_owner[i] = Some((BodyId(b as u32), slot.prototype, normal_matrix(&xf)));
                    slot.placement = Placement::Instance { id, pose };
                    stats.instances_added += 1;
                    changed = true;
                }
                Placement::Absent | Placement::Baked(_) => slot.placement = Placement::Absent,
            }
        }
        Ok(changed)
    }
}

impl ObjectMap for SceneManager {
    fn resolve(&self, object: HitObject, prim: u32) -> Option<ResolvedHit> {
        match object {
            HitObject::Instance(id) => {
                let (body, proto, m) = (*self.instance_owner.get(id.0 as usize)?)?;
                Some(ResolvedHit {
                    mesh: MeshRef::Prototype(proto),
                    prim,
                    body: Some(body),
                    normal_matrix: m,
                    baked: false,
                })
            }
            HitObject::Static(id) => match self.static_owner.get(id)? {
                StaticOwner::Environment(i) => Some(ResolvedHit {
                    mesh: MeshRef::Static(*i),
                    prim,
                    body: None,
                    normal_matrix: Mat3::IDENTITY,
                    baked: false,
                }),
                StaticOwner::Island(baked) => {
                    let (part, local) = baked.part_of(prim)?;
                    Some(ResolvedHit {
                        mesh: MeshRef::Prototype(part.prototype),
                        prim: local,
                        body: Some(part.body),
                        normal_matrix: part.normal_matrix,
                        baked: true,
                    })
                }
            },
        }
    }
}

fn triangles_in<'a>(
    integrated: &BTreeMap<IslandId, Integrated>,
    ids: impl Iterator<Item = &'a IslandId>,
) -> usize {
    ids.map(|i| integrated[i].baked.triangle_count()).sum()
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
