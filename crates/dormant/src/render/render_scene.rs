//! The renderer's view of a committed scene: how a hit resolves to a mesh, triangle and
//! transform (through an [`ObjectMap`]), and the shading data there (normal, UV, textured
//! material, emission).

use glam::{Vec2, Vec3};

use super::emitters::{EmitterSample, Emitters};
use super::texture_sampling::sample;
use super::RenderError;
use crate::accel::{load_scene, Accelerator, Hit, HitObject, InstanceId};
use crate::accel::{LoadedObjectMap, MeshRef, ObjectMap, ResolvedHit};
use crate::geometry::{Ray, TriangleMesh};
use crate::scene::{Body, Light, Material, SceneDescription, Sky, Sun};

/// Where a scene's hit ids are resolved: a map built here, or the scene manager's.
enum Objects<'a> {
    Loaded(LoadedObjectMap),
    Mapped(&'a dyn ObjectMap),
}

/// The renderer's side of a scene: the description's meshes, materials and textures, the
/// camera and lights, and how to resolve a hit to the mesh, triangle and transform to shade
/// it with.
pub struct RenderScene<'a> {
    pub(crate) camera: crate::scene::Camera,
    /// Motion blur: the camera at shutter close, `camera` being the one at open. Each camera
    /// sample then gets a time in the shutter, which its rays keep. `None`: no blur; every ray
    /// is at the frame's instant.
    pub(crate) camera_close: Option<crate::scene::Camera>,
    pub(crate) sun: Sun,
    pub(crate) sky: Sky,
    /// Punctual lights besides the sun.
    pub(crate) lights: Vec<Light>,
    /// Emissive triangles, for light sampling.
    pub(crate) emitters: Emitters,
    desc: &'a SceneDescription,
    objects: Objects<'a>,
}

/// Shading data at a ray hit. Both normals face the side the ray came from.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfaceHit {
    pub p: Vec3,
    pub ng: Vec3,
    pub(crate) ns: Vec3,
    /// The triangle's material with its textures applied at the hit's texture coordinates.
    pub material: Material,
    /// Radiance the surface emits (towards either side).
    pub(crate) emission: Vec3,
    /// What was hit, for the debug view: the environment, an instanced body or a baked one.
    pub kind: SurfaceKind,
}

/// The kind of object a hit is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SurfaceKind {
    Environment,
    Instanced,
    Baked,
}

impl<'a> RenderScene<'a> {
    /// Loads `desc` into `accel` (see [`crate::accel::load_scene`]) with every body an
    /// instance, commits it, and maps the accelerator's ids back to `desc`.
    pub fn build(desc: &'a SceneDescription, accel: &mut dyn Accelerator) -> Result<Self, RenderError> {
        Self::check(desc)?;
        let loaded = load_scene(desc, accel)?;
        accel.commit()?;
        let emitters = Emitters::build(desc, &desc.bodies);
        Ok(Self::new(desc, Objects::Loaded(LoadedObjectMap::new(desc, &loaded)), emitters))
    }

    /// A scene whose accelerator someone else fills (the scene manager), resolving hits
    /// through `objects`. The bodies of `desc` are ignored; `bodies` (every body present in
    /// the frame, instanced or baked) place emissive prototypes for light sampling.
    pub(crate) fn with_objects(
        desc: &'a SceneDescription,
        objects: &'a dyn ObjectMap,
        bodies: &[Body],
    ) -> Result<Self, RenderError> {
        Self::check(desc)?;
        Ok(Self::new(desc, Objects::Mapped(objects), Emitters::build(desc, bodies)))
    }

    fn new(desc: &'a SceneDescription, objects: Objects<'a>, emitters: Emitters) -> Self {
        Self {
            camera: desc.camera,
            camera_close: None,
            sun: desc.sun,
            sky: desc.sky,
            lights: desc.lights.clone(),
            emitters,
            desc,
            objects,
        }
    }

    /// Every texture and material a mesh can refer to exists.
    fn check(desc: &SceneDescription) -> Result<(), RenderError> {
        let bad = |what: String| Err(RenderError::Scene { scene: desc.name.clone(), what });
        for (i, m) in desc.materials.iter().enumerate() {
            if let Some(t) = m.textures().find(|&t| t as usize >= desc.textures.len()) {
                return bad(format!("material {i}: texture {t} does not exist"));
            }
        }
        // The object's material and, for meshes with per-triangle slots, the last slot.
        let last = |m: u32, mesh: &TriangleMesh| m as u64 + mesh.max_material_slot() as u64;
        let n = desc.materials.len() as u64;
        for (i, s) in desc.statics.iter().enumerate() {
            if last(s.material, &s.mesh) >= n {
                return bad(format!(
                    "static mesh {i}: material {} does not exist",
                    last(s.material, &s.mesh)
                ));
            }
        }
        for p in &desc.prototypes {
            if last(p.material, &p.mesh) >= n {
                return bad(format!(
                    "prototype '{}': material {} does not exist",
                    p.name,
                    last(p.material, &p.mesh)
                ));
            }
        }
        Ok(())
    }

