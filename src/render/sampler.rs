//! Deterministic low-discrepancy sampling: Roberts' R2 sequence per pixel, decorrelated
//! between pixels, frames and dimensions by a hashed Cranley-Patterson rotation. The same
//! pixel, frame and sample index always give the same point, whatever thread renders it.

use glam::Vec2;

/// Plastic-constant generator of the R2 sequence.
const R2: Vec2 = Vec2::new(0.754_877_7, 0.569_840_3);

/// Samples for one pixel of one frame.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler {
    seed: u32,
}

fn hash(mut x: u32) -> u32 {
    // A well-mixed 32-bit integer hash (lowbias32).
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

fn unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

impl PixelSampler {
    pub(crate) fn new(x: u32, y: u32, frame: u32) -> Self {
        Self { seed: hash(x ^ hash(y ^ hash(frame.wrapping_add(0x9e37_79b9)))) }
    }

    /// The `index`-th value of the 1D dimension `dim`, in `[0, 1)`: the base-2 radical inverse
    /// (van der Corput) of `index`, rotated per pixel and dimension. For the shutter time: a
    /// coordinate of [`Self::get_2d`] would be `offset + index * R2.x`, a fixed shift of the
    /// pixel jitter's x (every dimension shares R2's generator), tying each sample's time to
    /// where in the pixel it lands.
    pub fn get_1d(&self, index: u32, dim: u32) -> f32 {
        let h = hash(self.seed ^ hash(dim.wrapping_mul(0x68e3_1da4)));
        let p = unit(h) + unit(index.reverse_bits());
        p - p.floor()
    }

    /// The `index`-th 2D point of dimension pair `dim`, in `[0, 1)^2`.
    pub fn get_2d(&self, index: u32, dim: u32) -> Vec2 {
        let h = hash(self.seed ^ hash(dim.wrapping_mul(0x68e3_1da4)));
        let offset = Vec2::new(unit(h), unit(hash(h)));
        let p = offset + index as f32 * R2;
        // `p` is non-negative, so truncation is its floor: a plain conversion instead of a call
        // to libm's `floorf` (x86-64's baseline SSE2 has no rounding instruction), which was
        // 2% of a path-traced frame's profile. Same bits as `p - p.floor()`.
        debug_assert!(p.x >= 0.0 && p.y >= 0.0);
        p - p.as_uvec2().as_vec2()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_are_in_unit_square_and_deterministic() {
        let s = PixelSampler::new(3, 7, 0);
        for i in 0..1000 {
            let p = s.get_2d(i, 2);
            assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
            assert_eq!(p, PixelSampler::new(3, 7, 0).get_2d(i, 2));
        }
    }

    #[test]
    fn sixteen_points_cover_the_quadrants_evenly() {
        let s = PixelSampler::new(1, 2, 3);
        let mut quadrants = [0; 4];
        for i in 0..16 {
            let p = s.get_2d(i, 0);
            quadrants[(p.x >= 0.5) as usize + 2 * (p.y >= 0.5) as usize] += 1;
        }
        assert!(quadrants.iter().all(|&q| (2..=6).contains(&q)), "{quadrants:?}");
    }
}
