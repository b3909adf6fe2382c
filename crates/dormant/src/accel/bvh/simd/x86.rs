//! The x86-64 kernels: AVX2 (8 boxes in one `__m256`, and a leaf's triangles two packets at a
//! time) and AVX-512 (the same with the box compare going straight to a mask register). Their
//! tokens are made only by [`super::dispatch!`] once the path is known to run here; every
//! intrinsic below relies on that, except [`truncate3`]'s, which are SSE2 (part of x86-64).

use std::arch::x86_64::*;

use glam::Vec3A;

use super::{BoxRay8, Boxes8, Kernel, FAR_SCALE};
use crate::accel::bvh::triangle::{Axis, RayTri, Tri4, TriHit, TriLanes};

/// [`super::truncate3`]: one SSE2 conversion, then the three lanes moved out.
#[inline(always)]
pub(crate) fn truncate3(x: Vec3A) -> [usize; 3] {
    // SAFETY: SSE2 is part of the x86-64 baseline, so every CPU this runs on has these
    // instructions; they only convert and move register lanes.
    unsafe {
        let k = _mm_cvttps_epi32(x.into());
        let (y, z) = (_mm_shuffle_epi32::<0b01_01_01_01>(k), _mm_shuffle_epi32::<0b10_10_10_10>(k));
        [k, y, z].map(|v| _mm_cvtsi128_si32(v) as u32 as usize)
    }
}

/// Token of the AVX2 + FMA path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(());

/// Token of the AVX-512 (F + VL) path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512(());

impl Avx2 {
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    pub(crate) unsafe fn new_unchecked() -> Self {
        Avx2(())
    }
}

