//! The committed scene rays see: the static snapshot, the resting level over instances at rest
//! and the top level over awake instances, each instance holding its prototype's bottom-level
//! BVH and inverse transform. Rays are transformed into object space per instance; normals go
//! back with the inverse transpose.
//!
//! Closest hits trace the three structures one after the other, each up to the nearest hit so
//! far: the static tree, the resting level, then the top level. Static first, because in
//! scenes of piles inside a large environment most rays end on the environment; resting first
//! gains a little where bodies stand in front of the floor but costs piles much more.
//! Without resting instances the resting level is empty. Any-hit queries trace the static tree
//! first too. The other orders measured, a root over the three, and the instance levels first
//! for rays that start among the bodies:
//! docs/lab/accelerators.md#2026-12-01-how-rays-meet-the-resting-level-the-bvhs-order-embrees-skipped-top-level

use std::sync::Arc;

use glam::{Affine3A, Mat3, Vec3};
use rayon::prelude::*;

use crate::accel::bvh::flat::{
    build, each_bit, interval_is_valid, BoxRay, FlatBvh, Lanes, MeshBvh, PacketLanes, PrimHit, RayPacket,
    Start, Wide, ANY_HIT, CLOSEST_HIT, PACKET,
};
use crate::accel::bvh::persistent::StaticSnapshot;
use crate::accel::bvh::simd::{dispatch, Kernel};
use crate::accel::bvh::triangle::RayTri;
use crate::accel::bvh::BuildParams;
use crate::accel::{Hit, HitObject, InstanceId, Occluder, SceneQuery, StaticId};
use crate::geometry::{Aabb, InstanceMotion, Ray};

/// Instances per rayon task when a level's bounds and items are made in parallel.
const PAR_CHUNK: usize = 1024;

/// One instance as traversal needs it: what a ray reads to enter it, in one cache line (with
/// the inverse as an `Affine3A`, the normal matrix and the motion inline it took three):
/// docs/lab/accelerators.md#2026-12-02-counted-instead-of-timed-cachegrind-instance-records-child-codes
#[derive(Clone, Debug)]
#[repr(C, align(64))]
pub(crate) struct TopItem {
    /// Linear part of the inverse transform: object directions are `linear * dir`. Its
    /// transpose takes object normals to world (the inverse transpose of the forward part).
    linear: Mat3,
    /// The forward transform's translation: object origins are `linear * (o - translation)`.
    translation: Vec3,
    pub(crate) blas: Arc<MeshBvh>,
    pub id: u32,
    /// A ghost of the resting level: its instance woke, moved or was removed since the level
    /// was built, and rays skip it (`crate::accel::RestingSchedule`).
    pub(crate) ghost: bool,
    /// Whether the instance moves over the shutter ([`Top::motion`]; top level only).
    moving: bool,
}

const _: () = assert!(std::mem::size_of::<TopItem>() == 64);

/// An instance hit: the triangle hit in object space, the instance and, if it moves, its
/// motion.
type InstanceHit<'a> = (PrimHit, &'a TopItem, Option<&'a InstanceMotion>);

/// One instance for [`build_top`]: id, prototype BVH, transform, its inverse and its motion.
pub(crate) type TopInstance = (u32, Arc<MeshBvh>, Affine3A, Affine3A, Option<InstanceMotion>);

/// A BVH over instances (the per-frame top level, or the resting level); `items` are in leaf
/// order.
#[derive(Clone, Debug, Default)]
pub(crate) struct Top {
    pub bvh: FlatBvh,
    pub(crate) wide: Wide,
    pub items: Vec<TopItem>,
    /// Per item, its motion over the shutter (motion blur): rays see a moving instance where
    /// it is at their time instead of at its transform ([`object_ray`]).
    motion: Vec<Option<Box<InstanceMotion>>>,
    /// Position in `items` of each instance id (`u32::MAX`: not in this level).
    leaf_of: Vec<u32>,
}

