//! The metallic-roughness BSDF (glTF's model, layered as Blender's Principled BSDF): a
//! Lambertian diffuse base under a dielectric GGX specular layer (exact Fresnel at IOR 1.5,
//! scaled by `specular`), and GGX with Schlick Fresnel for metals, with height-correlated Smith
//! shadowing. The base is weighted by one minus the layer's lobe-averaged reflectance
//! ([`fresnel`]). Directions are in world space; both point away from the surface.

mod fresnel;
mod lobe_table;

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2};

use glam::{Vec2, Vec3};

use crate::scene::Material;

/// `(sin, cos)` of the angle `2 pi turn`, for `turn` in `[0, 1]` (sample points): the nearest
/// quarter turn exactly, then Cephes' `sinf`/`cosf` minimax polynomials on the rest, at most
/// `pi / 4`, with no branch. Within 2e-7 of the exact values (the unit test
/// `sincos_turn_is_within_its_bound` checks a dense grid); it replaced libm's `sincosf`,
/// whose range reduction handles any angle and showed in a path-traced frame's profile:
/// docs/lab/rendering.md#2026-12-02-shading-cut-last-bit-changes-allowed
pub(crate) fn sincos_turn(turn: f32) -> (f32, f32) {
    debug_assert!((0.0..=1.0).contains(&turn), "turn {turn}");
    let quarters = 4.0 * turn;
    // Round to nearest (turn >= 0); an integer conversion, since x86-64's baseline has no
    // rounding instruction.
    let q = (quarters + 0.5) as i32;
    let x = (quarters - q as f32) * FRAC_PI_2;
    let x2 = x * x;
    let s = x + x * x2 * (-1.666_665_5e-1 + x2 * (8.332_161e-3 + x2 * -1.951_529_6e-4));
    let c = 1.0 - 0.5 * x2 + x2 * x2 * (4.166_664_6e-2 + x2 * (-1.388_731_6e-3 + x2 * 2.443_315_7e-5));
    // Angle q pi/2 + x: odd quarters swap sine and cosine, then signs follow the quadrant.
    let (s, c) = if q & 1 == 0 { (s, c) } else { (c, s) };
    let sign = |v: f32, negative: i32| f32::from_bits(v.to_bits() ^ (((negative & 2) as u32) << 30));
    (sign(s, q), sign(c, q + 1))
}

/// An orthonormal basis around unit `n` (Duff et al. 2017).
pub(crate) fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// A unit axis with its [`basis`], built once where several directions are sampled around the
/// same axis (a vertex's shading normal for the sky and the next bounce, the sun's direction
/// for a whole frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    t: Vec3,
    b: Vec3,
    pub n: Vec3,
}

impl Frame {
    pub(crate) fn new(n: Vec3) -> Self {
        let (t, b) = basis(n);
        Self { t, b, n }
    }

    /// The direction `turn` of a full turn around the axis, with sine `sin` and cosine `cos`
    /// to it.
    fn around(&self, sin: f32, cos: f32, turn: f32) -> Vec3 {
        let (sin_phi, cos_phi) = sincos_turn(turn);
        self.t * (sin * cos_phi) + self.b * (sin * sin_phi) + self.n * cos
    }

    /// Cosine-weighted direction in the hemisphere around the axis; pdf `cos / pi`. Unit to
    /// within 1e-6 without normalising (an orthonormal basis and `sin^2 + cos^2 = 1` to within
    /// [`sincos_turn`]'s error; `sampled_directions_are_unit` checks it).
    pub(crate) fn cosine(&self, u: Vec2) -> Vec3 {
        self.around(u.x.sqrt(), (1.0 - u.x).max(0.0).sqrt(), u.y)
    }

    /// A GGX microfacet normal of `alpha^2 = a2` around the axis, distributed as `D(h) cos(h)`.
    fn ggx_half_vector(&self, a2: f32, u: Vec2) -> Vec3 {
        let cos_h = ((1.0 - u.x) / (1.0 + (a2 - 1.0) * u.x)).max(0.0).sqrt();
        let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
        self.around(sin_h, cos_h, u.y)
    }

    /// Uniform direction within the cone of half-angle `acos(cos_max)` around the axis; unit
    /// to within 1e-6, as [`Self::cosine`].
    pub(crate) fn cone(&self, cos_max: f32, u: Vec2) -> Vec3 {
        let cos = 1.0 - u.x * (1.0 - cos_max);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        self.around(sin, cos, u.y)
    }
}

