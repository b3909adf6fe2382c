//! Plain geometric data shared by every domain: rays, bounding boxes, triangle meshes,
//! procedural primitives and rigid motion over a shutter. No acceleration structures and no
//! rendering state live here.

mod aabb;
mod mesh;
mod motion;
pub mod primitives;
mod ray;

pub use aabb::Aabb;
pub(crate) use mesh::NormalTurn;
pub use mesh::{MeshError, TriangleMesh};
pub use motion::{InstanceMotion, RigidTransform};
pub use ray::{offset_origin, Ray};
