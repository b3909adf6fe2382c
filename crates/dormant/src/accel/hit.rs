//! [`Hit`]: a ray-triangle intersection as every backend reports it, and [`Occluder`]: what
//! blocks an occlusion ray.

use glam::Vec3;

use super::{InstanceId, StaticId};

/// What a ray hit: a static mesh or an instance (whose prototype the caller knows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HitObject {
    Static(StaticId),
    Instance(InstanceId),
}

/// What blocks an occlusion ray ([`super::SceneQuery::occluder`]): the object of one hit on
/// it, any, not necessarily the nearest. Exact temporal reuse reads it: the ray stays blocked,
/// whatever else moves along it, for as long as that object stays where it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Occluder {
    /// Static geometry: the environment or a baked island.
    Static,
    Instance(InstanceId),
    /// Something, not said what (a backend that only answers whether).
    Unknown,
}

/// A ray-triangle intersection, the same for every backend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of the ray's direction.
    pub t: f32,
    /// Barycentric coordinates: the hit point is `(1-u-v)*p0 + u*p1 + v*p2`.
    pub u: f32,
    pub v: f32,
    /// Unit geometric normal in world space, `(p1-p0) x (p2-p0)` transformed and normalised.
    pub ng: Vec3,
    pub object: HitObject,
    /// Triangle index within the mesh that was hit.
    pub prim: u32,
}
