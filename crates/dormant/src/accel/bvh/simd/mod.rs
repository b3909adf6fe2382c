//! The SIMD paths of the BVH's ray queries: which one runs ([`SimdPath`]: run-time CPU
//! detection, overridden by the `DORMANT_SIMD` environment variable), and the per-path kernels
//! ([`Kernel`]: the 8-wide box test of [`crate::accel::bvh`]'s wide nodes, and how many triangle
//! packets a leaf test takes at once).
//!
//! The default is AVX2 where the CPU runs it ([`SimdPath::best`]: AVX-512 measured slower).
//! A query picks its path once ([`SimdPath::current`]) and runs the whole traversal as one
//! function compiled for it: [`dispatch!`] calls a `#[target_feature]` entry point whose body is
//! the generic traversal (`#[inline(always)]` down to the kernel), so the intrinsics inline and
//! no node pays a dispatch. The portable path ([`Portable`]) uses glam's `Vec4` only (SSE2 on
//! x86-64, NEON on aarch64, scalar elsewhere) and always exists.

#[cfg(target_arch = "x86_64")]
mod x86;

use std::cell::Cell;
use std::sync::atomic::{AtomicU8, Ordering};

use glam::{Vec3A, Vec4};
use serde::Serialize;

use super::triangle::{RayTri, Tri4, TriHit};

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx2, Avx512};

/// `1 + 2 * gamma(3)`: widens the far slab distance of every box test (the 8-wide kernels and
/// the binary traversal) to absorb rounding (pbrt 4, section 6.8).
pub(crate) const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// The environment variable that selects a path.
pub(crate) const SIMD_ENV: &str = "DORMANT_SIMD";

/// One SIMD path of the BVH traversal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SimdPath {
    /// glam only: no hand-written intrinsics; runs on every CPU.
    Portable,
    /// AVX2 + FMA: 8-wide box tests in one `__m256`.
    Avx2,
    /// AVX-512 (F + VL): the AVX2 kernel with compares straight into mask registers (only
    /// when asked for: measured slower than AVX2).
    Avx512,
}

/// `DORMANT_SIMD` names no path, or one this CPU cannot run.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SimdError {
    #[error("{SIMD_ENV}={value}: unknown SIMD path (expected portable, avx2 or avx512)")]
    Unknown { value: String },
    #[error("{SIMD_ENV}={value}: this CPU does not support it (supported: {supported})")]
    Unsupported { value: String, supported: String },
}

impl SimdPath {
    pub const ALL: [SimdPath; 3] = [SimdPath::Portable, SimdPath::Avx2, SimdPath::Avx512];

    pub(crate) fn name(self) -> &'static str {
        match self {
            SimdPath::Portable => "portable",
            SimdPath::Avx2 => "avx2",
            SimdPath::Avx512 => "avx512",
        }
    }

    /// Whether this CPU runs the path.
    pub(crate) fn is_supported(self) -> bool {
        match self {
            SimdPath::Portable => true,
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx512 => {
                SimdPath::Avx2.is_supported()
                    && is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The paths this CPU runs, portable first.
    pub fn supported() -> Vec<SimdPath> {
        Self::ALL.into_iter().filter(|p| p.is_supported()).collect()
    }

    /// The default: AVX2 where the CPU runs it, else portable. AVX-512 is never the default:
    /// its 8-wide kernel differs only in the compare going to a mask register, and it measured
    /// slower than AVX2 on the project's AVX-512 machine:
    /// docs/lab/accelerators.md#2026-12-02-simd-paths-8-wide-nodes-four-triangle-leaves-avx2-avx-512-portable
    pub(crate) fn best() -> SimdPath {
        if SimdPath::Avx2.is_supported() {
            SimdPath::Avx2
        } else {
            SimdPath::Portable
        }
    }

    /// The path `DORMANT_SIMD` asks for (the best supported one when unset or empty).
    fn from_env() -> Result<SimdPath, SimdError> {
        match std::env::var(SIMD_ENV) {
            Ok(v) if !v.trim().is_empty() => Self::parse(&v),
            _ => Ok(Self::best()),
        }
    }

    /// A path by name, if this CPU supports it.
    pub(crate) fn parse(value: &str) -> Result<SimdPath, SimdError> {
        let path = Self::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(value.trim()))
            .ok_or_else(|| SimdError::Unknown { value: value.to_string() })?;
        if !path.is_supported() {
            let supported = Self::supported().iter().map(|p| p.name()).collect::<Vec<_>>().join(", ");
            return Err(SimdError::Unsupported { value: value.to_string(), supported });
        }
        Ok(path)
    }

    fn code(self) -> u8 {
        self as u8 + 1
    }

    /// The path queries run now: this thread's override ([`Self::with_override`]), else the
    /// process-wide one, which is read from `DORMANT_SIMD` on first use (a bad value falls back
    /// to the best path there; the CLI refuses it before any query with [`Self::activate_from_env`]).
    #[inline]
    pub fn current() -> SimdPath {
        if let Some(p) = OVERRIDE.with(Cell::get) {
            return p;
        }
        match ACTIVE.load(Ordering::Relaxed) {
            0 => {
                let p = Self::from_env().unwrap_or_else(|_| Self::best());
                ACTIVE.store(p.code(), Ordering::Relaxed);
                p
            }
            c => Self::ALL[(c - 1) as usize],
        }
    }

    /// Makes the path `DORMANT_SIMD` asks for the process-wide one and returns it; a value that
    /// is unknown or unsupported here is an error (the CLI calls this before any query).
    pub fn activate_from_env() -> Result<SimdPath, SimdError> {
        let path = Self::from_env()?;
        ACTIVE.store(path.code(), Ordering::Relaxed);
        Ok(path)
    }

    /// Runs `f` with queries on this thread using `path` (tests iterate over the paths with it).
    /// Panics when the CPU does not support `path` (callers iterate [`Self::supported`]).
    #[cfg(test)]
    pub(crate) fn with_override<R>(path: SimdPath, f: impl FnOnce() -> R) -> R {
        assert!(path.is_supported(), "SIMD path {} is not supported here", path.name());
        let old = OVERRIDE.with(|o| o.replace(Some(path)));
        let r = f();
        OVERRIDE.with(|o| o.set(old));
        r
    }
}

/// 0: not yet read from the environment; otherwise `SimdPath::code`.
static ACTIVE: AtomicU8 = AtomicU8::new(0);

thread_local! {
    static OVERRIDE: Cell<Option<SimdPath>> = const { Cell::new(None) };
}

/// A ray prepared for 8-wide box tests (origin, safe inverse direction, `t_min`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxRay8 {
    pub org: [f32; 3],
    pub(crate) inv: [f32; 3],
    pub t_min: f32,
}

