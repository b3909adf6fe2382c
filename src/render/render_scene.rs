use glam::{Mat3, Vec3};

use super::RenderError;
use crate::accel::{load_scene, Accelerator, Hit, HitObject};
use crate::geometry::{Ray, TriangleMesh};
use crate::scene::{Material, SceneDescription, Sky, Sun};

#[derive(Clone, Copy, Debug)]
struct ObjectRef {
    mesh: u32,
    material: u32,
    /// Object-to-world transform for normals (identity for static meshes).
    normal_matrix: Mat3,
}

/// The renderer's side of a scene: for every object the accelerator holds, the mesh and
/// material to shade it with, plus camera and lights.
pub struct RenderScene {
    pub name: String,
    pub camera: crate::scene::Camera,
    pub sun: Sun,
    pub sky: Sky,
    meshes: Vec<TriangleMesh>,
    materials: Vec<Material>,
    statics: Vec<Option<ObjectRef>>,
    instances: Vec<Option<ObjectRef>>,
}

/// Shading data at a ray hit. Both normals face the side the ray came from.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub material: Material,
}

fn place<T>(v: &mut Vec<Option<T>>, index: u32, value: T) {
    let i = index as usize;
    if v.len() <= i {
        v.resize_with(i + 1, || None);
    }
    v[i] = Some(value);
}

impl RenderScene {
    /// Loads `desc` into `accel` (see [`crate::accel::load_scene`]), commits it, and records
    /// how to shade every object it holds.
    pub fn build(desc: &SceneDescription, accel: &mut dyn Accelerator) -> Result<Self, RenderError> {
        let bad = |what: String| RenderError::Scene { scene: desc.name.clone(), what };
        let material = |m: u32, what: &dyn Fn() -> String| {
            if (m as usize) < desc.materials.len() {
                Ok(m)
            } else {
                Err(bad(format!("{}: material {m} does not exist", what())))
            }
        };
        let loaded = load_scene(desc, accel)?;
        accel.commit()?;
        let mut scene = RenderScene {
            name: desc.name.clone(),
            camera: desc.camera,
            sun: desc.sun,
            sky: desc.sky,
            meshes: Vec::with_capacity(desc.statics.len() + desc.prototypes.len()),
            materials: desc.materials.clone(),
            statics: Vec::new(),
            instances: Vec::new(),
        };
        for (i, (s, id)) in desc.statics.iter().zip(&loaded.statics).enumerate() {
            let object = ObjectRef {
                mesh: scene.meshes.len() as u32,
                material: material(s.material, &|| format!("static mesh {i}"))?,
                normal_matrix: Mat3::IDENTITY,
            };
            place(&mut scene.statics, id.0, object);
            scene.meshes.push(s.mesh.clone());
        }
        let first_prototype_mesh = scene.meshes.len() as u32;
        for p in &desc.prototypes {
            material(p.material, &|| format!("prototype '{}'", p.name))?;
            scene.meshes.push(p.mesh.clone());
        }
        for (b, id) in desc.bodies.iter().zip(&loaded.instances) {
            let object = ObjectRef {
                mesh: first_prototype_mesh + b.prototype,
                material: desc.prototypes[b.prototype as usize].material,
                normal_matrix: Mat3::from(b.transform.matrix3).inverse().transpose(),
            };
            place(&mut scene.instances, id.0, object);
        }
        Ok(scene)
    }

    fn object(&self, object: HitObject) -> Option<&ObjectRef> {
        match object {
            HitObject::Static(id) => self.statics.get(id.0 as usize),
            HitObject::Instance(id) => self.instances.get(id.0 as usize),
        }
        .and_then(Option::as_ref)
    }

    /// Shading data for `hit` on `ray`. Hits on objects the scene does not know (which a
    /// correct accelerator never reports) shade as a neutral grey facet.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let p = ray.at(hit.t);
        let ng = if hit.ng.dot(ray.dir) > 0.0 { -hit.ng } else { hit.ng };
        let Some(obj) = self.object(hit.object) else {
            debug_assert!(false, "hit on unknown object {:?}", hit.object);
            return SurfaceHit { p, ng, ns: ng, material: Material::diffuse(Vec3::splat(0.5)) };
        };
        let mesh = &self.meshes[obj.mesh as usize];
        let ns = mesh
            .normals
            .as_ref()
            .and_then(|normals| {
                let [a, b, c] = *mesh.indices.get(hit.prim as usize)?;
                let w = 1.0 - hit.u - hit.v;
                let n = w * normals[a as usize] + hit.u * normals[b as usize] + hit.v * normals[c as usize];
                let n = (obj.normal_matrix * n).normalize_or_zero();
                (n != Vec3::ZERO).then_some(if n.dot(ng) < 0.0 { -n } else { n })
            })
            .unwrap_or(ng);
        SurfaceHit { p, ng, ns, material: self.materials[obj.material as usize] }
    }
}
