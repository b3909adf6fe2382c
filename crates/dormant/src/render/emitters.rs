//! Emissive triangles as area lights: every world-space triangle whose material emits, chosen
//! in proportion to its area times its emitted luminance (the material's emissive factor),
//! then a uniform point on it. With that choice the area pdf of a point depends only on its
//! material's emissive factor, so a path that hits an emitter can weigh it against light
//! sampling (MIS) from the shading data alone, whatever object the hit resolved to.

use glam::{Affine3A, Vec2, Vec3};

use super::bsdf::luminance;
use crate::geometry::TriangleMesh;
use crate::scene::{Body, SceneDescription};

#[derive(Clone, Copy, Debug)]
struct EmissiveTriangle {
    p: [Vec3; 3],
    uv: [Vec2; 3],
    /// Index into the scene's materials.
    material: u32,
    /// The material's emitted luminance.
    luminance: f32,
}

/// A point chosen on an emitter.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EmitterSample {
    pub p: Vec3,
    /// Unit geometric normal (emitters shine from both sides).
    pub n: Vec3,
    pub uv: Vec2,
    pub material: u32,
    /// Probability density per unit area of having chosen `p`.
    pub(crate) pdf_area: f32,
}

/// The scene's emissive triangles with a cumulative distribution over their power.
#[derive(Clone, Debug, Default)]
pub(crate) struct Emitters {
    triangles: Vec<EmissiveTriangle>,
    /// Running sums of area times luminance, ending at `total`.
    cdf: Vec<f32>,
    total: f32,
}

/// Emitted luminance of material `m` of `desc`, 0 for a material that does not exist.
fn power(desc: &SceneDescription, m: u32) -> f32 {
    desc.materials.get(m as usize).map_or(0.0, |m| luminance(m.emissive).max(0.0))
}

impl Emitters {
    /// The emissive triangles of `desc`'s static meshes and of `bodies` (placed prototypes).
    pub(crate) fn build(desc: &SceneDescription, bodies: &[Body]) -> Self {
        let mut e = Emitters::default();
        let mut add = |mesh: &TriangleMesh, material: u32, xf: &Affine3A, prims: &[usize]| {
            for &i in prims {
                let m = material + mesh.material_slot(i);
                let [a, b, c] = mesh.indices[i];
                let p = [a, b, c].map(|v| xf.transform_point3(mesh.positions[v as usize]));
                let uv = mesh.uvs.as_ref().map_or([Vec2::ZERO; 3], |uvs| [a, b, c].map(|v| uvs[v as usize]));
                let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
                let luminance = power(desc, m);
                let weight = area * luminance;
                if weight > 0.0 && weight.is_finite() {
                    e.total += weight;
                    e.cdf.push(e.total);
                    e.triangles.push(EmissiveTriangle { p, uv, material: m, luminance });
                }
            }
        };
        let emissive = |mesh: &TriangleMesh, material: u32| -> Vec<usize> {
            (0..mesh.triangle_count())
                .filter(|&i| power(desc, material + mesh.material_slot(i)) > 0.0 && mesh.triangle_is_valid(i))
                .collect()
        };
        for s in &desc.statics {
            add(&s.mesh, s.material, &Affine3A::IDENTITY, &emissive(&s.mesh, s.material));
        }
        let per_prototype: Vec<Vec<usize>> =
            desc.prototypes.iter().map(|p| emissive(&p.mesh, p.material)).collect();
        for b in bodies {
            let (Some(proto), Some(prims)) =
                (desc.prototypes.get(b.prototype as usize), per_prototype.get(b.prototype as usize))
            else {
                continue;
            };
            if !prims.is_empty() {
                add(&proto.mesh, proto.material, &b.transform, prims);
            }
        }
        e
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Whether any prototype of `desc` has an emissive triangle (so its bodies' positions
    /// matter for light sampling).
    pub(crate) fn prototypes_emit(desc: &SceneDescription) -> bool {
        Self::emissive_prototypes(desc).into_iter().any(|e| e)
    }

    /// Per prototype of `desc`, whether it has an emissive triangle.
    pub(crate) fn emissive_prototypes(desc: &SceneDescription) -> Vec<bool> {
        desc.prototypes
            .iter()
            .map(|p| {
                (0..p.mesh.triangle_count()).any(|i| power(desc, p.material + p.mesh.material_slot(i)) > 0.0)
            })
            .collect()
    }

    /// Area density with which [`Self::sample`] picks a given point on a surface whose
    /// material has emissive factor `emissive`.
    pub(crate) fn pdf_area(&self, emissive: Vec3) -> f32 {
        if self.total > 0.0 {
            luminance(emissive).max(0.0) / self.total
        } else {
            0.0
        }
    }

    /// Picks a triangle with `u_pick` and a uniform point on it with `u`.
    pub(crate) fn sample(&self, u_pick: f32, u: Vec2) -> Option<EmitterSample> {
        let target = u_pick * self.total;
        let i = self.cdf.partition_point(|&c| c <= target).min(self.triangles.len().checked_sub(1)?);
        let t = &self.triangles[i];
        let su = u.x.sqrt();
        let (b0, b1) = (1.0 - su, u.y * su);
        let b2 = 1.0 - b0 - b1;
        let p = b0 * t.p[0] + b1 * t.p[1] + b2 * t.p[2];
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
        (n != Vec3::ZERO).then(|| EmitterSample {
            p,
            n,
            uv: b0 * t.uv[0] + b1 * t.uv[1] + b2 * t.uv[2],
            material: t.material,
            // The triangle's share of the power over its area: its luminance over the total.
            pdf_area: t.luminance / self.total,
        })
    }
}
