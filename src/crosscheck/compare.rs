use rayon::prelude::*;
use serde::Serialize;

use crate::accel::{Hit, HitObject, SceneQuery};
use crate::geometry::Ray;
use crate::integrate::{MeshRef, ObjectMap};
use crate::physics::BodyId;

/// When two answers count as the same.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Tolerance {
    /// Hits agree when `|t_a - t_b| <= t_rel * max(1, t)`.
    pub t_rel: f32,
    /// A hit closer than this (in barycentric units) to a triangle edge may be missed or
    /// claimed by a neighbour: a tie, not a mismatch. Embree's default triangle test is not
    /// watertight, so it can miss such hits by a few ulps, which is up to ~1e-3 in barycentric
    /// terms for small triangles far from the origin.
    pub edge: f32,
    /// Same triangle, but `t` differs by more than `t_rel * max(1, t)`: still a precision tie
    /// when within `t_rel * max(1, t, |origin|)`. f32 instance transforms lose precision in
    /// proportion to the coordinates' magnitude; an f64 analysis of the monastery's such rays
    /// showed Embree's `t` off by 1e-4 where the BVH's was off by 3e-7.
    pub origin_scaled: bool,
}

impl Default for Tolerance {
    fn default() -> Self {
        Self { t_rel: 1e-4, edge: 1e-3, origin_scaled: true }
    }
}

/// One ray the backends disagree on.
#[derive(Clone, Debug, Serialize)]
pub struct Mismatch {
    pub ray: usize,
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub reference: Option<HitSummary>,
    pub candidate: Option<HitSummary>,
    pub occlusion: Option<[bool; 2]>,
}

#[derive(Clone, Debug, Serialize)]
pub struct HitSummary {
    pub t: f32,
    pub object: String,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

impl From<&Hit> for HitSummary {
    fn from(h: &Hit) -> Self {
        Self { t: h.t, object: format!("{:?}", h.object), prim: h.prim, u: h.u, v: h.v }
    }
}

/// The outcome of [`compare`].
#[derive(Clone, Debug, Default, Serialize)]
pub struct VerifyReport {
    pub rays: u64,
    /// Rays both backends hit (closest hit).
    pub hits: u64,
    pub misses: u64,
    pub mismatches: u64,
    /// Coincident or edge-shared triangles: different answers that are both right.
    pub ties: u64,
    /// Same triangle with `t` within the origin-scaled tolerance only (see [`Tolerance`]).
    pub precision_ties: u64,
    /// Largest `|t_a - t_b| / max(1, t, |origin|)` over precision ties.
    pub max_precision_err: f32,
    /// Largest `|t_a - t_b| / max(1, t)` over rays whose hits agree.
    pub max_t_rel_err: f32,
    /// The first few mismatches, for diagnosis.
    pub examples: Vec<Mismatch>,
}

impl VerifyReport {
    const EXAMPLES: usize = 20;

    /// Folds another report into this one.
    pub fn merge(&mut self, other: VerifyReport) {
        self.rays += other.rays;
        self.hits += other.hits;
        self.misses += other.misses;
        self.mismatches += other.mismatches;
        self.ties += other.ties;
        self.precision_ties += other.precision_ties;
        self.max_precision_err = self.max_precision_err.max(other.max_precision_err);
        self.max_t_rel_err = self.max_t_rel_err.max(other.max_t_rel_err);
        let room = Self::EXAMPLES.saturating_sub(self.examples.len());
        self.examples.extend(other.examples.into_iter().take(room));
    }
}

enum Verdict {
    Agree { both_hit: bool, t_rel: f32 },
    Tie,
    PrecisionTie { err: f32 },
    Mismatch,
}

fn near_edge(h: &Hit, eps: f32) -> bool {
    h.u.min(h.v).min(1.0 - h.u - h.v) <= eps
}

/// Whether `h` lies at the start of `ray` within float precision at the origin's magnitude.
fn at_origin(ray: &Ray, h: &Hit, tol: &Tolerance) -> bool {
    h.t - ray.t_min <= tol.t_rel * ray.origin.abs().max_element().max(1.0)
}

/// What a hit is on, for deciding whether two hits are on the same triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum HitKey {
    /// The accelerator's own id (scenes loaded the same way).
    Raw(HitObject, u32),
    /// A body's prototype triangle, or an environment triangle, after mapping.
    Body(BodyId, u32),
    Mesh(MeshRef, u32),
    Unknown,
}

