//! [`FrozenScene`]: a committed Embree scene that can no longer change, shared by the
//! instances that place it (a prototype). It holds the scene it was frozen from only as an
//! owner to keep alive, so instances (single or arrays) depend on this file and not on the
//! mutable [`super::Scene`].

use std::any::Any;

use embree4_sys as sys;

use super::view::SceneView;

/// A committed scene that can no longer change: a prototype shared by instances.
pub struct FrozenScene {
    /// The committed scene's handle, valid while `owner` lives.
    raw: sys::RTCScene,
    /// An upper bound on the distance of the scene's points from its origin (the farthest
    /// corner of its bounds): how far a turn moves them ([`super::motion::lerps_as_matrices`]).
    radius: f32,
    /// The [`super::Scene`] frozen, which holds the Embree reference to `raw` and its
    /// geometries' buffers; never changed again.
    _owner: Box<dyn Any + Send + Sync>,
}

// SAFETY: `raw` is only read (ray queries on a committed scene, which Embree allows from many
// threads at once, rtcIntersect1(3)); the owner that keeps it alive is `Send + Sync`.
unsafe impl Send for FrozenScene {}
// SAFETY: see `Send`.
unsafe impl Sync for FrozenScene {}

impl FrozenScene {
    /// `raw`, committed, kept alive by `owner`, with its points within `radius` of its origin.
    pub(super) fn new(raw: sys::RTCScene, radius: f32, owner: Box<dyn Any + Send + Sync>) -> Self {
        Self { raw, radius, _owner: owner }
    }

    /// An upper bound on the distance of the scene's points from its origin: how far a turn of
    /// an instance of it moves them.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    pub(super) fn raw(&self) -> sys::RTCScene {
        self.raw
    }

    pub fn view(&self) -> SceneView<'_> {
        SceneView::new(self.raw)
    }
}