/// Builds a BVH over `(instance id, prototype BVH, transform, inverse)`: world bounds and
/// items in parallel chunks, the tree by the parallel binned-SAH builder.
/// A moving instance's box holds it over the whole shutter.
pub(crate) fn build_top(instances: &[TopInstance], params: BuildParams) -> Top {
    let bounds: Vec<Aabb> = instances
        .par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|(_, blas, xf, _, motion)| match motion {
            Some(m) => m.bounds(&blas.bounds()),
            // The moved root box, as Embree bounds an instance. The union of the root's
            // children's boxes, each moved, is tighter for a rotated body, but building it costs
            // every frame's top level more than the trace gains:
            // docs/lab/accelerators.md#2026-12-03-a-leafs-two-packets-in-one-avx2-test-cachegrind
            None => blas.bounds().transformed(xf),
        })
        .collect();
    let (bvh, order) = build(&bounds, params);
    let (items, motion): (Vec<TopItem>, Vec<_>) = order
        .par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|&i| {
            let (id, blas, xf, inv, motion) = &instances[i as usize];
            let item = TopItem {
                linear: inv.matrix3.into(),
                translation: xf.translation.into(),
                blas: blas.clone(),
                id: *id,
                ghost: false,
                moving: motion.is_some(),
            };
            (item, motion.map(Box::new))
        })
        .unzip();
    let wide = Wide::new(&bvh, |_, n| (n.first, n.count));
    let mut leaf_of = vec![u32::MAX; items.iter().map(|x| x.id as usize + 1).max().unwrap_or(0)];
    for (i, item) in items.iter().enumerate() {
        leaf_of[item.id as usize] = i as u32;
    }
    Top { bvh, wide, items, motion, leaf_of }
}

impl Top {
    /// Makes instance `id`'s copy a ghost that rays skip; false if it has none here.
    pub(crate) fn ghost(&mut self, id: u32) -> bool {
        match self.leaf_of.get(id as usize).copied().filter(|&i| i != u32::MAX) {
            Some(i) => {
                self.items[i as usize].ghost = true;
                true
            }
            None => false,
        }
    }

    /// The items of leaf range `first..first + count` that rays enter (not ghosts), each with
    /// its motion if it moves.
    #[inline(always)]
    fn live(&self, first: u32, count: u32) -> impl Iterator<Item = (&TopItem, Option<&InstanceMotion>)> {
        let range = first as usize..(first + count) as usize;
        self.items[range.clone()]
            .iter()
            .zip(range)
            .filter(|(item, _)| !item.ghost)
            .map(|(item, i)| (item, if item.moving { self.motion[i].as_deref() } else { None }))
    }

    /// Closest instance hit with `t <= *t_max`; lowers `*t_max` and overwrites `hit` when it
    /// finds one.
    #[inline(always)]
    fn intersect_with<'a, K: Kernel>(
        &'a self,
        k: K,
        ray: &Ray,
        bray: &BoxRay,
        t_max: &mut f32,
        hit: &mut Option<InstanceHit<'a>>,
    ) {
        self.wide.traverse::<_, _, CLOSEST_HIT>(
            k,
            &self.bvh,
            Start::Test(0),
            bray,
            t_max,
            &mut |first, count, t_max| {
                for (item, motion) in self.live(first, count) {
                    let oray = object_ray(ray, item, motion);
                    let mut best = None;
                    // The `RayTri` is made on entry: made at the first leaf reached instead, so
                    // that an instance left without reaching a leaf skips it, it timed as noise
                    // and counted more mispredictions:
                    // docs/lab/accelerators.md#2026-12-03-redundant-box-tests-and-stack-round-trips-removed-cachegrind
                    if item.blas.intersect_from(
                        k,
                        Start::Entered(0),
                        &BoxRay::new(&oray),
                        &RayTri::new(&oray),
                        t_max,
                        &mut best,
                    ) {
                        if let Some(h) = best {
                            *hit = Some((h, item, motion));
                        }
                    }
                }
                false
            },
        );
    }

    /// The first instance found hit within `[t_min, t_max]`, if any (any-hit: not the
    /// nearest).
    #[inline(always)]
    fn occluder_with<K: Kernel>(&self, k: K, ray: &Ray, bray: &BoxRay, t_max: f32) -> Option<InstanceId> {
        let mut t_max = t_max;
        let mut found = None;
        self.wide.traverse::<_, _, ANY_HIT>(
            k,
            &self.bvh,
            Start::Test(0),
            bray,
            &mut t_max,
            &mut |first, count, t_max| {
                found = self.live(first, count).find_map(|(item, motion)| {
                    let oray = object_ray(ray, item, motion);
                    item.blas
                        .occluded_from(k, Start::Entered(0), &BoxRay::new(&oray), &RayTri::new(&oray), *t_max)
                        .then_some(InstanceId(item.id))
                });
                found.is_some()
            },
        );
        found
    }
}