/// A scene to compare, with the map from its hit ids to scene objects when its ids differ from
/// the other side's (an integrated scene against an all-instanced one).
#[derive(Clone, Copy)]
pub struct MappedQuery<'a> {
    pub query: &'a dyn SceneQuery,
    pub objects: Option<&'a dyn ObjectMap>,
}

impl MappedQuery<'_> {
    fn key(&self, h: &Hit) -> HitKey {
        let Some(map) = self.objects else {
            return HitKey::Raw(h.object, h.prim);
        };
        match map.resolve(h.object, h.prim) {
            Some(r) => match r.body {
                Some(body) => HitKey::Body(body, r.prim),
                None => HitKey::Mesh(r.mesh, r.prim),
            },
            None => HitKey::Unknown,
        }
    }
}

fn classify(ray: &Ray, a: Option<&Hit>, b: Option<&Hit>, same_triangle: bool, tol: &Tolerance) -> Verdict {
    match (a, b) {
        (None, None) => Verdict::Agree { both_hit: false, t_rel: 0.0 },
        (Some(a), Some(b)) => {
            let dt = (a.t - b.t).abs();
            let t_rel = dt / a.t.abs().max(1.0);
            let same_t = t_rel <= tol.t_rel;
            if same_triangle {
                let scale = a.t.abs().max(1.0).max(ray.origin.abs().max_element());
                if same_t {
                    Verdict::Agree { both_hit: true, t_rel }
                } else if tol.origin_scaled && dt / scale <= tol.t_rel {
                    Verdict::PrecisionTie { err: dt / scale }
                } else {
                    Verdict::Mismatch
                }
            } else if same_t {
                // Coincident faces, or an edge or vertex shared by two triangles.
                Verdict::Tie
            } else {
                // One backend slipped past the nearer triangle's edge and hit something behind,
                // or the nearer hit is at the ray's origin (a ray leaving a surface that touches
                // or slightly penetrates another body), where rounding decides.
                let nearer = if a.t < b.t { a } else { b };
                if near_edge(nearer, tol.edge) || at_origin(ray, nearer, tol) {
                    Verdict::Tie
                } else {
                    Verdict::Mismatch
                }
            }
        }
        (Some(h), None) | (None, Some(h)) => {
            if near_edge(h, tol.edge) || at_origin(ray, h, tol) {
                Verdict::Tie
            } else {
                Verdict::Mismatch
            }
        }
    }
}

/// Traces every ray through both scenes (closest hit and any hit) and classifies the answers.
/// Hits are on the same triangle when they have the same object and primitive ids.
pub fn compare(
    reference: &dyn SceneQuery,
    candidate: &dyn SceneQuery,
    rays: &[Ray],
    tol: &Tolerance,
) -> VerifyReport {
    compare_mapped(
        MappedQuery { query: reference, objects: None },
        MappedQuery { query: candidate, objects: None },
        rays,
        tol,
    )
}