/// Eight children's boxes, structure of arrays: `min[axis][child]`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Boxes8 {
    pub min: [[f32; 8]; 3],
    pub max: [[f32; 8]; 3],
}

/// One SIMD path's kernels. Implementors are zero-sized tokens: a value exists only on a CPU
/// that runs the path (the intrinsic paths' constructors are private to [`dispatch!`]).
pub(crate) trait Kernel: Copy {
    /// The ray with its per-ray constants in this path's registers.
    type Ray: Copy;
    fn prepare(self, ray: &BoxRay8) -> Self::Ray;
    /// Slab test of eight boxes: bit `i` set when child `i` is entered within `[t_min, t_max]`
    /// (a conservative far bound, `FAR_SCALE`), and each child's entry distance.
    fn box8(self, ray: &Self::Ray, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]);
    /// [`Self::box8`] with `+inf` as the distance of every child missed (packet traversal
    /// takes the minimum over its lanes).
    fn box8_or_inf(self, ray: &Self::Ray, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]);
    /// Runs `f` compiled for this path: a leaf's triangle tests. The leaf closures stay out of
    /// line (a mesh is traversed from two places in one query), so without this they are
    /// compiled for the x86-64 baseline: legacy SSE, where every operation that keeps its
    /// input costs a register copy (compiled for AVX2 they run fewer instructions:
    /// docs/lab/accelerators.md#2026-12-03-embree-counted-too-half-its-instructions-cachegrind).
    fn leaf<R>(self, f: impl FnOnce() -> R) -> R;
    /// [`RayTri::closest_in`] on a leaf's `packets`, as many at once as this path's registers
    /// hold: one on the portable path, two on AVX2 and AVX-512.
    fn closest_tri(self, ray: &RayTri, packets: &[Tri4], t_max: f32) -> Option<(usize, TriHit)>;
    /// [`RayTri::occluded_in`], as [`Self::closest_tri`].
    fn occluded_tri(self, ray: &RayTri, packets: &[Tri4], t_max: f32) -> bool;
}

/// glam's `Vec4`, two halves per node.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Portable;

#[derive(Clone, Copy, Debug)]
pub(crate) struct PortableRay {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    t_min: Vec4,
}

impl Kernel for Portable {
    type Ray = PortableRay;

    #[inline(always)]
    fn prepare(self, r: &BoxRay8) -> PortableRay {
        PortableRay { org: r.org.map(Vec4::splat), inv: r.inv.map(Vec4::splat), t_min: Vec4::splat(r.t_min) }
    }

    #[inline(always)]
    fn box8(self, r: &PortableRay, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
        portable_box8(r, b, t_max, false)
    }

    #[inline(always)]
    fn box8_or_inf(self, r: &PortableRay, b: &Boxes8, t_max: f32) -> (u32, [f32; 8]) {
        portable_box8(r, b, t_max, true)
    }

    #[inline(always)]
    fn leaf<R>(self, f: impl FnOnce() -> R) -> R {
        f()
    }

    #[inline(always)]
    fn closest_tri(self, ray: &RayTri, packets: &[Tri4], t_max: f32) -> Option<(usize, TriHit)> {
        ray.closest_in::<Vec4>(packets, t_max)
    }