/// Cosine-weighted direction in the hemisphere around `n`; pdf `cos / pi`.
pub fn sample_cosine(n: Vec3, u: Vec2) -> Vec3 {
    Frame::new(n).cosine(u)
}

/// Uniform direction within the cone of half-angle `acos(cos_max)` around `axis`.
pub fn sample_cone(axis: Vec3, cos_max: f32, u: Vec2) -> Vec3 {
    Frame::new(axis).cone(cos_max, u)
}

/// A sampled incident direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BsdfSample {
    pub(crate) wi: Vec3,
    /// `f * |cos| / pdf`: what the path throughput is multiplied by.
    pub weight: Vec3,
    pub(crate) pdf: f32,
}

/// The BSDF at one surface point, seen from one outgoing direction `wo` (a path vertex
/// evaluates it for several incident directions: sun, sky, emitter and the next bounce).
/// Holds what every evaluation shares, with the constant factors folded in once (`1 / pi` as
/// a multiplication: the results differ from dividing by `pi` at the last bit).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bsdf {
    /// The shading normal and its basis.
    frame: Frame,
    wo: Vec3,
    /// `n . wo`, and Smith's `lambda` of it: the same for every incident direction.
    cos_o: f32,
    lambda_o: f32,
    /// The diffuse lobe's albedo over `pi`, weighted by what the specular layer leaves it.
    diffuse_over_pi: Vec3,
    /// The specular reflectance at `cos` to the microfacet normal is
    /// `dielectric * fresnel::dielectric(cos) + metal_f0 + metal_rise * fresnel::schlick_rise(cos)`.
    dielectric: f32,
    fresnel: &'static fresnel::DielectricTables,
    metallic: bool,
    metal_f0: Vec3,
    metal_rise: Vec3,
    /// GGX's `alpha^2` (`alpha` = roughness squared), and that over `pi`.
    a2: f32,
    a2_over_pi: f32,
    /// Probability of sampling the specular lobe, and that of the diffuse lobe over `pi`
    /// (the diffuse lobe's share of the pdf per unit cosine).
    p_spec: f32,
    p_diffuse_over_pi: f32,
}

pub(crate) fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Smith's `lambda` for GGX of `alpha^2 = a2` at a direction of cosine `cos` to the normal.
fn lambda(a2: f32, cos: f32) -> f32 {
    let c2 = (cos * cos).max(1e-8);
    // alpha^2 tan^2 = a2 (1 - c2) / c2.
    0.5 * ((1.0 + a2 * (1.0 - c2) / c2).sqrt() - 1.0)
}

impl Bsdf {
    /// `n` is the unit shading normal on the side the ray came from, `wo` the unit direction
    /// back along the ray.
    pub(crate) fn new(material: &Material, n: Vec3, wo: Vec3) -> Self {
        let metallic = material.metallic.clamp(0.0, 1.0);
        let roughness = material.roughness.clamp(0.03, 1.0);
        let cos_o = n.dot(wo);
        // The dielectric layer: KHR_materials_specular's factor scales its whole reflectance.
        let dielectric = (1.0 - metallic) * material.specular.clamp(0.0, 1.0);
        let (metal_f0, metal_rise) =
            (material.base_color * metallic, (Vec3::ONE - material.base_color) * metallic);
        let tables = fresnel::tables();
        let layer = dielectric * tables.lobe_average(cos_o.max(0.0), roughness);
        let diffuse = material.base_color * ((1.0 - metallic) * (1.0 - layer));
        // Reflectance at normal incidence: the dielectric's is 0.04.
        let f0 = metal_f0 + Vec3::splat(0.04 * dielectric);
        let (ld, ls) = (luminance(diffuse), luminance(f0));
        // Sample the specular lobe in proportion to its share, but never starve either lobe
        // that exists.
        let p_spec = if ls <= 0.0 {
            0.0
        } else if ld <= 0.0 {
            1.0
        } else {
            (ls.max(0.04) / (ls.max(0.04) + ld)).clamp(0.1, 0.9)
        };
        let alpha = roughness * roughness;
        let a2 = alpha * alpha;
        Self {
            frame: Frame::new(n),
            wo,
            cos_o,
            lambda_o: lambda(a2, cos_o),
            diffuse_over_pi: diffuse * FRAC_1_PI,
            dielectric,
            fresnel: tables,
            metallic: metallic > 0.0,
            metal_f0,
            metal_rise,
            a2,
            a2_over_pi: a2 * FRAC_1_PI,
            p_spec,
            p_diffuse_over_pi: (1.0 - p_spec) * FRAC_1_PI,
        }
    }

