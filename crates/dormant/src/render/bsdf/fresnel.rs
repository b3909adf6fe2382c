//! Fresnel reflectance of the specular layer, and the dielectric layer's reflectance averaged
//! over its GGX lobe, which weights the diffuse base beneath it.
//!
//! The base is layered by albedo scaling, as Blender's Principled BSDF (v2) and OpenPBR layer
//! it: the diffuse lobe is weighted by one minus the specular layer's reflectance averaged
//! over that layer's lobe for the outgoing direction, a constant per shading point. glTF's
//! reference `fresnel_mix` weights it by `1 - F(wo.h)` per incident direction instead, which
//! at grazing views makes a sunlit diffuse ground brighter than Principled (measured against
//! Cycles: docs/lab/cycles.md#2026-12-07-layering-the-demolitions-bias-was-the-diffuse-bases-layering).

use std::sync::OnceLock;

use super::lobe_table::DIELECTRIC_LOBE_AVERAGE;

/// The index of refraction of glTF's dielectric (F0 = 0.04).
const IOR: f32 = 1.5;

/// Schlick's rise of a metal's reflectance from its colour to white at grazing: `(1 - cos)^5`.
pub(super) fn schlick_rise(cos: f32) -> f32 {
    (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// Exact unpolarised Fresnel reflectance of a dielectric of IOR 1.5 at `cos` to the
/// microfacet normal: 0.04 at normal incidence, 1 at grazing. With `g^2 = eta^2 - 1 + c^2`,
/// `F = (g-c)^2 / (2 (g+c)^2) (1 + ((c (g+c) - 1) / (c (g-c) + 1))^2)`, as one quotient.
fn dielectric(cos: f32) -> f32 {
    let c = cos.clamp(0.0, 1.0);
    let g = (IOR * IOR - 1.0 + c * c).sqrt();
    let (minus, plus) = (g - c, g + c);
    let (b_num, b_den) = (c * plus - 1.0, c * minus + 1.0);
    let b_den2 = b_den * b_den;
    0.5 * minus * minus * (b_den2 + b_num * b_num) / (plus * plus * b_den2)
}

/// Nodes of the table of [`dielectric`] over `cos` in `[0, 1]`.
const FRESNEL_NODES: usize = 257;
/// Nodes per axis of the table of the lobe average over `cos_o` and roughness in `[0, 1]`.
const LOBE_NODES: usize = 32;

/// [`dielectric`] and its lobe average as tables: a lookup costs less on the BSDF's hot path
/// than the exact formula's square root and division. The lobe averages are committed
/// (`lobe_table.rs`, 2 million lobe samples, which every start-up would compute otherwise), the Fresnel table
/// is computed on first use (the variants measured: the lab entry linked above).
#[derive(Debug)]
pub(super) struct DielectricTables {
    fresnel: [f32; FRESNEL_NODES],
    /// Rows of equal roughness.
    lobe_average: &'static [[f32; LOBE_NODES]; LOBE_NODES],
}

pub(super) fn tables() -> &'static DielectricTables {
    static TABLES: OnceLock<DielectricTables> = OnceLock::new();
    TABLES.get_or_init(|| DielectricTables {
        fresnel: std::array::from_fn(|k| dielectric(k as f32 / (FRESNEL_NODES - 1) as f32)),
        lobe_average: &DIELECTRIC_LOBE_AVERAGE,
    })
}

impl DielectricTables {
    /// [`dielectric`] at `cos` in `[0, 1]`, linear between the table's nodes (within 1e-4 of
    /// it).
    pub(super) fn fresnel(&self, cos: f32) -> f32 {
        let x = cos * (FRESNEL_NODES - 1) as f32;
        // Truncation is the floor for x >= 0 (and saturates: any `cos` stays in the table); the
        // last cell takes the upper edge.
        let i = (x as u32 as usize).min(FRESNEL_NODES - 2);
        let (a, b) = (self.fresnel[i], self.fresnel[i + 1]);
        a + (b - a) * (x - i as f32)
    }

    /// [`dielectric`] averaged over the GGX lobe of `roughness` seen from a direction at
    /// `cos_o` to the normal (weighted by the lobe's `f cos`, so independent of the lobe's own
    /// energy loss): the share of light the dielectric layer takes from the base beneath.
    /// Bilinear between the table's nodes, for `cos_o` and `roughness` in `[0, 1]`.
    pub(super) fn lobe_average(&self, cos_o: f32, roughness: f32) -> f32 {
        let scale = (LOBE_NODES - 1) as f32;
        let (x, y) = (cos_o * scale, roughness * scale);
        let (i, j) = ((x as u32 as usize).min(LOBE_NODES - 2), (y as u32 as usize).min(LOBE_NODES - 2));
        let (tx, ty) = (x - i as f32, y - j as f32);
        let (row, next) = (&self.lobe_average[j], &self.lobe_average[j + 1]);
        let low = row[i] + (row[i + 1] - row[i]) * tx;
        let high = next[i] + (next[i + 1] - next[i]) * tx;
        low + (high - low) * ty
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::PI;

    use glam::{Vec2, Vec3};

    use super::super::{lambda, Frame};
    use super::*;

    /// The lobe averages at the table's nodes, `cos_o` varying fastest: what `lobe_table.rs` holds.
    fn lobe_average_nodes() -> Vec<f32> {
        let node = |k: usize| k as f32 / (LOBE_NODES - 1) as f32;
        // Grazing and mirror limits: the renderer clamps roughness to 0.03 and meets cos_o > 0.
        (0..LOBE_NODES * LOBE_NODES)
            .map(|k| lobe_average(node(k % LOBE_NODES).max(1e-3), node(k / LOBE_NODES).max(0.03), 64))
            .collect()
    }

    /// The lobe average of [`dielectric`] by a midpoint rule over `n x n/2` half vectors placed by
    /// the GGX distribution (over half a turn: the lobe is symmetric about the plane of `wo` and
    /// the normal). A half vector with pdf `D cos_h` carries `f cos_i / pdf = G (wo.h) / (cos_o
    /// cos_h)` of the lobe; `cos_o` cancels in the average.
    fn lobe_average(cos_o: f32, roughness: f32, n: usize) -> f32 {
        let a2 = roughness.powi(4);
        let wo = Vec3::new((1.0 - cos_o * cos_o).max(0.0).sqrt(), 0.0, cos_o);
        let frame = Frame::new(Vec3::Z);
        let lambda_o = lambda(a2, cos_o);
        let (mut fresnel_sum, mut weight_sum) = (0.0f64, 0.0f64);
        for i in 0..n {
            for j in 0..n / 2 {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let h = frame.ggx_half_vector(a2, u);
                let wo_h = wo.dot(h);
                let wi = 2.0 * wo_h * h - wo;
                if wo_h <= 0.0 || wi.z <= 0.0 {
                    continue;
                }
                let weight = (wo_h / (h.z * (1.0 + lambda_o + lambda(a2, wi.z)))) as f64;
                fresnel_sum += dielectric(wo_h) as f64 * weight;
                weight_sum += weight;
            }
        }
        debug_assert!(weight_sum > 0.0, "no half vector reflects at cos_o {cos_o}, roughness {roughness}");
        (fresnel_sum / weight_sum) as f32
    }

    /// The same average over incident directions on a fine grid of the hemisphere: an
    /// independent quadrature of `∫ F f cos dwi / ∫ f cos dwi` (rough lobes only, which a
    /// uniform grid resolves).
    fn solid_angle_average(cos_o: f32, roughness: f32) -> f32 {
        let a2 = roughness.powi(4);
        let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
        let (n, mut num, mut den) = (400, 0.0f64, 0.0f64);
        for i in 0..n {
            for j in 0..2 * n {
                let theta = (i as f32 + 0.5) / n as f32 * PI / 2.0;
                let phi = (j as f32 + 0.5) / (2 * n) as f32 * 2.0 * PI;
                let wi = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let h = (wo + wi).normalize();
                let t = h.z * h.z * (a2 - 1.0) + 1.0;
                let d = a2 / (PI * t * t);
                let g = 1.0 / (1.0 + lambda(a2, cos_o) + lambda(a2, wi.z));
                // f cos_i dwi, up to constant factors that cancel.
                let w = (d * g * theta.sin()) as f64;
                num += dielectric(wo.dot(h)) as f64 * w;
                den += w;
            }
        }
        (num / den) as f32
    }

    #[test]
    fn dielectric_fresnel_is_four_percent_head_on_and_one_at_grazing() {
        assert!((dielectric(1.0) - 0.04).abs() < 1e-6);
        assert!((dielectric(0.0) - 1.0).abs() < 1e-6);
        // Reflectance at 60 degrees, unpolarised, from the Fresnel equations by hand.
        assert!((dielectric(0.5) - 0.0891).abs() < 2e-4, "{}", dielectric(0.5));
    }

    /// `DORMANT_WRITE_LOBE_TABLE=1` rewrites the file from the quadrature (after a change to
    /// the lobe or its Fresnel).
    #[test]
    fn committed_lobe_table_matches_its_quadrature() {
        let nodes = lobe_average_nodes();
        if std::env::var_os("DORMANT_WRITE_LOBE_TABLE").is_some() {
            let rows: Vec<String> = nodes
                .chunks(LOBE_NODES)
                .map(|row| {
                    format!("    [{}],", row.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(", "))
                })
                .collect();
            let text = format!(
                "//! The dielectric layer's Fresnel reflectance averaged over its GGX lobe at 32 x 32 nodes\n\
                 //! (`cos_o` fastest, then roughness, each over `[0, 1]`), generated by the test\n\
                 //! `committed_lobe_table_matches_its_quadrature` in `fresnel.rs`: do not edit.\n\n\
                 #[rustfmt::skip]\n\
                 pub(super) const DIELECTRIC_LOBE_AVERAGE: [[f32; 32]; 32] = [\n{}\n];\n",
                rows.join("\n")
            );
            std::fs::write(concat!(env!("CARGO_MANIFEST_DIR"), "/src/render/bsdf/lobe_table.rs"), text)
                .unwrap();
        }
        for (k, (committed, computed)) in DIELECTRIC_LOBE_AVERAGE.iter().flatten().zip(&nodes).enumerate() {
            assert!((committed - computed).abs() < 1e-6, "node {k}: {committed} against {computed}");
        }
    }

    #[test]
    fn tabulated_fresnel_is_within_its_bound() {
        let worst = (0..=100_000)
            .map(|k| k as f32 / 100_000.0)
            .map(|cos| (tables().fresnel(cos) - dielectric(cos)).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "worst error {worst:e}");
    }

    #[test]
    fn lobe_average_agrees_with_a_solid_angle_quadrature() {
        for (cos_o, roughness) in [(0.17, 1.0), (0.5, 0.7), (0.3, 0.5), (0.9, 0.6)] {
            let (table, direct) =
                (tables().lobe_average(cos_o, roughness), solid_angle_average(cos_o, roughness));
            assert!(
                (table - direct).abs() < 2e-3,
                "cos_o {cos_o} roughness {roughness}: {table} vs {direct}"
            );
        }
    }

    #[test]
    fn smooth_lobe_averages_to_the_fresnel_of_the_mirror_direction() {
        for cos_o in [0.2, 0.6, 1.0] {
            let average = lobe_average(cos_o, 0.03, 64);
            assert!((average - dielectric(cos_o)).abs() < 1e-3, "cos_o {cos_o}: {average}");
        }
    }
}
