use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::{Serialize, Serializer};

use super::exact::Exact;
use super::verdict::{judge, Answer, RayVerdict, TriangleKey, Verdict};
use dormant::accel::ObjectMap;
use dormant::accel::{Hit, SceneQuery};
use dormant::geometry::Ray;
use dormant::scene::SceneDescription;

/// A scene to compare, with the map from its hit ids to scene objects and triangles (an
/// integrated scene's ids differ from an all-instanced one's).
#[derive(Clone, Copy)]
pub struct MappedQuery<'a> {
    pub query: &'a dyn SceneQuery,
    pub objects: &'a dyn ObjectMap,
}

impl MappedQuery<'_> {
    /// Both queries for `ray`, the closest hit resolved to its triangle in `desc`.
    pub fn answer(&self, desc: &SceneDescription, ray: &Ray) -> Answer {
        let hit = self.query.intersect(ray);
        let triangle = hit.and_then(|h| {
            let r = self.objects.resolve(h.object, h.prim)?;
            let tri = self.objects.hit_triangle(desc, h.object, h.prim, ray.time)?;
            Some((TriangleKey { mesh: r.mesh, prim: r.prim, body: r.body }, tri))
        });
        Answer { hit, triangle, occluded: self.query.intersect_p(ray) }
    }
}

/// One ray the backends disagree on beyond the bound, with what it takes to debug it.
#[derive(Clone, Debug, Serialize)]
pub struct Mismatch {
    pub ray: usize,
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub t_min: f32,
    pub t_max: f32,
    pub closest: Verdict,
    pub occlusion: Verdict,
    pub reference: Option<HitSummary>,
    pub candidate: Option<HitSummary>,
    /// Each backend's closest hit's triangle re-intersected in f64, with its bounds.
    pub reference_exact: Option<Exact>,
    pub candidate_exact: Option<Exact>,
    /// The any-hit answers, reference then candidate.
    pub occluded: [bool; 2],
}

#[derive(Clone, Debug, Serialize)]
pub struct HitSummary {
    pub t: f32,
    pub object: String,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    /// The scene triangle it resolved to (`None`: the ids are unknown).
    pub triangle: Option<TriangleKey>,
}

impl HitSummary {
    fn new(a: &Answer) -> Option<Self> {
        let h: &Hit = a.hit.as_ref()?;
        Some(Self {
            t: h.t,
            object: format!("{:?}", h.object),
            prim: h.prim,
            u: h.u,
            v: h.v,
            triangle: a.triangle.map(|(k, _)| k),
        })
    }
}

/// Verdicts on one query over many rays: how many of each, and why.
#[derive(Clone, Debug, Default)]
pub struct VerdictCounts(BTreeMap<Verdict, u64>);

impl VerdictCounts {
    fn add(&mut self, v: Verdict) {
        *self.0.entry(v).or_default() += 1;
    }

    fn merge(&mut self, other: VerdictCounts) {
        for (v, n) in other.0 {
            *self.0.entry(v).or_default() += n;
        }
    }

    /// Rays with this verdict kind (`agree`, `tie`, `mismatch`).
    pub fn count(&self, kind: &str) -> u64 {
        self.0.iter().filter(|(v, _)| v.kind() == kind).map(|(_, n)| n).sum()
    }
}

/// `{"agree": n, "tie": n, "mismatch": n, "reasons": {"tie": {"edge": n, ...}, ...}}`.
impl Serialize for VerdictCounts {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut reasons: BTreeMap<&str, BTreeMap<String, u64>> = BTreeMap::new();
        for (v, n) in &self.0 {
            for r in v.reasons() {
                *reasons.entry(v.kind()).or_default().entry(r).or_default() += n;
            }
        }
        let mut out = serde_json::Map::new();
        for kind in ["agree", "tie", "mismatch"] {
            out.insert(kind.into(), self.count(kind).into());
        }
        out.insert("reasons".into(), serde_json::to_value(reasons).map_err(serde::ser::Error::custom)?);
        out.serialize(s)
    }
}