    /// `f(wo, wi) * cos(wi)`; zero below the surface.
    pub(crate) fn eval(&self, wi: Vec3) -> Vec3 {
        self.eval_pdf(wi).0
    }

    /// [`Self::eval`] and the solid-angle pdf of [`Self::sample`] returning `wi`, together:
    /// they share the half vector and the microfacet distribution, and every light sample
    /// needs both (the pdf for its MIS weight). Four divisions: GGX's `D` is
    /// `a2 / (pi t^2)`, its product with the Smith term over `4 (n.wo) (n.wi)` one quotient, the
    /// specular pdf another, and Smith's `lambda` of `wi` the last (results differ from the term-by-term quotients at the last bits).
    pub(crate) fn eval_pdf(&self, wi: Vec3) -> (Vec3, f32) {
        let (wo, co, ci) = (self.wo, self.cos_o, self.frame.n.dot(wi));
        if co <= 0.0 || ci <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let h = (wo + wi).normalize();
        let (cos_h, wo_h) = (self.frame.n.dot(h), wo.dot(h));
        let t = cos_h * cos_h * (self.a2 - 1.0) + 1.0;
        let d = self.a2_over_pi / (t * t);
        let mut f = Vec3::splat(self.dielectric * self.fresnel.fresnel(wo_h));
        // Most materials are dielectrics: they skip the metal's term.
        if self.metallic {
            f += self.metal_f0 + self.metal_rise * fresnel::schlick_rise(wo_h);
        }
        // D G / (4 co ci) with G = 1 / (1 + lambda_o + lambda_i).
        let g_denominator = 1.0 + self.lambda_o + lambda(self.a2, ci);
        let spec = f * (d / (g_denominator * (4.0 * co * ci)));
        let pdf_spec = d * cos_h / (4.0 * wo_h.max(1e-8));
        ((spec + self.diffuse_over_pi) * ci, self.p_spec * pdf_spec + self.p_diffuse_over_pi * ci)
    }

    /// Whether `wi` and `wo` are both above the shading surface: where [`Self::eval_pdf`] can
    /// be non-zero (zero elsewhere). Light samples test it before their shadow ray and
    /// evaluate the BSDF only when the ray arrives.
    pub(crate) fn reflects(&self, wi: Vec3) -> bool {
        self.cos_o > 0.0 && self.frame.n.dot(wi) > 0.0
    }

    /// The shading normal and its basis, for sampling light around it.
    pub(crate) fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Picks a lobe with `u_lobe`, then a direction with `u`.
    pub(crate) fn sample(&self, u: Vec2, u_lobe: f32) -> Option<BsdfSample> {
        let wo = self.wo;
        if self.cos_o <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.p_spec {
            // Sample D(h) cos(h), reflect wo about h.
            let h = self.frame.ggx_half_vector(self.a2, u);
            2.0 * wo.dot(h) * h - wo
        } else {
            self.frame.cosine(u)
        };
        let (f, pdf) = self.eval_pdf(wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some(BsdfSample { wi, weight: f * (1.0 / pdf), pdf })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Monte Carlo estimate of the directional albedo `∫ f cos dwi` by sampling the BSDF.
    fn albedo(m: &Material, cos_o: f32) -> Vec3 {
        let n = Vec3::Z;
        let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
        let b = Bsdf::new(m, n, wo);
        let k = 64;
        let mut sum = Vec3::ZERO;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let lobe = ((i * k + j) as f32 * 0.618_034).fract();
                if let Some(s) = b.sample(u, lobe) {
                    sum += s.weight;
                }
            }
        }
        sum / (k * k) as f32
    }

    #[test]
    fn sampled_directions_are_unit() {
        let mut worst: f32 = 0.0;
        for (i, n) in
            [Vec3::Z, -Vec3::Z, Vec3::new(0.3, -0.8, 0.52), Vec3::new(-0.99, 0.1, -0.05)].iter().enumerate()
        {
            let frame = Frame::new(n.normalize());
            for k in 0..4096 {
                let u = Vec2::new((k % 64) as f32 / 64.0 + 0.007, (k / 64) as f32 / 64.0 + 0.003 * i as f32);
                for d in [frame.cosine(u), frame.cone(0.9998, u)] {
                    worst = worst.max((d.length() - 1.0).abs());
                }
            }
        }
        assert!(worst < 1e-6, "worst |length - 1| {worst:e}");
    }