/// Like [`compare`], with hits identified through each side's object map: the same body and
/// prototype triangle (or environment triangle) whether instanced or baked.
pub fn compare_mapped(
    reference: MappedQuery<'_>,
    candidate: MappedQuery<'_>,
    rays: &[Ray],
    tol: &Tolerance,
) -> VerifyReport {
    let (ra, rb) = (reference, candidate);
    let (reference, candidate) = (ra.query, rb.query);
    rays.par_iter()
        .enumerate()
        .fold(VerifyReport::default, |mut report, (i, ray)| {
            let a = reference.intersect(ray);
            let b = candidate.intersect(ray);
            let same = match (&a, &b) {
                (Some(x), Some(y)) => {
                    let (kx, ky) = (ra.key(x), rb.key(y));
                    kx == ky && kx != HitKey::Unknown
                }
                _ => false,
            };
            let mut verdict = classify(ray, a.as_ref(), b.as_ref(), same, tol);
            // Any-hit must agree with closest-hit existence, except at ties.
            let occ = [reference.intersect_p(ray), candidate.intersect_p(ray)];
            let occlusion_differs = occ[0] != occ[1] || occ[0] != a.is_some() || occ[1] != b.is_some();
            if occlusion_differs && matches!(verdict, Verdict::Agree { .. } | Verdict::PrecisionTie { .. }) {
                let edge = a.iter().chain(b.iter()).any(|h| near_edge(h, tol.edge));
                verdict = if edge { Verdict::Tie } else { Verdict::Mismatch };
            }
            report.rays += 1;
            match verdict {
                Verdict::Agree { both_hit, t_rel } => {
                    if both_hit {
                        report.hits += 1;
                        report.max_t_rel_err = report.max_t_rel_err.max(t_rel);
                    } else {
                        report.misses += 1;
                    }
                }
                Verdict::Tie => report.ties += 1,
                Verdict::PrecisionTie { err } => {
                    report.precision_ties += 1;
                    report.max_precision_err = report.max_precision_err.max(err);
                }
                Verdict::Mismatch => {
                    report.mismatches += 1;
                    if report.examples.len() < VerifyReport::EXAMPLES {
                        report.examples.push(Mismatch {
                            ray: i,
                            origin: ray.origin.to_array(),
                            dir: ray.dir.to_array(),
                            reference: a.as_ref().map(HitSummary::from),
                            candidate: b.as_ref().map(HitSummary::from),
                            occlusion: occlusion_differs.then_some(occ),
                        });
                    }
                }
            }
            report
        })
        .reduce(VerifyReport::default, |mut a, b| {
            a.merge(b);
            a
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{HitObject, StaticId};
    use glam::Vec3;

    fn hit(t: f32, object: u32, prim: u32, u: f32, v: f32) -> Hit {
        Hit { t, u, v, ng: Vec3::Z, object: HitObject::Static(StaticId(object)), prim }
    }

    #[test]
    fn verdicts() {
        let tol = Tolerance::default();
        let near = Ray::new(Vec3::ZERO, Vec3::X);
        let far = Ray::new(Vec3::splat(40.0), Vec3::X);
        let a = hit(10.0, 0, 3, 0.3, 0.3);
        let c = |r: &Ray, x: Option<&Hit>, y: Option<&Hit>| {
            let same = x.zip(y).is_some_and(|(x, y)| (x.object, x.prim) == (y.object, y.prim));
            classify(r, x, y, same, &tol)
        };
        assert!(matches!(c(&near, Some(&a), Some(&hit(10.0005, 0, 3, 0.3, 0.3))), Verdict::Agree { .. }));
        assert!(matches!(c(&near, Some(&a), Some(&hit(10.1, 0, 3, 0.3, 0.3))), Verdict::Mismatch));
        assert!(matches!(c(&near, Some(&a), Some(&hit(10.0, 0, 4, 0.0, 0.5))), Verdict::Tie));
        assert!(matches!(c(&near, Some(&a), None), Verdict::Mismatch));
        assert!(matches!(c(&near, Some(&hit(2.0, 0, 0, 0.5, 0.4995)), None), Verdict::Tie));
        assert!(matches!(c(&near, None, None), Verdict::Agree { both_hit: false, .. }));
        // A nearer hit at an edge that the other backend slipped past.
        assert!(matches!(c(&near, Some(&a), Some(&hit(9.0, 0, 7, 0.0002, 0.5))), Verdict::Tie));
        assert!(matches!(c(&near, Some(&a), Some(&hit(9.0, 0, 7, 0.2, 0.5))), Verdict::Mismatch));
        // A hit at the ray's origin (touching bodies) against a farther one or a miss.
        assert!(matches!(c(&far, Some(&a), Some(&hit(0.0, 0, 7, 0.2, 0.5))), Verdict::Tie));
        assert!(matches!(c(&near, None, Some(&hit(1e-5, 0, 7, 0.2, 0.5))), Verdict::Tie));
        // Same triangle, t off by 3e-4 absolute at t = 0.04: precision-limited 40 units out.
        let (p, q) = (hit(0.0390, 1, 2, 0.3, 0.3), hit(0.0393, 1, 2, 0.3, 0.3));
        assert!(matches!(c(&near, Some(&p), Some(&q)), Verdict::Mismatch));
        assert!(matches!(c(&far, Some(&p), Some(&q)), Verdict::PrecisionTie { .. }));
    }
}
