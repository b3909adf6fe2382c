//! Hit to object mapping: what a hit on the accelerator's ids means in scene terms, so shading
//! is the same whether a body is an instance or baked into the static scene.

use glam::{Affine3A, Mat3, Vec3};

use crate::accel::{HitObject, InstanceId, LoadedScene};
use crate::geometry::{InstanceMotion, TriangleMesh};
use crate::physics::BodyId;
use crate::scene::SceneDescription;

/// The mesh a hit lies on, as the scene description names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum MeshRef {
    /// `SceneDescription::statics[i]` (the environment).
    Static(u32),
    /// `SceneDescription::prototypes[i]`, placed by a body's transform.
    Prototype(u32),
}

impl MeshRef {
    /// The mesh in `desc`, if `desc` has it.
    pub(crate) fn mesh(self, desc: &SceneDescription) -> Option<&TriangleMesh> {
        match self {
            MeshRef::Static(i) => desc.statics.get(i as usize).map(|s| &s.mesh),
            MeshRef::Prototype(i) => desc.prototypes.get(i as usize).map(|p| &p.mesh),
        }
    }
}

/// A hit's triangle exactly as the accelerator was given it: what the cross-check
/// re-intersects in f64 (`crosscheck`, docs/crosscheck.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitTriangle {
    /// In the space the accelerator holds them: object space for instances, world space for
    /// static geometry (the environment and baked islands).
    pub vertices: [Vec3; 3],
    /// The f32 object-to-world transform the accelerator was given (instances); `None` when
    /// the vertices are in world space.
    pub transform: Option<Affine3A>,
}

/// A hit resolved to its scene object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedHit {
    pub mesh: MeshRef,
    /// Triangle index within that mesh.
    pub prim: u32,
    /// The body, for hits on bodies (instanced or baked).
    pub body: Option<BodyId>,
    /// Object-to-world transform for normals (identity for static meshes).
    pub(crate) normal_matrix: Mat3,
    /// Whether the hit was on an integrated body (baked, or in the resting scene): the debug
    /// view colours it.
    pub integrated: bool,
}

/// Resolves the accelerator's hit ids to scene objects.
pub trait ObjectMap: Sync {
    /// `None` for ids the map does not know (a correct accelerator never reports them).
    fn resolve(&self, object: HitObject, prim: u32) -> Option<ResolvedHit>;

    /// The triangle a hit is on as the accelerator holds it, given `desc`, the description
    /// the scene shows (meshes named by [`MeshRef`]), for a ray of shutter time `time` (an
    /// instance moving over the shutter is placed at it). `None` as for [`ObjectMap::resolve`].
    fn hit_triangle(
        &self,
        desc: &SceneDescription,
        object: HitObject,
        prim: u32,
        time: f32,
    ) -> Option<HitTriangle>;
}

/// Triangle `prim` of `mesh`, if it has one.
pub(crate) fn mesh_triangle(mesh: &TriangleMesh, prim: u32) -> Option<[Vec3; 3]> {
    ((prim as usize) < mesh.triangle_count()).then(|| mesh.triangle(prim as usize))
}

/// The normal matrix of an object-to-world transform.
pub(crate) fn normal_matrix(transform: &Affine3A) -> Mat3 {
    Mat3::from(transform.matrix3).inverse().transpose()
}

/// The map of a description loaded by [`crate::accel::load_scene`]: every body an instance.
#[derive(Clone, Debug, Default)]
pub struct LoadedObjectMap {
    statics: Vec<Option<u32>>,
    instances: Vec<Option<LoadedInstance>>,
}

#[derive(Clone, Copy, Debug)]
struct LoadedInstance {
    prototype: u32,
    body: BodyId,
    normal_matrix: Mat3,
    transform: Affine3A,
    /// Its motion over the shutter, when the accelerator was given one
    /// ([`LoadedObjectMap::set_motion`]).
    motion: Option<InstanceMotion>,
}

fn place<T>(v: &mut Vec<Option<T>>, index: u32, value: T) {
    let i = index as usize;
    if v.len() <= i {
        v.resize_with(i + 1, || None);
    }
    v[i] = Some(value);
}

impl LoadedObjectMap {
    /// Body `i` of `desc` is `BodyId(i)`.
    pub fn new(desc: &SceneDescription, loaded: &LoadedScene) -> Self {
        let ids: Vec<BodyId> = (0..desc.bodies.len() as u32).map(BodyId).collect();
        Self::with_body_ids(desc, loaded, &ids)
    }

    /// Body `i` of `desc` is `body_ids[i]` (a frame description lists only present bodies).
    pub fn with_body_ids(desc: &SceneDescription, loaded: &LoadedScene, body_ids: &[BodyId]) -> Self {
        debug_assert_eq!(desc.bodies.len(), body_ids.len());
        let mut map = Self::default();
        for (i, id) in loaded.statics.iter().enumerate() {
            place(&mut map.statics, id.0, i as u32);
        }
        for ((body, id), b) in desc.bodies.iter().zip(&loaded.instances).zip(body_ids) {
            let instance = LoadedInstance {
                prototype: body.prototype,
                body: *b,
                normal_matrix: normal_matrix(&body.transform),
                transform: body.transform,
                motion: None,
            };
            place(&mut map.instances, id.0, instance);
        }
        map
    }

    /// Records that `instance` moves with `motion` over the shutter (as the accelerator was
    /// told by [`crate::accel::Accelerator::set_instance_motion`]).
    pub fn set_motion(&mut self, instance: InstanceId, motion: Option<InstanceMotion>) {
        if let Some(Some(i)) = self.instances.get_mut(instance.0 as usize) {
            i.motion = motion;
        }
    }
}

impl ObjectMap for LoadedObjectMap {
    fn resolve(&self, object: HitObject, prim: u32) -> Option<ResolvedHit> {
        match object {
            HitObject::Static(id) => {
                self.statics.get(id.0 as usize).copied().flatten().map(|i| ResolvedHit {
                    mesh: MeshRef::Static(i),
                    prim,
                    body: None,
                    normal_matrix: Mat3::IDENTITY,
                    integrated: false,
                })
            }
            HitObject::Instance(id) => {
                self.instances.get(id.0 as usize).copied().flatten().map(|i| ResolvedHit {
                    mesh: MeshRef::Prototype(i.prototype),
                    prim,
                    body: Some(i.body),
                    normal_matrix: i.normal_matrix,
                    integrated: false,
                })
            }
        }
    }

    fn hit_triangle(
        &self,
        desc: &SceneDescription,
        object: HitObject,
        prim: u32,
        time: f32,
    ) -> Option<HitTriangle> {
        let transform = match object {
            HitObject::Static(_) => None,
            HitObject::Instance(id) => {
                let i = self.instances.get(id.0 as usize).copied().flatten()?;
                Some(i.motion.map_or(i.transform, |m| m.at(time).to_affine()))
            }
        };
        let resolved = self.resolve(object, prim)?;
        let vertices = mesh_triangle(resolved.mesh.mesh(desc)?, resolved.prim)?;
        Some(HitTriangle { vertices, transform })
    }
}
