//! The film: per-pixel linear radiance and its tone mapping to 8-bit sRGB.

use glam::Vec3;

/// Linear RGB radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// ACES filmic tone curve (Narkowicz's fit), input and output linear.
fn aces(x: Vec3) -> Vec3 {
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// A linear value in `[0, 1]` as an 8-bit sRGB code. (A code table instead of the `powf` gave
/// the same bytes and no faster frames: docs/lab/reuse.md#2026-12-06-the-first-frames-mean-a-wide-change-index-the-benchmarks-again)
pub(super) fn srgb_encode(c: f32) -> u8 {
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

impl Film {
    pub(crate) fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// A pass showing per-pixel counts (`counts` row-major), each in all three channels.
    pub(crate) fn from_counts(width: u32, height: u32, counts: &[u32]) -> Self {
        debug_assert_eq!(counts.len(), width as usize * height as usize);
        Self { width, height, pixels: counts.iter().map(|&n| Vec3::splat(n as f32)).collect() }
    }

    /// Tone-mapped, sRGB-encoded 8-bit pixels. Non-finite radiance maps to black.
    pub(super) fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|&p| {
                let p = if p.is_finite() { p } else { Vec3::ZERO };
                let m = aces(p * exposure);
                [srgb_encode(m.x), srgb_encode(m.y), srgb_encode(m.z)]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_curve_is_monotonic_and_bounded() {
        let mut last = 0u8;
        for i in 0..100 {
            let v = srgb_encode(aces(Vec3::splat(i as f32 * 0.1)).x);
            assert!(v >= last);
            last = v;
        }
        assert_eq!(srgb_encode(aces(Vec3::splat(1e9)).x), 255);
        assert_eq!(srgb_encode(aces(Vec3::ZERO).x), 0);
    }
}