/// The outcome of [`compare`]. Its JSON fields are documented in docs/crosscheck.md.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VerifyReport {
    pub rays: u64,
    /// Rays both backends hit (closest hit).
    pub hits: u64,
    /// Rays neither backend hit.
    pub misses: u64,
    /// Rays with a mismatch in either query.
    pub mismatches: u64,
    /// Rays with a tie in either query and no mismatch.
    pub ties: u64,
    pub closest: VerdictCounts,
    pub occlusion: VerdictCounts,
    /// Largest `|t - t_f64| / t_bound` over every hit either backend reported.
    pub max_t_err_over_bound: f64,
    /// Largest `|t_a - t_b| / max(1, t)` over rays where both hit the same triangle.
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
        self.closest.merge(other.closest);
        self.occlusion.merge(other.occlusion);
        self.max_t_err_over_bound = self.max_t_err_over_bound.max(other.max_t_err_over_bound);
        self.max_t_rel_err = self.max_t_rel_err.max(other.max_t_rel_err);
        let room = Self::EXAMPLES.saturating_sub(self.examples.len());
        self.examples.extend(other.examples.into_iter().take(room));
    }

    /// Counts one ray's verdicts.
    fn record(&mut self, i: usize, ray: &Ray, answers: [&Answer; 2], v: &RayVerdict) {
        let [a, b] = answers;
        self.rays += 1;
        match (&a.hit, &b.hit) {
            (Some(x), Some(y)) => {
                self.hits += 1;
                if a.triangle.map(|t| t.0) == b.triangle.map(|t| t.0) {
                    self.max_t_rel_err = self.max_t_rel_err.max((x.t - y.t).abs() / x.t.abs().max(1.0));
                }
            }
            (None, None) => self.misses += 1,
            _ => {}
        }
        for (answer, exact) in answers.iter().zip(&v.exact) {
            if let (Some(h), Some(e)) = (&answer.hit, exact) {
                self.max_t_err_over_bound = self.max_t_err_over_bound.max(e.t_error_over_bound(h.t));
            }
        }
        self.closest.add(v.closest);
        self.occlusion.add(v.occlusion);
        let kinds = [v.closest.kind(), v.occlusion.kind()];
        if kinds.contains(&"mismatch") {
            self.mismatches += 1;
            if self.examples.len() < Self::EXAMPLES {
                self.examples.push(Mismatch {
                    ray: i,
                    origin: ray.origin.to_array(),
                    dir: ray.dir.to_array(),
                    t_min: ray.t_min,
                    t_max: ray.t_max,
                    closest: v.closest,
                    occlusion: v.occlusion,
                    reference: HitSummary::new(a),
                    candidate: HitSummary::new(b),
                    reference_exact: v.exact[0],
                    candidate_exact: v.exact[1],
                    occluded: [a.occluded, b.occluded],
                });
            }
        } else if kinds.contains(&"tie") {
            self.ties += 1;
        }
    }
}

/// Traces every ray through both scenes (closest hit and any hit), both showing `desc`, and
/// judges the answers against f64 re-intersections of the triangles they hit ([`judge`]).
pub fn compare(
    desc: &SceneDescription,
    reference: MappedQuery<'_>,
    candidate: MappedQuery<'_>,
    rays: &[Ray],
) -> VerifyReport {
    rays.par_iter()
        .enumerate()
        .fold(VerifyReport::default, |mut report, (i, ray)| {
            let a = reference.answer(desc, ray);
            let b = candidate.answer(desc, ray);
            let verdict = judge(ray, &a, &b);
            report.record(i, ray, [&a, &b], &verdict);
            report
        })
        .reduce(VerifyReport::default, |mut a, b| {
            a.merge(b);
            a
        })
}
