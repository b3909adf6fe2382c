//! Ray queries on [`EmbreeAccel`]'s committed scenes. Without resting instances a ray traces
//! the top level alone, as it always did. With them it traces the resting scene (environment
//! and resting bodies) and then the top level (the awake bodies) up to the first hit, skipping
//! the top level when the ray cannot meet its bounds before that hit; packets do the same per
//! lane, and the top level's packet is skipped when no lane needs it.
//!
//! Skipping the top level by its bounds ([`AwakeBounds`]) brought the resting form's camera
//! packets close to the all-instanced scene's trace. The other orders, the resting scene at
//! other qualities and a box test of whole packets did not pay:
//! docs/lab/accelerators.md#2026-12-01-how-rays-meet-the-resting-level-the-bvhs-order-embrees-skipped-top-level
//! One scene per ray (Embree's two-level builder over arrays of bodies) traced no faster:
//! docs/lab/accelerators.md#2026-12-07-one-scene-for-the-resting-form-embrees-two-level-builder-over-arrays-of-bodies-not-kept
//!
//! [`AwakeBounds`]: super::awake_bounds::AwakeBounds

use std::array;

use glam::{Mat3, Vec3};

use super::{EmbreeAccel, STATIC_SLOT};
use crate::accel::{Hit, HitObject, InstanceId, Occluder, SceneQuery, StaticId};
use crate::geometry::Ray;
use dormant_embree::{Coherence, EmbreeHit, EmbreeOccluder, PacketRay, SceneView};

/// Widest packet: rays are traced in chunks of this many.
const LANES: usize = 16;

impl EmbreeAccel {
    /// The resting scene, when it holds instances (rays then trace it and the top level).
    fn resting_view(&self) -> Option<SceneView<'_>> {
        if self.static_in_resting {
            self.resting.view().map(|v| v.skipping(&self.ghosts))
        } else {
            None
        }
    }

    /// `h`, a hit of `ray`, with its normal in world space: Embree reports an instance hit's
    /// normal in object space, turned by the instance's rotation at the ray's time when it
    /// moves.
    fn to_hit(&self, h: EmbreeHit, ray: &Ray) -> Hit {
        let ng = Vec3::from_array(h.ng);
        let (object, ng) = match h.inst_id {
            Some(STATIC_SLOT) | None => (HitObject::Static(StaticId(h.geom_id)), ng),
            Some(slot) => {
                let id = slot - 1;
                let m = self.instances[id as usize].as_ref().map_or(Mat3::IDENTITY, |s| match &s.motion {
                    Some(motion) => motion.normal_matrix_at(ray.time),
                    None => s.normal_matrix,
                });
                (HitObject::Instance(InstanceId(id)), m * ng)
            }
        };
        Hit { t: h.t, u: h.u, v: h.v, ng: ng.normalize_or_zero(), object, prim: h.prim_id }
    }

    /// The blocker Embree reported, as the scene's object.
    fn to_occluder(found: Option<EmbreeOccluder>) -> Occluder {
        match found.map(|o| o.inst_id) {
            None => Occluder::Unknown,
            Some(Some(STATIC_SLOT) | None) => Occluder::Static,
            Some(Some(slot)) => Occluder::Instance(InstanceId(slot - 1)),
        }
    }

    /// `ray` cut at `t_max`, if it may meet an awake body in the top level before then (only
    /// asked while the resting scene is in use).
    fn awake_part(&self, ray: &Ray, t_max: f32) -> Option<Ray> {
        self.awake_bounds.may_hit(ray, t_max).then_some(Ray { t_max, ..*ray })
    }
}