    /// The body a hit lies on (instanced, resting or baked), if it is on one.
    pub(crate) fn body_of(&self, hit: &Hit) -> Option<u32> {
        self.object(hit.object, hit.prim)?.body.map(|b| b.0)
    }

    /// The body instance `id` places, if it places one.
    pub(crate) fn body_of_instance(&self, id: InstanceId) -> Option<u32> {
        self.object(HitObject::Instance(id), 0)?.body.map(|b| b.0)
    }

    /// What primitive `prim` of `object` is: its mesh, local primitive and body.
    fn object(&self, object: HitObject, prim: u32) -> Option<ResolvedHit> {
        match &self.objects {
            Objects::Loaded(map) => map.resolve(object, prim),
            Objects::Mapped(map) => map.resolve(object, prim),
        }
    }

    /// The mesh and material index a resolved hit refers to.
    fn mesh(&self, mesh: MeshRef) -> Option<(&TriangleMesh, u32)> {
        match mesh {
            MeshRef::Static(i) => self.desc.statics.get(i as usize).map(|s| (&s.mesh, s.material)),
            MeshRef::Prototype(i) => self.desc.prototypes.get(i as usize).map(|p| (&p.mesh, p.material)),
        }
    }

    /// Shading data for `hit` on `ray`. The hit resolves to an object (mesh, local primitive,
    /// normal matrix); normal, UV and material are then looked up from the mesh by that local
    /// primitive. Hits on objects the scene does not know (which a correct accelerator never
    /// reports) shade as a neutral grey facet.
    pub(crate) fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let p = ray.at(hit.t);
        let ng = if hit.ng.dot(ray.dir) > 0.0 { -hit.ng } else { hit.ng };
        let resolved =
            self.object(hit.object, hit.prim).and_then(|obj| self.mesh(obj.mesh).map(|m| (obj, m)));
        let Some((obj, (mesh, material))) = resolved else {
            debug_assert!(false, "hit on unknown object {:?}", hit.object);
            let material = Material::diffuse(Vec3::splat(0.5));
            let (emission, kind) = (Vec3::ZERO, SurfaceKind::Environment);
            return SurfaceHit { p, ng, ns: ng, material, emission, kind };
        };
        let prim = obj.prim as usize;
        let tri = mesh.indices.get(prim).copied();
        debug_assert!(tri.is_some(), "primitive {prim} outside its mesh");
        let (w, u, v) = (1.0 - hit.u - hit.v, hit.u, hit.v);
        let ns = mesh
            .normals
            .as_ref()
            .zip(tri)
            .and_then(|(normals, [a, b, c])| {
                let n = w * normals[a as usize] + u * normals[b as usize] + v * normals[c as usize];
                let n = (obj.normal_matrix * n).normalize_or_zero();
                (n != Vec3::ZERO).then_some(if n.dot(ng) < 0.0 { -n } else { n })
            })
            .unwrap_or(ng);
        let uv = mesh.uvs.as_ref().zip(tri).map_or(Vec2::ZERO, |(uvs, [a, b, c])| {
            w * uvs[a as usize] + u * uvs[b as usize] + v * uvs[c as usize]
        });
        // Per-triangle material slot on top of the object's material; build() checked the
        // range, the fallback only guards against a mesh changed since.
        let index = material as usize + mesh.material_slot(prim) as usize;
        let mut material = *self.desc.materials.get(index).unwrap_or(&self.desc.materials[material as usize]);
        let texture = |t: Option<u32>, srgb: bool| {
            t.and_then(|t| self.desc.textures.get(t as usize)).map(|tex| sample(tex, uv, srgb))
        };
        if let Some(c) = texture(material.base_color_texture, true) {
            material.base_color *= c.truncate();
        }
        if let Some(mr) = texture(material.metallic_roughness_texture, false) {
            material.roughness *= mr.y;
            material.metallic *= mr.z;
        }
        let emission = self.emission(&material, uv);
        let kind = match (obj.body, obj.integrated) {
            (None, _) => SurfaceKind::Environment,
            (Some(_), false) => SurfaceKind::Instanced,
            (Some(_), true) => SurfaceKind::Baked,
        };
        SurfaceHit { p, ng, ns, material, emission, kind }
    }

    /// Radiance emitted by `material` at `uv` (its emissive factor times its texture).
    fn emission(&self, material: &Material, uv: Vec2) -> Vec3 {
        let mut emission = material.emissive;
        if emission != Vec3::ZERO {
            if let Some(tex) = material.emissive_texture.and_then(|t| self.desc.textures.get(t as usize)) {
                emission *= sample(tex, uv, true).truncate();
            }
        }
        emission
    }

    /// A point on an emissive triangle for light sampling (see [`Emitters`]), with the
    /// radiance it emits; `None` when the scene has no emitters.
    pub(crate) fn sample_emitter(&self, u_pick: f32, u: Vec2) -> Option<(EmitterSample, Vec3)> {
        let s = self.emitters.sample(u_pick, u)?;
        let material = self.desc.materials.get(s.material as usize)?;
        Some((s, self.emission(material, s.uv)))
    }
}
