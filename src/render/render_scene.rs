use glam::Vec3;

use super::RenderError;
use crate::accel::{load_scene, Accelerator, Hit};
use crate::geometry::{Ray, TriangleMesh};
use crate::integrate::{LoadedObjectMap, MeshRef, ObjectMap, ResolvedHit};
use crate::scene::{Material, SceneDescription, Sky, Sun};

/// Where a scene's hit ids are resolved: a map built here, or the scene manager's.
enum Objects<'a> {
    Loaded(LoadedObjectMap),
    Mapped(&'a dyn ObjectMap),
}

/// The renderer's side of a scene: the description's meshes and materials, the camera and
/// lights, and how to resolve a hit to the mesh, triangle and transform to shade it with.
pub struct RenderScene<'a> {
    pub name: String,
    pub camera: crate::scene::Camera,
    pub sun: Sun,
    pub sky: Sky,
    desc: &'a SceneDescription,
    objects: Objects<'a>,
}

/// Shading data at a ray hit. Both normals face the side the ray came from.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub material: Material,
}

impl<'a> RenderScene<'a> {
    /// Loads `desc` into `accel` (see [`crate::accel::load_scene`]) with every body an
    /// instance, commits it, and maps the accelerator's ids back to `desc`.
    pub fn build(desc: &'a SceneDescription, accel: &mut dyn Accelerator) -> Result<Self, RenderError> {
        Self::check_materials(desc)?;
        let loaded = load_scene(desc, accel)?;
        accel.commit()?;
        Ok(Self::new(desc, Objects::Loaded(LoadedObjectMap::new(desc, &loaded))))
    }

    /// A scene whose accelerator someone else fills (the scene manager), resolving hits
    /// through `objects`. The bodies of `desc` are ignored.
    pub fn with_objects(desc: &'a SceneDescription, objects: &'a dyn ObjectMap) -> Result<Self, RenderError> {
        Self::check_materials(desc)?;
        Ok(Self::new(desc, Objects::Mapped(objects)))
    }

    fn new(desc: &'a SceneDescription, objects: Objects<'a>) -> Self {
        Self { name: desc.name.clone(), camera: desc.camera, sun: desc.sun, sky: desc.sky, desc, objects }
    }

    fn check_materials(desc: &SceneDescription) -> Result<(), RenderError> {
        let n = desc.materials.len();
        let bad = |what: String| Err(RenderError::Scene { scene: desc.name.clone(), what });
        for (i, s) in desc.statics.iter().enumerate() {
            if s.material as usize >= n {
                return bad(format!("static mesh {i}: material {} does not exist", s.material));
            }
        }
        for p in &desc.prototypes {
            if p.material as usize >= n {
                return bad(format!("prototype '{}': material {} does not exist", p.name, p.material));
            }
        }
        Ok(())
    }

    fn object(&self, hit: &Hit) -> Option<ResolvedHit> {
        match &self.objects {
            Objects::Loaded(map) => map.resolve(hit.object, hit.prim),
            Objects::Mapped(map) => map.resolve(hit.object, hit.prim),
        }
    }

    /// The mesh and material index a resolved hit refers to.
    fn mesh(&self, mesh: MeshRef) -> Option<(&TriangleMesh, u32)> {
        match mesh {
            MeshRef::Static(i) => self.desc.statics.get(i as usize).map(|s| (&s.mesh, s.material)),
            MeshRef::Prototype(i) => self.desc.prototypes.get(i as usize).map(|p| (&p.mesh, p.material)),
        }
    }

    /// Shading data for `hit` on `ray`. Hits on objects the scene does not know (which a
    /// correct accelerator never reports) shade as a neutral grey facet.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let p = ray.at(hit.t);
        let ng = if hit.ng.dot(ray.dir) > 0.0 { -hit.ng } else { hit.ng };
        let resolved = self.object(hit).and_then(|obj| self.mesh(obj.mesh).map(|m| (obj, m)));
        let Some((obj, (mesh, material))) = resolved else {
            debug_assert!(false, "hit on unknown object {:?}", hit.object);
            return SurfaceHit { p, ng, ns: ng, material: Material::diffuse(Vec3::splat(0.5)) };
        };
        let ns = mesh
            .normals
            .as_ref()
            .and_then(|normals| {
                let [a, b, c] = *mesh.indices.get(obj.prim as usize)?;
                let w = 1.0 - hit.u - hit.v;
                let n = w * normals[a as usize] + hit.u * normals[b as usize] + hit.v * normals[c as usize];
                let n = (obj.normal_matrix * n).normalize_or_zero();
                (n != Vec3::ZERO).then_some(if n.dot(ng) < 0.0 { -n } else { n })
            })
            .unwrap_or(ng);
        SurfaceHit { p, ng, ns, material: self.desc.materials[material as usize] }
    }
}
