//! Deterministic low-discrepancy sampling: per pixel, every dimension pair is its own
//! shuffled, Owen-scrambled 2D Sobol sequence (Burley 2020, "Practical Hash-based Owen
//! Scrambling"). The same pixel, frame and sample index always give the same point, whatever
//! thread renders it.
//!
//! Each pair `dim` of a pixel hashes three seeds: one shuffles the sample index, two scramble
//! the point's coordinates. The point is the first two Sobol dimensions (the (0,2)-sequence:
//! van der Corput in base 2 and Sobol's second generator matrix), each coordinate nested-
//! uniform (Owen) scrambled. The index shuffle is itself a nested uniform scramble of the
//! index bits: it maps the first `2^k` indices onto one aligned block of `2^k` consecutive
//! Sobol indices, and every such block of a (0,2)-sequence is a (0,k,2)-net. So any prefix of
//! `2^k` samples of a pair is stratified in every elementary interval of area `2^-k` (in
//! particular in a `2^(k/2)` grid for even `k`), whatever the pixel's sample budget, which an
//! adaptive pixel that stops early relies on. Because every pair gets an independent shuffle,
//! sample `i` of one pair is unrelated to sample `i` of another: the pairs are independent.
//!
//! Do not go back to one sequence shared by all pairs with only per-pair offsets or per-pair
//! scrambling: without a per-pair index shuffle the pairs stay correlated (Owen scrambling
//! flips the same index bit in both), and each pixel converges to a seed-dependent value, an
//! error floor no sample count removes. The R2 lattice this sampler replaced had that floor:
//! docs/lab/sampling.md#2026-12-02-adaptive-sampling-with-the-r2-sampler
//! pbrt-v4's padded Sobol sampler shuffles with a random permutation of `[0, spp)` instead,
//! which needs the pixel's budget and leaves an early-stopped prefix unstratified.
//!
//! Cost: the dimension-hash table, the pre-reversed Sobol tables and the per-pixel seeds of the
//! first pairs keep the sampler a small share of a path-traced frame; cheaper hash-combined
//! seeds for the three scrambles would change every image for little:
//! docs/lab/rendering.md#2026-12-02-shading-cut-last-bit-changes-allowed

use glam::Vec2;

/// Samples for one pixel of one frame.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler {
    seed: u32,
    /// [`Self::hash_seeds`] of the pairs below [`CACHED_PAIRS`], hashed once per pixel: every
    /// camera sample draws from them (the pixel jitter and the first path vertex's sun, sky
    /// and bounce pairs). Same bits as hashing at each call.
    cached: [(u32, u32, u32); CACHED_PAIRS],
}

/// Dimension pairs whose seeds a [`PixelSampler`] hashes when made: `dims::PIXEL` (0), the
/// preview's `SUN` and `SKY` (1, 2) and the path tracer's first vertex (`BOUNCE` + 0..4).
const CACHED_PAIRS: usize = 7;

