//! The renderer's view of a committed scene: which mesh and material every accelerator
//! object is, and the shading data (normal, UV, textured material, emission) at a hit.

use std::sync::Arc;

use glam::{Mat3, Vec2, Vec3};

use super::emitters::{EmitterSample, Emitters};
use super::texture::sample;
use super::RenderError;
use crate::accel::{load_scene, Accelerator, Hit, HitObject};
use crate::geometry::{Ray, TriangleMesh};
use crate::scene::{Light, Material, SceneDescription, Sky, Sun, Texture};

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
    /// Punctual lights besides the sun.
    pub lights: Vec<Light>,
    meshes: Vec<TriangleMesh>,
    materials: Vec<Material>,
    textures: Vec<Arc<Texture>>,
    /// Emissive triangles, for light sampling.
    pub(crate) emitters: Emitters,
    statics: Vec<Option<ObjectRef>>,
    instances: Vec<Option<ObjectRef>>,
}

/// Shading data at a ray hit. Both normals face the side the ray came from.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    /// Texture coordinates (zero when the mesh has none).
    pub uv: Vec2,
    /// The triangle's material with its textures applied at `uv`.
    pub material: Material,
    /// Radiance the surface emits (towards either side).
    pub emission: Vec3,
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
        for (i, m) in desc.materials.iter().enumerate() {
            if let Some(t) = m.textures().find(|&t| t as usize >= desc.textures.len()) {
                return Err(bad(format!("material {i}: texture {t} does not exist")));
            }
        }
        // The object's material and, for meshes with per-triangle slots, the last slot.
        let material = |m: u32, mesh: &TriangleMesh, what: &dyn Fn() -> String| {
            let last = m as u64 + mesh.max_material_slot() as u64;
            if last < desc.materials.len() as u64 {
                Ok(m)
            } else {
                Err(bad(format!("{}: material {last} does not exist", what())))
            }
        };
        let loaded = load_scene(desc, accel)?;
        accel.commit()?;
        let mut scene = RenderScene {
            name: desc.name.clone(),
            camera: desc.camera,
            sun: desc.sun,
            sky: desc.sky,
            lights: desc.lights.clone(),
            meshes: Vec::with_capacity(desc.statics.len() + desc.prototypes.len()),
            materials: desc.materials.clone(),
            textures: desc.textures.clone(),
            emitters: Emitters::build(desc),
            statics: Vec::new(),
            instances: Vec::new(),
        };
        for (i, (s, id)) in desc.statics.iter().zip(&loaded.statics).enumerate() {
            let object = ObjectRef {
                mesh: scene.meshes.len() as u32,
                material: material(s.material, &s.mesh, &|| format!("static mesh {i}"))?,
                normal_matrix: Mat3::IDENTITY,
            };
            place(&mut scene.statics, id.0, object);
            scene.meshes.push(s.mesh.clone());
        }
        let first_prototype_mesh = scene.meshes.len() as u32;
        for p in &desc.prototypes {
            material(p.material, &p.mesh, &|| format!("prototype '{}'", p.name))?;
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

    /// Shading data for `hit` on `ray`. The hit resolves to an object (mesh, local primitive,
    /// normal matrix); normal, UV and material are then looked up from the mesh by that local
    /// primitive. Hits on objects the scene does not know (which a correct accelerator never
    /// reports) shade as a neutral grey facet.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let p = ray.at(hit.t);
        let ng = if hit.ng.dot(ray.dir) > 0.0 { -hit.ng } else { hit.ng };
        let Some(obj) = self.object(hit.object) else {
            debug_assert!(false, "hit on unknown object {:?}", hit.object);
            let material = Material::diffuse(Vec3::splat(0.5));
            return SurfaceHit { p, ng, ns: ng, uv: Vec2::ZERO, material, emission: Vec3::ZERO };
        };
        let mesh = &self.meshes[obj.mesh as usize];
        let prim = hit.prim as usize;
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
        let index = obj.material as usize + mesh.material_slot(prim) as usize;
        let mut material = *self.materials.get(index).unwrap_or(&self.materials[obj.material as usize]);
        let texture = |t: Option<u32>, srgb: bool| {
            t.and_then(|t| self.textures.get(t as usize)).map(|tex| sample(tex, uv, srgb))
        };
        if let Some(c) = texture(material.base_color_texture, true) {
            material.base_color *= c.truncate();
        }
        if let Some(mr) = texture(material.metallic_roughness_texture, false) {
            material.roughness *= mr.y;
            material.metallic *= mr.z;
        }
        let emission = self.emission(&material, uv);
        SurfaceHit { p, ng, ns, uv, material, emission }
    }

    /// Radiance emitted by `material` at `uv` (its emissive factor times its texture).
    fn emission(&self, material: &Material, uv: Vec2) -> Vec3 {
        let mut emission = material.emissive;
        if emission != Vec3::ZERO {
            if let Some(tex) = material.emissive_texture.and_then(|t| self.textures.get(t as usize)) {
                emission *= sample(tex, uv, true).truncate();
            }
        }
        emission
    }

    /// A point on an emissive triangle for light sampling (see [`Emitters`]), with the
    /// radiance it emits; `None` when the scene has no emitters.
    pub(crate) fn sample_emitter(&self, u_pick: f32, u: Vec2) -> Option<(EmitterSample, Vec3)> {
        let s = self.emitters.sample(u_pick, u)?;
        let material = self.materials.get(s.material as usize)?;
        Some((s, self.emission(material, s.uv)))
    }
}
