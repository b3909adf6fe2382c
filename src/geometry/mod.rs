//! Plain geometric data shared by every domain: rays, bounding boxes, triangle meshes and
//! procedural primitives. No acceleration structures and no rendering state live here.

mod aabb;
mod mesh;
pub mod primitives;
mod ray;

pub use aabb::Aabb;
pub use mesh::{MeshError, TriangleMesh};
pub use ray::{offset_origin, Ray};