const fn hash(mut x: u32) -> u32 {
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

/// A random bijection of 32-bit words in which output bit `j` depends only on input bits
/// `0..=j` (each step only carries from lower bits to higher ones), seeded by `seed`: applied
/// to bit-reversed words, a nested uniform scramble. Laine and Karras' construction with
/// Burley's (2020) mixing constants.
fn low_to_high_permutation(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Nested uniform (Owen) scramble of a binary fraction `x` (most significant bit first): each
/// bit is flipped by a random function of the bits above it.
fn owen_scramble(x: u32, seed: u32) -> u32 {
    low_to_high_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// Sobol's second generator matrix (the Pascal matrix mod 2) as byte tables, in the bit order
/// the scramble works in: entry `b` of table `t` is `reverse_bits(sobol_1(reverse_bits(r)))`
/// for the word `r` whose byte `t` is `b` (the others zero). The map is linear over GF(2), so a
/// scrambled index straight out of [`low_to_high_permutation`] gives its point's second
/// coordinate, bit-reversed, in four lookups: one bit reversal fewer than reversing the
/// index, looking its point up and reversing the point (same bits).
const SOBOL_1_REVERSED: [[u32; 256]; 4] = sobol_1_reversed_tables();

/// Column `j` of Sobol's second generator matrix: `v_0 = 1/2`, `v_j = v_{j-1} ^ (v_{j-1} >> 1)`.
const fn sobol_1_columns() -> [u32; 32] {
    let mut columns = [0u32; 32];
    columns[0] = 1 << 31;
    let mut j = 1;
    while j < 32 {
        columns[j] = columns[j - 1] ^ (columns[j - 1] >> 1);
        j += 1;
    }
    columns
}

const fn sobol_1_reversed_tables() -> [[u32; 256]; 4] {
    let columns = sobol_1_columns();
    let mut tables = [[0u32; 256]; 4];
    let mut t = 0;
    while t < 4 {
        let mut b = 0;
        while b < 256 {
            let mut v = 0;
            let mut bit = 0;
            while bit < 8 {
                // Bit `8t + bit` of `r` is bit `31 - 8t - bit` of the index.
                if b >> bit & 1 == 1 {
                    v ^= columns[31 - (8 * t + bit)].reverse_bits();
                }
                bit += 1;
            }
            tables[t][b] = v;
            b += 1;
        }
        t += 1;
    }
    tables
}

/// `reverse_bits(sobol_1(reverse_bits(r)))`: the second coordinate of the Sobol point whose
/// index is `r` bit-reversed, itself bit-reversed.
fn sobol_1_reversed(r: u32) -> u32 {
    let b = r.to_le_bytes();
    SOBOL_1_REVERSED[0][b[0] as usize]
        ^ SOBOL_1_REVERSED[1][b[1] as usize]
        ^ SOBOL_1_REVERSED[2][b[2] as usize]
        ^ SOBOL_1_REVERSED[3][b[3] as usize]
}

/// The second coordinate of Sobol point `index`, as a 32-bit binary fraction.
#[cfg(test)]
fn sobol_1(index: u32) -> u32 {
    let columns = sobol_1_columns();
    (0..32).filter(|&j| index >> j & 1 == 1).fold(0, |v, j| v ^ columns[j])
}

/// Dimension pairs below this get their seed hash from [`DIM_HASHES`].
const DIM_TABLE: usize = 512;

/// `hash(dim * 0x68e3_1da4)` of every dimension below [`DIM_TABLE`] (every one the integrators
/// use), computed at compile time: one hash fewer per sample point, same bits.
const DIM_HASHES: [u32; DIM_TABLE] = {
    let mut table = [0u32; DIM_TABLE];
    let mut d = 0;
    while d < DIM_TABLE {
        table[d] = hash((d as u32).wrapping_mul(0x68e3_1da4));
        d += 1;
    }
    table
};

fn dim_hash(dim: u32) -> u32 {
    match DIM_HASHES.get(dim as usize) {
        Some(&h) => h,
        None => hash(dim.wrapping_mul(0x68e3_1da4)),
    }
}

impl PixelSampler {
    pub(crate) fn new(x: u32, y: u32, frame: u32) -> Self {
        let seed = hash(x ^ hash(y ^ hash(frame.wrapping_add(0x9e37_79b9))));
        Self { seed, cached: std::array::from_fn(|dim| Self::hash_seeds(seed, dim as u32)) }
    }

    /// The seeds of dimension `dim`'s index shuffle and of its two coordinates' scrambles.
    fn seeds(&self, dim: u32) -> (u32, u32, u32) {
        match self.cached.get(dim as usize) {
            Some(&seeds) => seeds,
            None => Self::hash_seeds(self.seed, dim),
        }
    }

    /// [`Self::seeds`] of the pixel seeded `seed`, hashed.
    fn hash_seeds(seed: u32, dim: u32) -> (u32, u32, u32) {
        let h = hash(seed ^ dim_hash(dim));
        (hash(h ^ 0x5bd1_e995), hash(h ^ 0x1b87_3593), hash(h ^ 0xcc9e_2d51))
    }

    /// The `index`-th value of the 1D dimension `dim`, in `[0, 1)`: the first coordinate of
    /// [`Self::get_2d`]'s construction (shuffled, Owen-scrambled van der Corput), so independent
    /// of every pair and stratified in `2^k` intervals for any prefix of `2^k`. For the shutter
    /// time; `dim` must not also be a pair's.
    pub(crate) fn get_1d(&self, index: u32, dim: u32) -> f32 {
        let (shuffle, sx, _) = self.seeds(dim);
        unit(low_to_high_permutation(owen_scramble(index, shuffle), sx).reverse_bits())
    }

    /// The `index`-th 2D point of dimension pair `dim`, in `[0, 1)^2`.
    pub(crate) fn get_2d(&self, index: u32, dim: u32) -> Vec2 {
        let (shuffle, sx, sy) = self.seeds(dim);
        // The shuffled index, bit-reversed: `i = owen_scramble(index, shuffle)` is
        // `r.reverse_bits()`.
        let r = low_to_high_permutation(index.reverse_bits(), shuffle);
        // Dimension 0 is the van der Corput sequence, reverse_bits(i); scrambling it is
        // reverse_bits(low_to_high_permutation(i)).
        let x = low_to_high_permutation(r.reverse_bits(), sx).reverse_bits();
        // owen_scramble(sobol_1(i), sy), with the reversals folded into the tables.
        let y = low_to_high_permutation(sobol_1_reversed(r), sy).reverse_bits();
        Vec2::new(unit(x), unit(y))
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
        assert_eq!(quadrants, [4; 4]);
    }

    #[test]
    fn reversed_tables_match_the_scramble_they_replace() {
        let s = PixelSampler::new(9, 4, 5);
        for dim in [0, 3, 6, 7, 300, 511, 512, 9000] {
            let (shuffle, sx, sy) = s.seeds(dim);
            for index in (0..300).chain([1 << 20, u32::MAX]) {
                let i = owen_scramble(index, shuffle);
                let x = low_to_high_permutation(i, sx).reverse_bits();
                let y = owen_scramble(sobol_1(i), sy);
                assert_eq!(s.get_2d(index, dim), Vec2::new(unit(x), unit(y)), "dim {dim} index {index}");
            }
            assert_eq!(dim_hash(dim), hash(dim.wrapping_mul(0x68e3_1da4)));
            assert_eq!(s.seeds(dim), PixelSampler::hash_seeds(s.seed, dim));
        }
    }

    #[test]
    fn unscrambled_sobol_starts_as_expected() {
        // The (0,2)-sequence's second coordinate: 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8.
        let eighths: Vec<u32> = (0..8).map(|i| sobol_1(i) >> 29).collect();
        assert_eq!(eighths, [0, 4, 6, 2, 5, 1, 3, 7]);
    }

    /// Every prefix of `2^k` samples of a pair has exactly one point in each elementary
    /// interval of area `2^-k` (`2^a` by `2^(k-a)` cells, every `a`): a (0,k,2)-net.
    #[test]
    fn every_power_of_two_prefix_is_stratified_in_every_elementary_interval() {
        for (pixel, dim) in [((0, 0), 0), ((5, 9), 1), ((123, 45), 7), ((640, 360), 300)] {
            let s = PixelSampler::new(pixel.0, pixel.1, 11);
            for k in 0..=10u32 {
                let n = 1u32 << k;
                let points: Vec<Vec2> = (0..n).map(|i| s.get_2d(i, dim)).collect();
                for a in 0..=k {
                    let (cx, cy) = (1u32 << a, 1u32 << (k - a));
                    let mut cells = vec![0u8; n as usize];
                    for p in &points {
                        let (x, y) = ((p.x * cx as f32) as u32, (p.y * cy as f32) as u32);
                        cells[(y * cx + x) as usize] += 1;
                    }
                    assert!(
                        cells.iter().all(|&c| c == 1),
                        "pixel {pixel:?} pair {dim}: {n} points, {cx}x{cy}"
                    );
                }
            }
        }
    }

    #[test]
    fn one_dimensional_prefixes_are_stratified() {
        let s = PixelSampler::new(17, 4, 2);
        for k in 0..=10u32 {
            let n = 1u32 << k;
            let mut cells = vec![0u8; n as usize];
            for i in 0..n {
                cells[(s.get_1d(i, 600) * n as f32) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "{n} values");
        }
    }

    /// Sample correlation of coordinate `a` of pair 0 with coordinate `b` of pair `other`.
    fn correlation(s: &PixelSampler, n: u32, other: u32, a: usize, b: usize) -> f64 {
        let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let (p, q) = (s.get_2d(i, 0).to_array()[a] as f64, s.get_2d(i, other).to_array()[b] as f64);
            (sx, sy, sxx, syy, sxy) = (sx + p, sy + q, sxx + p * p, syy + q * q, sxy + p * q);
        }
        let n = n as f64;
        (sxy / n - sx * sy / n / n) / ((sxx / n - (sx / n).powi(2)) * (syy / n - (sy / n).powi(2))).sqrt()
    }

    #[test]
    fn dimension_pairs_of_a_pixel_are_uncorrelated() {
        // 256 independent uniform pairs have correlation ~ N(0, 1/16); the R2 sampler this
        // replaced gave |r| near 1 for some pixels.
        let mut worst: f64 = 0.0;
        for p in 0..16 {
            let s = PixelSampler::new(p, 3 * p, 0);
            for other in [1, 2, 5, 200] {
                for (a, b) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    worst = worst.max(correlation(&s, 256, other, a, b).abs());
                }
            }
        }
        assert!(worst < 0.3, "worst |correlation| {worst}");
    }

    /// A 4D integrand across two pairs: the product of step functions with known integral
    /// 0.3 * 0.7 * 0.55 * 0.45. Each pixel's 1,024-sample estimate must be within the error of
    /// randomised sampling of the pairs, not stuck at a per-pixel seed-dependent value.
    #[test]
    fn a_four_dimensional_product_converges_in_every_pixel() {
        let truth = 0.3 * 0.7 * 0.55 * 0.45;
        let f = |p: Vec2, q: Vec2| (p.x < 0.3 && p.y < 0.7 && q.x < 0.55 && q.y < 0.45) as u32 as f64;
        let n = 1024;
        let mut worst: f64 = 0.0;
        let mut squared = 0.0;
        let pixels = 64;
        for pixel in 0..pixels {
            let s = PixelSampler::new(pixel % 8, pixel / 8, 1);
            let estimate = (0..n).map(|i| f(s.get_2d(i, 3), s.get_2d(i, 4))).sum::<f64>() / n as f64;
            worst = worst.max((estimate - truth).abs());
            squared += (estimate - truth).powi(2);
        }
        // Independent samples: standard error sqrt(t(1-t)/n) = 0.0085; stratified pairs do
        // somewhat better. The old sampler's per-pixel errors reached several times that.
        let rms = (squared / pixels as f64).sqrt();
        assert!(rms < 0.0085, "rms error {rms}");
        assert!(worst < 4.0 * 0.0085, "worst error {worst}");
    }
}