    #[inline(always)]
    fn occluded_tri(self, ray: &RayTri, packets: &[Tri4], t_max: f32) -> bool {
        ray.occluded_in::<Vec4>(packets, t_max)
    }
}

/// [`Portable`]'s box test; `inf_missed`: [`Kernel::box8_or_inf`].
#[inline(always)]
fn portable_box8(r: &PortableRay, b: &Boxes8, t_max: f32, inf_missed: bool) -> (u32, [f32; 8]) {
    let half = |h: usize| {
        let lane = |a: &[f32; 8]| Vec4::from_slice(&a[4 * h..4 * h + 4]);
        let t0: [Vec4; 3] = std::array::from_fn(|k| (lane(&b.min[k]) - r.org[k]) * r.inv[k]);
        let t1: [Vec4; 3] = std::array::from_fn(|k| (lane(&b.max[k]) - r.org[k]) * r.inv[k]);
        // The same reduction trees as the x86 paths' `near_far`, so NaN lanes agree too.
        let near = t0[0].min(t1[0]).max(t0[1].min(t1[1])).max(t0[2].min(t1[2]).max(r.t_min));
        let far = (t0[0].max(t1[0]).min(t0[1].max(t1[1])) * FAR_SCALE)
            .min((t0[2].max(t1[2]) * FAR_SCALE).min(Vec4::splat(t_max)));
        let hit = near.cmple(far);
        let near = if inf_missed { Vec4::select(hit, near, Vec4::INFINITY) } else { near };
        (hit.bitmask(), near.to_array())
    };
    let (m0, n0) = half(0);
    let (m1, n1) = half(1);
    (m0 | m1 << 4, [n0[0], n0[1], n0[2], n0[3], n1[0], n1[1], n1[2], n1[3]])
}

/// Runs `$body` with `$k` bound to the current path's kernel token, inside a function compiled
/// for that path (`#[target_feature]`), so the generic traversal `$body` calls is compiled
/// for it too. `$body` must call `#[inline(always)]` code only down to the kernel.
macro_rules! dispatch {
    (|$k:ident| $body:expr) => {{
        match $crate::accel::bvh::simd::SimdPath::current() {
            #[cfg(target_arch = "x86_64")]
            $crate::accel::bvh::simd::SimdPath::Avx512 => {
                #[target_feature(enable = "avx,avx2,fma,avx512f,avx512vl")]
                #[inline]
                fn entry<R>(f: impl FnOnce($crate::accel::bvh::simd::Avx512) -> R) -> R {
                    // SAFETY: reached only when `SimdPath::current()` is Avx512, which it is only
                    // on a CPU that runs it (`SimdPath::is_supported`).
                    f(unsafe { $crate::accel::bvh::simd::Avx512::new_unchecked() })
                }
                // SAFETY: as above: this CPU supports every feature `entry` enables.
                unsafe { entry(|$k| $body) }
            }
            #[cfg(target_arch = "x86_64")]
            $crate::accel::bvh::simd::SimdPath::Avx2 => {
                #[target_feature(enable = "avx,avx2,fma")]
                #[inline]
                fn entry<R>(f: impl FnOnce($crate::accel::bvh::simd::Avx2) -> R) -> R {
                    // SAFETY: reached only when `SimdPath::current()` is Avx2 (see above).
                    f(unsafe { $crate::accel::bvh::simd::Avx2::new_unchecked() })
                }
                // SAFETY: this CPU supports every feature `entry` enables.
                unsafe { entry(|$k| $body) }
            }
            _ => {
                let $k = $crate::accel::bvh::simd::Portable;
                $body
            }
        }
    }};
}
pub(crate) use dispatch;

/// The integer parts of `x`'s lanes, each in `0..2^31`: the BVH builder's bin of a primitive on
/// each axis. On x86-64 one SSE2 conversion for the three lanes ([`x86::truncate3`]); Rust's
/// `as` casts saturate, which costs about a dozen instructions per lane and made the
/// monastery's tree slower to build. Elsewhere the casts.
/// docs/lab/bvh-build.md#2026-12-02-embrees-bin-count-one-sse2-conversion-triangles-stored-once
#[inline(always)]
pub(crate) fn truncate3(x: Vec3A) -> [usize; 3] {
    debug_assert!(x.cmpge(Vec3A::ZERO).all() && x.cmplt(Vec3A::splat(2_147_483_648.0)).all());
    #[cfg(target_arch = "x86_64")]
    {
        x86::truncate3(x)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [x.x as usize, x.y as usize, x.z as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncate3_matches_the_casts() {
        let mut rng = crate::rng::SplitMix64::new(7);
        for _ in 0..10_000 {
            let x = Vec3A::new(rng.unit(), rng.unit(), rng.unit()) * 64.0;
            assert_eq!(truncate3(x), [x.x as usize, x.y as usize, x.z as usize], "{x}");
        }
        for v in [0.0, 0.999_999_9, 1.0, 31.999_998, 32.0, 63.0] {
            let x = Vec3A::splat(v);
            assert_eq!(truncate3(x), [v as usize; 3]);
        }
    }
}