/// Packet queries: the level's tree walked by the world packet, each instance entered by the
/// lanes that reach it, with their rays in its object space ([`object_ray`], per lane).
impl Top {
    /// [`Self::intersect_with`] for the `lanes` of `packet`, made of `rays`.
    #[inline(always)]
    fn intersect_packet_with<'a, K: Kernel>(
        &'a self,
        k: K,
        rays: &[Ray],
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &mut [f32; PACKET],
        hit: &mut [Option<InstanceHit<'a>>; PACKET],
    ) {
        // Object-space lanes are rewritten per instance; the others are never read.
        let mut object = *packet;
        self.wide.traverse_packet(
            k,
            &self.bvh,
            Start::Test(0),
            PacketLanes { packet, lanes },
            t_max,
            &mut |first, count, lanes, t_max| {
                for (item, motion) in self.live(first, count) {
                    for i in each_bit(lanes) {
                        object.set(i, &object_ray(&rays[i], item, motion));
                    }
                    let mut best = [None; PACKET];
                    let found = item.blas.intersect_packet_from(
                        k,
                        Start::Entered(0),
                        &object,
                        lanes,
                        t_max,
                        &mut best,
                    );
                    for i in each_bit(found) {
                        if let Some(h) = best[i] {
                            hit[i] = Some((h, item, motion));
                        }
                    }
                }
                0
            },
        );
    }

    /// [`Self::occluded_with`] for the `lanes` of `packet`: the lanes blocked.
    #[inline(always)]
    fn occluded_packet_with<K: Kernel>(
        &self,
        k: K,
        rays: &[Ray],
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &[f32; PACKET],
    ) -> Lanes {
        let mut object = *packet;
        let mut t_max = *t_max;
        self.wide.traverse_packet(
            k,
            &self.bvh,
            Start::Test(0),
            PacketLanes { packet, lanes },
            &mut t_max,
            &mut |first, count, lanes, t_max| {
                let mut left = lanes;
                for (item, motion) in self.live(first, count) {
                    if left == 0 {
                        break;
                    }
                    for i in each_bit(left) {
                        object.set(i, &object_ray(&rays[i], item, motion));
                    }
                    left &= !item.blas.occluded_packet_from(k, Start::Entered(0), &object, left, t_max);
                }
                lanes & !left
            },
        )
    }
}

/// The ray in the instance's object space. The origin is moved by the forward translation
/// before the inverse linear part is applied: `inv * o` would add two large, nearly
/// cancelling terms for instances far from the world origin (errors beyond Embree's on ducks
/// 40 units out: docs/lab/crosscheck.md#2026-11-22-the-bvhs-object-rays-translation-first), while
/// `o - translation` is nearly exact.
///
/// A moving instance is placed at the ray's time first (its rotation is inverted by the
/// conjugate), as Embree interpolates a motion instance per ray.
#[inline]
fn object_ray(ray: &Ray, item: &TopItem, motion: Option<&InstanceMotion>) -> Ray {
    // Origin and direction as values, one `Ray` built from them: with a `Ray` returned from
    // each branch the two were merged in memory, stored in 8- and 4-byte pieces and read back
    // in 16, a failed store forward on every instance entered:
    // docs/lab/accelerators.md#2026-12-02-the-node-step-and-leaves-one-idea-at-a-time-second-pass
    let (origin, dir) = match motion {
        Some(motion) => moving_object_frame(ray, motion),
        None => (item.linear * (ray.origin - item.translation), item.linear * ray.dir),
    };
    Ray { origin, dir, ..*ray }
}