impl SceneQuery for EmbreeAccel {
    /// With a resting scene: its closest hit, then the top level's awake bodies up to it.
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let top = self.top.view()?;
        let (o, d, time) = (ray.origin.to_array(), ray.dir.to_array(), ray.time);
        let Some(resting) = self.resting_view() else {
            return top.intersect1_at(o, d, ray.t_min, ray.t_max, time).map(|h| self.to_hit(h, ray));
        };
        let first = resting.intersect1_at(o, d, ray.t_min, ray.t_max, time);
        let awake = self
            .awake_part(ray, first.map_or(ray.t_max, |h| h.t))
            .and_then(|r| top.intersect1_at(o, d, r.t_min, r.t_max, time));
        awake.or(first).map(|h| self.to_hit(h, ray))
    }

    fn intersect_p(&self, ray: &Ray) -> bool {
        let (o, d, time) = (ray.origin.to_array(), ray.dir.to_array(), ray.time);
        let Some(top) = self.top.view() else { return false };
        match self.resting_view() {
            None => top.occluded1_at(o, d, ray.t_min, ray.t_max, time),
            Some(resting) => {
                resting.occluded1_at(o, d, ray.t_min, ray.t_max, time)
                    || (self.awake_part(ray, ray.t_max).is_some()
                        && top.occluded1_at(o, d, ray.t_min, ray.t_max, time))
            }
        }
    }

    /// As [`Self::intersect_p`], the occlusion queries through a filter that records the hit
    /// each stops at.
    fn occluder(&self, ray: &Ray) -> Option<Occluder> {
        let (o, d, time) = (ray.origin.to_array(), ray.dir.to_array(), ray.time);
        let top = self.top.view()?;
        let found = match self.resting_view() {
            None => top.occluder1_at(o, d, ray.t_min, ray.t_max, time),
            Some(resting) => resting.occluder1_at(o, d, ray.t_min, ray.t_max, time).or_else(|| {
                self.awake_part(ray, ray.t_max)?;
                top.occluder1_at(o, d, ray.t_min, ray.t_max, time)
            }),
        };
        found.map(Self::to_occluder)
    }

    /// Chunks of up to 16 rays, each as one packet of the smallest width that holds it; with a
    /// resting scene, its packet first, then the top level's for the lanes that may meet an
    /// awake body before their hit (none: no second packet).
    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        let Some(top) = self.top.view() else {
            hits.fill(None);
            return;
        };
        let Some(resting) = self.resting_view() else {
            self.intersect_chunks(top, rays, hits);
            return;
        };
        for (rays, hits) in rays.chunks(LANES).zip(hits.chunks_mut(LANES)) {
            match rays.len() {
                0..=4 => self.closest_two_scenes(resting, top, rays, hits, SceneView::intersect4),
                5..=8 => self.closest_two_scenes(resting, top, rays, hits, SceneView::intersect8),
                _ => self.closest_two_scenes(resting, top, rays, hits, SceneView::intersect16),
            }
        }
    }

    /// Packets as in [`Self::intersect_packet`]; the top level's only for lanes the resting
    /// scene did not block and that may meet an awake body.
    fn intersect_p_packet(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one result slot per ray");
        let Some(top) = self.top.view() else {
            occluded.fill(false);
            return;
        };
        let Some(resting) = self.resting_view() else {
            occluded_chunks(top, rays, occluded);
            return;
        };
        for (rays, out) in rays.chunks(LANES).zip(occluded.chunks_mut(LANES)) {
            let n = rays.len();
            let mut found = blocked(resting, &array::from_fn(|i| rays.get(i).copied()), n);
            let mut open = [None; LANES];
            let mut any = false;
            for ((o, r), f) in open.iter_mut().zip(rays).zip(&found) {
                *o = if *f { None } else { self.awake_part(r, r.t_max) };
                any |= o.is_some();
            }
            if any {
                for (f, a) in found.iter_mut().zip(blocked(top, &open, n)) {
                    *f |= a;
                }
            }
            out.copy_from_slice(&found[..n]);
        }
    }
}