impl Avx512 {
    /// # Safety
    /// The CPU must support AVX2, FMA, AVX-512F and AVX-512VL.
    pub(crate) unsafe fn new_unchecked() -> Self {
        Avx512(())
    }
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct RayM256 {
    org: [__m256; 3],
    /// `-inv`: see [`near_far`].
    neg_inv: [__m256; 3],
    t_min: __m256,
}

#[inline(always)]
fn prepare(r: &BoxRay8) -> RayM256 {
    // SAFETY: only called through a token (`Avx2`/`Avx512`), which exists only on a CPU with
    // AVX2; `_mm256_set1_ps` needs AVX.
    unsafe {
        RayM256 {
            org: r.org.map(|x| _mm256_set1_ps(x)),
            neg_inv: r.inv.map(|x| _mm256_set1_ps(-x)),
            t_min: _mm256_set1_ps(r.t_min),
        }
    }
}

/// Near and far distances of the eight boxes: the values [`super::Portable`] computes, so
/// every path enters the same children in the same order.
///
/// Each plane's distance is `(org - plane) * -inv`: the portable path's `(plane - org) * inv`
/// up to the sign of a zero (negation is exact, rounding symmetric, and no comparison tells
/// `-0` from `+0`). This way round the box row's load folds into the subtraction: six loads
/// fewer per node (the portable path keeps its form: legacy SSE would copy the origin first).
/// The reductions are shallow trees, two and three dependent steps after the slabs instead of
/// three and four, which a single ray's latency-bound traversal pays at every node. `min` and
/// `max` are associative and scaling by `S > 0` commutes with `min`, so only a NaN lane (a ray
/// in a box's plane) may differ, and [`super::Portable`] reduces the same way.
///
/// Tried and not kept (FMA planes, Embree's per-ray octant planes, the ray's constants
/// reloaded per leaf instead of per node):
/// docs/lab/accelerators.md#2026-12-04-where-the-accelerator-targets-end-target-by-target
#[inline(always)]
fn near_far(r: &RayM256, b: &Boxes8, t_max: f32) -> (__m256, __m256) {
    // SAFETY: as in `prepare` (AVX only). `Boxes8` is `repr(C, align(32))` and each row is
    // 8 floats at a multiple of 32 bytes, so the aligned loads read exactly one row.
    unsafe {
        let slab = |k: usize| {
            let t0 = _mm256_mul_ps(_mm256_sub_ps(r.org[k], _mm256_load_ps(b.min[k].as_ptr())), r.neg_inv[k]);
            let t1 = _mm256_mul_ps(_mm256_sub_ps(r.org[k], _mm256_load_ps(b.max[k].as_ptr())), r.neg_inv[k]);
            (_mm256_min_ps(t0, t1), _mm256_max_ps(t0, t1))
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let scale = _mm256_set1_ps(FAR_SCALE);
        let near = _mm256_max_ps(_mm256_max_ps(nx, ny), _mm256_max_ps(nz, r.t_min));
        let far = _mm256_min_ps(
            _mm256_mul_ps(_mm256_min_ps(fx, fy), scale),
            _mm256_min_ps(_mm256_mul_ps(fz, scale), _mm256_set1_ps(t_max)),
        );
        (near, far)
    }
}

#[inline(always)]
fn to_array(v: __m256) -> [f32; 8] {
    let mut out = [0.0f32; 8];
    // SAFETY: AVX (token), and `out` holds 8 floats (unaligned store).
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
    out
}

/// [`Kernel::closest_tri`] and [`Kernel::occluded_tri`] on [`F32x8`] lanes: two packets per
/// test, for the AVX2 and the AVX-512 token alike (both run AVX2).
macro_rules! avx2_triangle_tests {
    () => {
        #[inline(always)]
        fn closest_tri(self, ray: &RayTri, packets: &[Tri4], t_max: f32) -> Option<(usize, TriHit)> {
            ray.closest_in::<F32x8>(packets, t_max)
        }

        #[inline(always)]
        fn occluded_tri(self, ray: &RayTri, packets: &[Tri4], t_max: f32) -> bool {
            ray.occluded_in::<F32x8>(packets, t_max)
        }
    };
}

impl Kernel for Avx2 {
    type Ray = RayM256;

    #[inline(always)]
    fn prepare(self, r: &BoxRay8) -> RayM256 {
        prepare(r)
    }

    #[inline(always)]
    fn box8(self, r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
        // SAFETY: the token exists only on a CPU with AVX2 and FMA.
        unsafe { box8_avx2(r, b, t_max) }
    }

    #[inline(always)]
    fn box8_or_inf(self, r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
        // SAFETY: as in `box8`.
        unsafe { box8_or_inf_avx2(r, b, t_max) }
    }

    #[inline(always)]
    fn leaf<R>(self, f: impl FnOnce() -> R) -> R {
        // SAFETY: as in `box8`.
        unsafe { run_avx2(f) }
    }

    avx2_triangle_tests!();
}

impl Kernel for Avx512 {
    type Ray = RayM256;

    #[inline(always)]
    fn prepare(self, r: &BoxRay8) -> RayM256 {
        prepare(r)
    }

    #[inline(always)]
    fn box8(self, r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
        // SAFETY: the token exists only on a CPU with AVX2, FMA, AVX-512F and AVX-512VL.
        unsafe { box8_avx512(r, b, t_max) }
    }

    /// The AVX2 kernel's: a masked move would need the mask in a vector again.
    #[inline(always)]
    fn box8_or_inf(self, r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
        // SAFETY: this CPU runs AVX2 and FMA (a subset of this token's features).
        unsafe { box8_or_inf_avx2(r, b, t_max) }
    }

    /// Compiled for AVX2: the leaf tests are AVX2's, and AVX-512 adds nothing to them.
    #[inline(always)]
    fn leaf<R>(self, f: impl FnOnce() -> R) -> R {
        // SAFETY: as in `box8_or_inf`.
        unsafe { run_avx2(f) }
    }

    avx2_triangle_tests!();
}

// The kernels as `#[target_feature]` functions: inlined into the query's entry point (which
// enables the same features), and a single call per node, not one per intrinsic, in code the
// compiler keeps out of line.

#[target_feature(enable = "avx,avx2,fma")]
#[inline]
unsafe fn box8_avx2(r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
    let (near, far) = near_far(r, b, t_max);
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
    (mask, to_array(near))
}

#[target_feature(enable = "avx,avx2,fma,avx512f,avx512vl")]
#[inline]
unsafe fn box8_avx512(r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
    let (near, far) = near_far(r, b, t_max);
    let mask = _mm256_cmp_ps_mask::<_CMP_LE_OQ>(near, far) as u32;
    (mask, to_array(near))
}

#[target_feature(enable = "avx,avx2,fma")]
#[inline]
unsafe fn box8_or_inf_avx2(r: &RayM256, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
    let (near, far) = near_far(r, b, t_max);
    let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
    let near = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), near, hit);
    (_mm256_movemask_ps(hit) as u32, to_array(near))
}

