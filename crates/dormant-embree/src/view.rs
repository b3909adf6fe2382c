//! [`SceneView`]: the single-ray queries of a committed Embree scene (closest hit and
//! occlusion, at a shutter time, skipping chosen instances), and the hit they report
//! ([`EmbreeHit`]). Ray packets are `packet.rs`'s.

use std::marker::PhantomData;

use embree4_sys as sys;
use glam::Vec3;

use super::filter::{self, GeometrySet, OccluderContext, SkipContext};

/// A closest hit as Embree reports it. For an instanced hit, `ng` is in the instanced
/// object's space and `inst_id` names the instance geometry in the top scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmbreeHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub ng: [f32; 3],
    pub prim_id: u32,
    pub geom_id: u32,
    pub inst_id: Option<u32>,
}

/// What blocked an occlusion ray ([`SceneView::occluder1_at`]): the instance (in the traced
/// scene) and geometry of one hit on it, not necessarily the nearest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeOccluder {
    pub geom_id: u32,
    pub inst_id: Option<u32>,
}

/// Ray queries on a committed scene. Borrowing the scene keeps it unchanged while rays run.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub(super) raw: sys::RTCScene,
    /// Instances (by geometry id in this scene) whose hits rays reject.
    pub(super) skip: Option<&'a GeometrySet>,
    /// The scene borrowed: it stays committed and alive while rays run.
    _scene: PhantomData<&'a ()>,
}

// SAFETY: rtcIntersect1/rtcOccluded1 may run concurrently on one committed scene from many
// threads (rtcIntersect1(3)); the borrow keeps the scene committed and alive.
unsafe impl Send for SceneView<'_> {}
// SAFETY: see `Send`.
unsafe impl Sync for SceneView<'_> {}

fn embree_ray(org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32, time: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: org[0],
        org_y: org[1],
        org_z: org[2],
        tnear,
        dir_x: dir[0],
        dir_y: dir[1],
        dir_z: dir[2],
        time,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl<'a> SceneView<'a> {
    /// The view of `raw`, a committed scene the caller keeps alive and unchanged for `'a`.
    pub(super) fn new(raw: sys::RTCScene) -> Self {
        SceneView { raw, skip: None, _scene: PhantomData }
    }

    /// The same scene, with every hit inside the instances in `skip` (geometry ids in this
    /// scene) rejected; an empty set is no filter at all.
    pub fn skipping(self, skip: &'a GeometrySet) -> SceneView<'a> {
        SceneView { skip: (!skip.is_empty()).then_some(skip), ..self }
    }

    /// The query context that carries the skipped set, if any.
    pub(super) fn skip_context(&self) -> Option<SkipContext<'a>> {
        self.skip.map(SkipContext::new)
    }

    /// Closest hit in `[tnear, tfar]` of a ray at shutter time `time` (motion blur).
    pub fn intersect1_at(
        &self,
        org: [f32; 3],
        dir: [f32; 3],
        tnear: f32,
        tfar: f32,
        time: f32,
    ) -> Option<EmbreeHit> {
        let mut rayhit = sys::RTCRayHit {
            ray: embree_ray(org, dir, tnear, tfar, time),
            hit: sys::RTCHit {
                geomID: sys::RTC_INVALID_GEOMETRY_ID,
                instID: [sys::RTC_INVALID_GEOMETRY_ID; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize],
                ..Default::default()
            },
        };
        let mut context = self.skip_context();
        let mut args = filter::intersect_args(sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT);
        if let Some(c) = context.as_mut() {
            c.intersect_args(&mut args);
        }
        // SAFETY: `rayhit` is an `RTCRayHit` laid out by bindings generated from the linked
        // library's headers (so the library writes within it); the scene is committed and
        // alive for the borrow; `args` is initialised as rtcInitIntersectArguments does and
        // its context, if any, lives until the call returns.
        unsafe { sys::rtcIntersect1(self.raw, &mut rayhit, &mut args) };
        let h = &rayhit.hit;
        (h.geomID != sys::RTC_INVALID_GEOMETRY_ID).then(|| EmbreeHit {
            t: rayhit.ray.tfar,
            u: h.u,
            v: h.v,
            ng: [h.Ng_x, h.Ng_y, h.Ng_z],
            prim_id: h.primID,
            geom_id: h.geomID,
            inst_id: (h.instID[0] != sys::RTC_INVALID_GEOMETRY_ID).then_some(h.instID[0]),
        })
    }

    /// Whether anything lies in `[tnear, tfar]` of a ray at shutter time `time`.
    pub fn occluded1_at(&self, org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32, time: f32) -> bool {
        let mut ray = embree_ray(org, dir, tnear, tfar, time);
        let mut context = self.skip_context();
        let mut args = filter::occluded_args(sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT);
        if let Some(c) = context.as_mut() {
            c.occluded_args(&mut args);
        }
        // SAFETY: as in `intersect1`; rtcOccluded1 writes only `ray.tfar`.
        unsafe { sys::rtcOccluded1(self.raw, &mut ray, &mut args) };
        ray.tfar == f32::NEG_INFINITY
    }

    /// What lies in `[tnear, tfar]` of a ray at shutter time `time`: `None` exactly when
    /// [`Self::occluded1_at`] is `false`, else one of the hits (`Some(None)` if Embree reported
    /// none to the filter, which every triangle hit is).
    pub fn occluder1_at(
        &self,
        org: [f32; 3],
        dir: [f32; 3],
        tnear: f32,
        tfar: f32,
        time: f32,
    ) -> Option<Option<EmbreeOccluder>> {
        let mut ray = embree_ray(org, dir, tnear, tfar, time);
        let mut context = OccluderContext::new(self.skip);
        let mut args = filter::occluded_args(sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT);
        context.occluded_args(&mut args);
        // SAFETY: as in `occluded1_at`; the context lives until the call returns.
        unsafe { sys::rtcOccluded1(self.raw, &mut ray, &mut args) };
        let invalid = sys::RTC_INVALID_GEOMETRY_ID;
        (ray.tfar == f32::NEG_INFINITY).then(|| {
            (context.geom != invalid).then(|| EmbreeOccluder {
                geom_id: context.geom,
                inst_id: (context.inst != invalid).then_some(context.inst),
            })
        })
    }

    /// World bounds of the committed scene: its lower and upper corners.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut b = sys::RTCBounds::default();
        // SAFETY: the scene is committed; `b` is a valid output struct.
        unsafe { sys::rtcGetSceneBounds(self.raw, &mut b) };
        (Vec3::new(b.lower_x, b.lower_y, b.lower_z), Vec3::new(b.upper_x, b.upper_y, b.upper_z))
    }
}