impl EmbreeAccel {
    /// Closest hits of up to `N` rays: the resting scene's packet, then the top level's for
    /// the lanes that may meet an awake body before their hit.
    fn closest_two_scenes<'v, const N: usize>(
        &self,
        resting: SceneView<'v>,
        top: SceneView<'v>,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        packet: impl Fn(&SceneView<'v>, &[Option<Ray>; N], Coherence) -> [Option<EmbreeHit>; N],
    ) {
        let first = packet(&resting, &lanes(rays), CLOSEST);
        let mut cut = [None; N];
        let mut any = false;
        for ((c, r), f) in cut.iter_mut().zip(rays).zip(&first) {
            *c = self.awake_part(r, f.map_or(r.t_max, |h| h.t));
            any |= c.is_some();
        }
        if any {
            let awake = packet(&top, &cut, CLOSEST);
            for (((slot, a), f), r) in hits.iter_mut().zip(awake).zip(first).zip(rays) {
                *slot = a.or(f).map(|h| self.to_hit(h, r));
            }
        } else {
            for ((slot, f), r) in hits.iter_mut().zip(first).zip(rays) {
                *slot = f.map(|h| self.to_hit(h, r));
            }
        }
    }

    /// Closest hits of `rays` in `view`, in packets of up to 16 (the top level alone).
    fn intersect_chunks(&self, view: SceneView<'_>, rays: &[Ray], hits: &mut [Option<Hit>]) {
        let c = CLOSEST;
        for (rays, hits) in rays.chunks(LANES).zip(hits.chunks_mut(LANES)) {
            let mut put = |found: &[Option<EmbreeHit>]| {
                for ((slot, h), r) in hits.iter_mut().zip(found).zip(rays) {
                    *slot = h.map(|h| self.to_hit(h, r));
                }
            };
            match rays.len() {
                0..=4 => put(&view.intersect4(&lanes(rays), c)),
                5..=8 => put(&view.intersect8(&lanes(rays), c)),
                _ => put(&view.intersect16(&lanes(rays), c)),
            }
        }
    }
}

/// Closest-hit packets are camera rays of neighbouring pixels, which the COHERENT hint traces as
/// fast or faster: docs/lab/rendering.md#2026-11-22-ray-packets-on-embree-rtcintersect4816-rtcoccluded4816
const CLOSEST: Coherence = Coherence::Coherent;
/// Shadow rays towards the sun: COHERENT traced them slower (the same entry), so Embree's
/// default.
const OCCLUSION: Coherence = Coherence::Incoherent;

/// Occlusion of `rays` in `view`, in packets of up to 16 (the top level alone).
fn occluded_chunks(view: SceneView<'_>, rays: &[Ray], occluded: &mut [bool]) {
    let c = OCCLUSION;
    for (rays, out) in rays.chunks(LANES).zip(occluded.chunks_mut(LANES)) {
        let n = rays.len();
        match n {
            0..=4 => out.copy_from_slice(&view.occluded4(&lanes(rays), c)[..n]),
            5..=8 => out.copy_from_slice(&view.occluded8(&lanes(rays), c)[..n]),
            _ => out.copy_from_slice(&view.occluded16(&lanes(rays), c)[..n]),
        }
    }
}

/// A packet's lanes: `rays` first, the rest inactive.
fn lanes<const N: usize>(rays: &[Ray]) -> [Option<Ray>; N] {
    array::from_fn(|i| rays.get(i).copied())
}

/// Occlusion of the first `n` lanes in `view`, packets as in [`closest`].
fn blocked(view: SceneView<'_>, lanes: &[Option<Ray>; LANES], n: usize) -> [bool; LANES] {
    let c = OCCLUSION;
    let mut out = [false; LANES];
    match n {
        0..=4 => out[..4].copy_from_slice(&view.occluded4(&prefix(lanes), c)),
        5..=8 => out[..8].copy_from_slice(&view.occluded8(&prefix(lanes), c)),
        _ => out = view.occluded16(lanes, c),
    }
    out
}

/// The first `N` lanes.
fn prefix<const N: usize>(lanes: &[Option<Ray>; LANES]) -> [Option<Ray>; N] {
    array::from_fn(|i| lanes[i])
}

/// Rays as the wrapper's packet queries read them.
impl PacketRay for Ray {
    #[inline]
    fn origin(&self) -> Vec3 {
        self.origin
    }

    #[inline]
    fn direction(&self) -> Vec3 {
        self.dir
    }

    #[inline]
    fn interval(&self) -> (f32, f32) {
        (self.t_min, self.t_max)
    }

    #[inline]
    fn time(&self) -> f32 {
        self.time
    }
}
