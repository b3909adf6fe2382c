//! Ray packets on a committed scene: [`SceneView`]'s `intersect4/8/16` and `occluded4/8/16`
//! (rtcIntersectN / rtcOccludedN), with the packet and its valid mask in Rust structs whose
//! alignment the types guarantee.

use std::array;

use embree4_sys as sys;

use super::filter::{intersect_args, occluded_args};
use super::view::{EmbreeHit, SceneView};
use glam::Vec3;

/// Embree's hint on how alike a packet's rays are (`RTC_RAY_QUERY_FLAG_COHERENT` /
/// `..._INCOHERENT`): it may pick its traversal by it; results do not depend on it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coherence {
    #[default]
    Incoherent,
    Coherent,
}

impl Coherence {
    fn flags(self) -> sys::RTCRayQueryFlags::Type {
        match self {
            Coherence::Incoherent => sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT,
            Coherence::Coherent => sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_COHERENT,
        }
    }
}

/// A ray as the packet queries read it; the caller's ray type implements it.
pub trait PacketRay {
    fn origin(&self) -> Vec3;
    /// Not necessarily normalised; hit distances are in its units.
    fn direction(&self) -> Vec3;
    /// The interval `[t_min, t_max]` hits may lie in.
    fn interval(&self) -> (f32, f32);
    /// The shutter time, from 0 (open) to 1 (close).
    fn time(&self) -> f32;
}

/// Embree wants a packet, and its valid mask, aligned to the packet's byte width: 16 bytes
/// for 4 rays, 32 for 8, 64 for 16 (rtcIntersect4(3)). 64 serves every width.
#[repr(C, align(64))]
struct Aligned<T>(T);

// The generated structs carry RTC_ALIGN from the headers; the wrapper does not rely on it.
const _: () = {
    assert!(std::mem::align_of::<Aligned<sys::RTCRayHit16>>() >= 64);
    assert!(std::mem::align_of::<Aligned<[i32; 16]>>() >= 64);
};

/// The valid mask Embree reads: -1 for an active lane, 0 for an inactive one.
fn valid_mask<R, const N: usize>(rays: &[Option<R>; N]) -> Aligned<[i32; N]> {
    Aligned(array::from_fn(|i| if rays[i].is_some() { -1 } else { 0 }))
}

/// Writes the active lanes' rays into an SoA ray packet; inactive lanes keep the defaults
/// (Embree does not read them).
macro_rules! fill_rays {
    ($packet:expr, $rays:expr) => {
        for (i, ray) in $rays.iter().enumerate() {
            let Some(r) = ray else { continue };
            let p = &mut $packet;
            let (o, d) = (r.origin(), r.direction());
            (p.org_x[i], p.org_y[i], p.org_z[i]) = (o.x, o.y, o.z);
            (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (d.x, d.y, d.z);
            (p.tnear[i], p.tfar[i]) = r.interval();
            p.time[i] = r.time();
            p.mask[i] = u32::MAX;
        }
    };
}

macro_rules! packet_queries {
    ($n:literal, $intersect:ident, $occluded:ident, $rayhit:ty, $ray:ty, $rtc_intersect:ident,
     $rtc_occluded:ident) => {
        impl SceneView<'_> {
            #[doc = concat!("Closest hits of a packet of ", $n, " rays (rtcIntersect", $n, "); `None` lanes")]
            /// are inactive and come back `None`. Lane `i` of the result is what
            /// [`SceneView::intersect1_at`] gives for `rays[i]`.
            pub fn $intersect<R: PacketRay>(
                &self,
                rays: &[Option<R>; $n],
                coherence: Coherence,
            ) -> [Option<EmbreeHit>; $n] {
                let valid = valid_mask(rays);
                let mut packet = Aligned(<$rayhit>::default());
                fill_rays!(packet.0.ray, rays);
                packet.0.hit.geomID = [sys::RTC_INVALID_GEOMETRY_ID; $n];
                packet.0.hit.instID =
                    [[sys::RTC_INVALID_GEOMETRY_ID; $n]; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize];
                let mut args = intersect_args(coherence.flags());
                let mut context = self.skip_context();
                if let Some(c) = context.as_mut() {
                    c.intersect_args(&mut args);
                }
                // SAFETY: the packet type is generated from the linked library's headers, so
                // the library writes within it; it and the mask are 64-byte aligned (`Aligned`),
                // beyond the required alignment for this width; the scene is committed and alive
                // for the borrow; `args` is initialised as rtcInitIntersectArguments does, and
                // its context, if any, lives until the call returns.
                unsafe { sys::$rtc_intersect(valid.0.as_ptr(), self.raw, &mut packet.0, &mut args) };
                let (r, h) = (&packet.0.ray, &packet.0.hit);
                array::from_fn(|i| {
                    (valid.0[i] != 0 && h.geomID[i] != sys::RTC_INVALID_GEOMETRY_ID).then(|| EmbreeHit {
                        t: r.tfar[i],
                        u: h.u[i],
                        v: h.v[i],
                        ng: [h.Ng_x[i], h.Ng_y[i], h.Ng_z[i]],
                        prim_id: h.primID[i],
                        geom_id: h.geomID[i],
                        inst_id: (h.instID[0][i] != sys::RTC_INVALID_GEOMETRY_ID).then_some(h.instID[0][i]),
                    })
                })
            }

            #[doc = concat!("Occlusion of a packet of ", $n, " rays (rtcOccluded", $n, "); `None` lanes")]
            /// are inactive and come back `false`. Lane `i` is what [`SceneView::occluded1_at`]
            /// gives for `rays[i]`.
            pub fn $occluded<R: PacketRay>(
                &self,
                rays: &[Option<R>; $n],
                coherence: Coherence,
            ) -> [bool; $n] {
                let valid = valid_mask(rays);
                let mut packet = Aligned(<$ray>::default());
                fill_rays!(packet.0, rays);
                let mut args = occluded_args(coherence.flags());
                let mut context = self.skip_context();
                if let Some(c) = context.as_mut() {
                    c.occluded_args(&mut args);
                }
                // SAFETY: as in the intersect query; rtcOccluded writes only `tfar` of active
                // lanes.
                unsafe { sys::$rtc_occluded(valid.0.as_ptr(), self.raw, &mut packet.0, &mut args) };
                array::from_fn(|i| valid.0[i] != 0 && packet.0.tfar[i] == f32::NEG_INFINITY)
            }
        }
    };
}

packet_queries!(4, intersect4, occluded4, sys::RTCRayHit4, sys::RTCRay4, rtcIntersect4, rtcOccluded4);
packet_queries!(8, intersect8, occluded8, sys::RTCRayHit8, sys::RTCRay8, rtcIntersect8, rtcOccluded8);
packet_queries!(16, intersect16, occluded16, sys::RTCRayHit16, sys::RTCRay16, rtcIntersect16, rtcOccluded16);
