//! [`Hit`]: a ray-triangle intersection as every backend reports it.

use glam::Vec3;

use super::{InstanceId, StaticId};

/// What a ray hit: a static mesh or an instance (whose prototype the caller knows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HitObject {
    Static(StaticId),
    Instance(InstanceId),
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