/// [`object_ray`]'s origin and direction for an instance that moves over the shutter.
#[cold]
fn moving_object_frame(ray: &Ray, motion: &InstanceMotion) -> (Vec3, Vec3) {
    let at = motion.at(ray.time);
    let back = at.rotation.conjugate();
    (back * (ray.origin - at.translation), back * ray.dir)
}

impl TopItem {
    /// Object normal `n` in world space for a hit by a ray at shutter time `time` (`motion`:
    /// the instance's, if it moves).
    #[inline]
    fn world_normal(&self, n: Vec3, time: f32, motion: Option<&InstanceMotion>) -> Vec3 {
        match motion {
            Some(m) => m.at(time).rotation * n,
            None => self.linear.transpose() * n,
        }
    }
}

/// A committed scene. Cheap to keep: everything in it is shared.
#[derive(Clone, Debug, Default)]
pub(crate) struct BvhScene {
    pub(crate) statics: StaticSnapshot,
    /// Instances at rest: rebuilt only when their set changes.
    pub(crate) resting: Top,
    /// Awake instances: rebuilt at each commit that changed one.
    pub(crate) top: Top,
}

fn unit(n: Vec3) -> Vec3 {
    n.normalize_or_zero()
}

/// The hit a ray reports from its closest static and instance hits (an instance hit, if any,
/// is the nearer: instances record only hits nearer than the static one).
#[inline(always)]
fn scene_hit(ray: &Ray, static_hit: Option<PrimHit>, inst_hit: Option<InstanceHit>) -> Option<Hit> {
    if let Some((h, item, motion)) = inst_hit {
        return Some(Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            ng: unit(item.world_normal(h.tri.normal(), ray.time, motion)),
            object: HitObject::Instance(InstanceId(item.id)),
            prim: h.tri.prim,
        });
    }
    static_hit.map(|h| Hit {
        t: h.t,
        u: h.u,
        v: h.v,
        ng: unit(h.tri.normal()),
        object: HitObject::Static(StaticId(h.tri.geom)),
        prim: h.tri.prim,
    })
}

impl SceneQuery for BvhScene {
    /// The static tree, the resting level, then the top level, each up to the closest hit
    /// found so far (see the measurements at the top). Without resting instances that is the
    /// static tree and the top level, as it always was.
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !interval_is_valid(ray) {
            return None;
        }
        dispatch!(|k| self.intersect_k(k, ray))
    }

    fn intersect_p(&self, ray: &Ray) -> bool {
        self.occluder(ray).is_some()
    }

    fn occluder(&self, ray: &Ray) -> Option<Occluder> {
        if !interval_is_valid(ray) {
            return None;
        }
        dispatch!(|k| self.occluder_k(k, ray))
    }

    /// Groups of up to [`PACKET`] rays walk the trees together (`flat::packet`); a group of
    /// one is traced as a single ray.
    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (rays, hits) in rays.chunks(PACKET).zip(hits.chunks_mut(PACKET)) {
            match rays {
                [ray] => hits[0] = self.intersect(ray),
                _ => dispatch!(|k| self.intersect_packet_k(k, rays, hits)),
            }
        }
    }

    fn intersect_p_packet(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one result slot per ray");
        for (rays, occluded) in rays.chunks(PACKET).zip(occluded.chunks_mut(PACKET)) {
            match rays {
                [ray] => occluded[0] = self.intersect_p(ray),
                _ => {
                    let blocked = dispatch!(|k| self.occluded_packet_k(k, rays));
                    for (i, o) in occluded.iter_mut().enumerate() {
                        *o = blocked >> i & 1 == 1;
                    }
                }
            }
        }
    }
}