    #[test]
    fn sincos_turn_is_within_its_bound() {
        // Every multiple of 2^-20 in [0, 1], and the sampler's largest value, 1 - 2^-24.
        let turns = (0..=1 << 20).map(|i| i as f32 / (1 << 20) as f32).chain([1.0 - 1.0 / (1 << 24) as f32]);
        let mut worst: f64 = 0.0;
        for turn in turns {
            let (s, c) = sincos_turn(turn);
            let phi = std::f64::consts::TAU * turn as f64;
            worst = worst.max((s as f64 - phi.sin()).abs()).max((c as f64 - phi.cos()).abs());
        }
        assert!(worst < 2e-7, "worst error {worst:e}");
    }

    #[test]
    fn pure_lambert_has_exactly_its_albedo() {
        let a = albedo(&Material::lambertian(Vec3::splat(0.8)), 0.5);
        assert!((a.x - 0.8).abs() < 1e-3, "{a}");
    }

    #[test]
    fn white_dielectric_conserves_energy() {
        for cos in [0.1, 0.4, 0.7] {
            let a = albedo(&Material::diffuse(Vec3::ONE), cos);
            // Lambert under the dielectric Fresnel layer: a bit below 1, never above.
            assert!(a.x > 0.85 && a.x <= 1.01, "cos {cos}: {a}");
        }
    }

    #[test]
    fn surface_without_specular_layer_is_exactly_lambertian() {
        let m = Material::lambertian(Vec3::splat(0.5));
        let wo = Vec3::new(0.98, 0.0, 0.2).normalize();
        let b = Bsdf::new(&m, Vec3::Z, wo);
        for wi in [Vec3::new(-0.9, 0.0, 0.3), Vec3::new(0.9, 0.1, 0.3), Vec3::new(0.1, 0.5, 0.8)] {
            let wi = wi.normalize();
            let expect = 0.5 * FRAC_1_PI * wi.z;
            assert!((b.eval(wi) - Vec3::splat(expect)).abs().max_element() < 1e-7, "{wi}");
        }
    }

    #[test]
    fn diffuse_base_is_weighted_by_the_layers_lobe_average_for_every_incident_direction() {
        // A black dielectric has only the specular term; the same with a white base adds the
        // base's Lambertian term, the same share of it towards and away from the view.
        let (white, black) = (Material::diffuse(Vec3::ONE), Material::diffuse(Vec3::ZERO));
        let wo = Vec3::new(0.98, 0.0, 0.17).normalize();
        let (w, k) = (Bsdf::new(&white, Vec3::Z, wo), Bsdf::new(&black, Vec3::Z, wo));
        let base = |wi: Vec3| (w.eval(wi) - k.eval(wi)).x / (wi.z * FRAC_1_PI);
        let (back, forward) =
            (base(Vec3::new(0.7, 0.0, 0.7).normalize()), base(Vec3::new(-0.7, 0.0, 0.7).normalize()));
        assert!((back - forward).abs() < 1e-6, "{back} against {forward}");
        let expect = 1.0 - fresnel::tables().lobe_average(wo.z, 1.0);
        assert!((back - expect).abs() < 1e-6 && expect < 0.95, "{back} against {expect}");
    }

    #[test]
    fn rough_metal_does_not_create_energy() {
        let m = Material::metal(Vec3::ONE, 0.6);
        for cos in [0.2, 0.5, 0.9] {
            let a = albedo(&m, cos);
            assert!(a.max_element() <= 1.02, "cos {cos}: {a}");
            assert!(a.min_element() > 0.6, "cos {cos}: {a}");
        }
    }

    #[test]
    fn sample_weight_matches_eval_over_pdf() {
        let m = Material { roughness: 0.3, metallic: 0.4, ..Material::diffuse(Vec3::new(0.8, 0.5, 0.2)) };
        let wo = Vec3::new(0.3, 0.9, 0.1).normalize();
        let b = Bsdf::new(&m, Vec3::Y, wo);
        for i in 0..50 {
            let u = Vec2::new(i as f32 / 50.0 + 0.005, (i * 7 % 50) as f32 / 50.0 + 0.005);
            if let Some(s) = b.sample(u, (i as f32 * 0.37).fract()) {
                let (f, pdf) = b.eval_pdf(s.wi);
                let expect = f / pdf;
                assert!((s.weight - expect).abs().max_element() < 1e-3);
            }
        }
    }
}