/// Runs `f` (inlined: a closure called once) compiled for AVX2 and FMA.
#[target_feature(enable = "avx,avx2,fma")]
#[inline]
unsafe fn run_avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Eight triangle lanes, two [`Tri4`] packets, in one AVX register: [`TriLanes`] for the AVX2
/// and AVX-512 leaf tests.
///
/// Private to this module, which makes values of it only inside [`Kernel::closest_tri`] and
/// [`Kernel::occluded_tri`] of the AVX2 and AVX-512 tokens: every intrinsic below runs on a CPU
/// with AVX2, which is what their `// SAFETY:` lines rely on.
#[derive(Clone, Copy, Debug)]
struct F32x8(__m256);

/// Lane flags of [`F32x8`]: all bits set or clear per lane.
#[derive(Clone, Copy, Debug)]
struct Mask8(__m256);

macro_rules! lane_op {
    ($trait:ident, $method:ident, $intrinsic:ident, $ty:ident) => {
        impl std::ops::$trait for $ty {
            type Output = $ty;
            #[inline(always)]
            fn $method(self, o: $ty) -> $ty {
                // SAFETY: values of this type exist only on a CPU with AVX2 (see `F32x8`).
                $ty(unsafe { $intrinsic(self.0, o.0) })
            }
        }
    };
}

lane_op!(Add, add, _mm256_add_ps, F32x8);
lane_op!(Sub, sub, _mm256_sub_ps, F32x8);
lane_op!(Mul, mul, _mm256_mul_ps, F32x8);
lane_op!(Div, div, _mm256_div_ps, F32x8);
lane_op!(BitAnd, bitand, _mm256_and_ps, Mask8);
lane_op!(BitOr, bitor, _mm256_or_ps, Mask8);

impl std::ops::Not for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn not(self) -> Mask8 {
        // SAFETY: as in `lane_op!` (AVX).
        Mask8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
    }
}

/// A [`TriLanes`] compare of [`F32x8`] by `_mm256_cmp_ps` with predicate `$op`.
macro_rules! lane_cmp {
    ($method:ident, $op:ident) => {
        #[inline(always)]
        fn $method(self, o: Self) -> Mask8 {
            // SAFETY: as in `lane_op!` (AVX).
            Mask8(unsafe { _mm256_cmp_ps::<$op>(self.0, o.0) })
        }
    };
}

impl TriLanes for F32x8 {
    type Mask = Mask8;
    type Array = [f32; 8];
    const PACKETS: usize = 2;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY: as in `lane_op!` (AVX).
        F32x8(unsafe { _mm256_set1_ps(x) })
    }

    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // SAFETY: as in `lane_op!` (AVX).
        F32x8(unsafe { _mm256_min_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn max(self, o: Self) -> Self {
        // SAFETY: as in `lane_op!` (AVX).
        F32x8(unsafe { _mm256_max_ps(self.0, o.0) })
    }

    /// Packet 0's row in the low half, packet 1's in the high half: two 16-byte loads.
    #[inline(always)]
    fn row(q: &[Tri4], v: usize, axis: Axis) -> Self {
        // SAFETY: as in `lane_op!` (AVX).
        F32x8(unsafe { _mm256_set_m128(q[1].row(v, axis).into(), q[0].row(v, axis).into()) })
    }

    // Ordered compares (false for a NaN lane), except `ne`, unordered (true for a NaN lane), as
    // glam's `cmpne` (`_mm_cmpneq_ps`) has it.
    lane_cmp!(lt, _CMP_LT_OQ);
    lane_cmp!(gt, _CMP_GT_OQ);
    lane_cmp!(eq, _CMP_EQ_OQ);
    lane_cmp!(ne, _CMP_NEQ_UQ);
    lane_cmp!(ge, _CMP_GE_OQ);
    lane_cmp!(le, _CMP_LE_OQ);

    /// `|x| < inf`: false for infinities and NaN, as glam's `is_finite_mask`.
    #[inline(always)]
    fn finite(self) -> Mask8 {
        // SAFETY: as in `lane_op!` (AVX).
        let abs = F32x8(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) });
        TriLanes::lt(abs, F32x8::splat(f32::INFINITY))
    }

    #[inline(always)]
    fn bitmask(m: Mask8) -> u32 {
        // SAFETY: as in `lane_op!` (AVX).
        unsafe { _mm256_movemask_ps(m.0) as u32 }
    }

    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        to_array(self.0)
    }
}