/// The packet of `rays` (2 to [`PACKET`]), its valid lanes and their `t_max`.
fn prepared(rays: &[Ray]) -> (RayPacket, Lanes, [f32; PACKET]) {
    let mut lanes = 0;
    let mut t_max = [f32::NEG_INFINITY; PACKET];
    for (i, ray) in rays.iter().enumerate() {
        if interval_is_valid(ray) {
            lanes |= 1 << i;
            t_max[i] = ray.t_max;
        }
    }
    (RayPacket::new(rays), lanes, t_max)
}

impl BvhScene {
    /// [`SceneQuery::intersect`] on SIMD path `K`.
    #[inline(always)]
    fn intersect_k<K: Kernel>(&self, k: K, ray: &Ray) -> Option<Hit> {
        let bray = BoxRay::new(ray);
        let tray = RayTri::new(ray);
        let mut t_max = ray.t_max;
        let mut static_hit: Option<PrimHit> = None;
        self.statics.intersect_with(k, &bray, &tray, &mut t_max, &mut static_hit);
        // Instances record only hits up to the nearest so far: one found is nearer.
        let mut inst_hit: Option<InstanceHit> = None;
        // One call site for both levels, so that its leaf closure is inlined into the SIMD
        // path's entry (see `flat::Wide::traverse`).
        for level in [&self.resting, &self.top] {
            level.intersect_with(k, ray, &bray, &mut t_max, &mut inst_hit);
        }
        scene_hit(ray, static_hit, inst_hit)
    }

    /// [`SceneQuery::intersect_packet`] of up to [`PACKET`] rays on SIMD path `K`: the same
    /// order of structures as [`Self::intersect_k`].
    #[inline(always)]
    fn intersect_packet_k<K: Kernel>(&self, k: K, rays: &[Ray], hits: &mut [Option<Hit>]) {
        let (packet, lanes, mut t_max) = prepared(rays);
        let mut static_hit = [None; PACKET];
        self.statics.intersect_packet_with(k, &packet, lanes, &mut t_max, &mut static_hit);
        let mut inst_hit = [None; PACKET];
        for level in [&self.resting, &self.top] {
            level.intersect_packet_with(k, rays, &packet, lanes, &mut t_max, &mut inst_hit);
        }
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            *hit = scene_hit(ray, static_hit[i], inst_hit[i]);
        }
    }

    /// [`SceneQuery::intersect_p_packet`] of up to [`PACKET`] rays on SIMD path `K`: the
    /// blocked lanes.
    #[inline(always)]
    fn occluded_packet_k<K: Kernel>(&self, k: K, rays: &[Ray]) -> Lanes {
        let (packet, lanes, t_max) = prepared(rays);
        let mut blocked = self.statics.occluded_packet_with(k, &packet, lanes, &t_max);
        for level in [&self.resting, &self.top] {
            let left = lanes & !blocked;
            if left == 0 {
                break;
            }
            blocked |= level.occluded_packet_with(k, rays, &packet, left, &t_max);
        }
        blocked
    }

    /// [`SceneQuery::occluder`] on SIMD path `K`: the static tree, then the resting and top
    /// levels.
    #[inline(always)]
    fn occluder_k<K: Kernel>(&self, k: K, ray: &Ray) -> Option<Occluder> {
        let bray = BoxRay::new(ray);
        let tray = RayTri::new(ray);
        if self.statics.occluded_with(k, &bray, &tray, ray.t_max) {
            return Some(Occluder::Static);
        }
        [&self.resting, &self.top]
            .into_iter()
            .find_map(|level| level.occluder_with(k, ray, &bray, ray.t_max))
            .map(Occluder::Instance)
    }
}
