//! Verdicts on one ray's answers from two backends, decided against the f64 re-intersection of
//! the triangles they hit ([`super::exact`]): agree, tie (both right within the f32 error
//! bound) or mismatch (one is wrong beyond it), each with its reason. The rules are in
//! docs/crosscheck.md, "Verdicts".

use serde::Serialize;

use super::exact::{reintersect, Exact};
use dormant::accel::Hit;
use dormant::accel::{HitTriangle, MeshRef};
use dormant::geometry::Ray;
use dormant::physics::BodyId;

/// What a hit is on in scene terms: the same for a body whether instanced or baked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct TriangleKey {
    pub mesh: MeshRef,
    pub prim: u32,
    pub body: Option<BodyId>,
}

/// One backend's answers for one ray: the closest hit (with its triangle, resolved through the
/// backend's object map; `None` for ids the map does not know) and the any-hit answer.
#[derive(Clone, Copy, Debug)]
pub struct Answer {
    pub hit: Option<Hit>,
    pub triangle: Option<(TriangleKey, HitTriangle)>,
    pub occluded: bool,
}

/// Why two answers agree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AgreeReason {
    /// The same answer (both miss, or the same triangle at the same `t`; the same occlusion).
    Identical,
    /// The same triangle, `t` different but each within its bound of the f64 `t`.
    SameTriangle,
}

/// Why two different answers are both right within the bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TieReason {
    /// Different triangles whose f64 `t` differ by at most the sum of their bounds.
    Coincident,
    /// The hit one backend has and the other lacks is within the bound of a triangle edge.
    Edge,
    /// ... or within the bound of an end of the ray's interval (`t_min`: touching bodies).
    IntervalEnd,
    /// The ray runs parallel to the triangle's plane in f64: no bound holds, nothing decides.
    Grazing,
}

/// How one backend's answer is wrong beyond the bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Fault {
    /// Its hit's ids resolve to no triangle.
    UnknownTriangle,
    /// Its hit lies outside its triangle by more than the edge bound.
    HitOffTriangle,
    /// Its hit's f64 `t` lies outside `[t_min, t_max]` by more than the bound.
    HitOutsideInterval,
    /// Its `t` differs from the f64 `t` of its triangle by more than the bound.
    TBeyondBound,
    /// The other backend's triangle is surely hit, nearer by more than both bounds.
    MissedNearerHit,
    /// It reports no hit; the other backend's triangle is surely hit.
    MissedHit,
    /// It reports the ray unoccluded; a triangle either backend hit surely blocks it.
    MissedBlocker,
    /// It reports the ray occluded; neither backend's closest hit found anything.
    OccludedWithoutHit,
    /// It reports the ray occluded; every hit found lies surely off its triangle or interval.
    BlockerOutside,
}

/// The verdict on one query (closest hit or occlusion) of one ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Agree(AgreeReason),
    Tie(TieReason),
    /// The fault of each backend that is wrong (at least one).
    Mismatch {
        reference: Option<Fault>,
        candidate: Option<Fault>,
    },
}

/// Both verdicts on one ray, with the f64 re-intersections of the hits they judged.
#[derive(Clone, Copy, Debug)]
pub struct RayVerdict {
    pub closest: Verdict,
    pub occlusion: Verdict,
    /// The re-intersection of each backend's closest hit's triangle.
    pub exact: [Option<Exact>; 2],
}

/// An answer with its triangle re-intersected.
struct Judged<'a> {
    answer: &'a Answer,
    exact: Option<Exact>,
}

impl Judged<'_> {
    fn key(&self) -> Option<TriangleKey> {
        self.answer.triangle.map(|(k, _)| k)
    }

    /// The hit's triangle is surely hit within the interval.
    fn surely_hit(&self, ray: &Ray) -> bool {
        self.answer.hit.is_some() && self.exact.is_some_and(|e| e.surely_hit(ray))
    }
}

/// Judges both queries of `ray` from the two backends' answers.
pub fn judge(ray: &Ray, reference: &Answer, candidate: &Answer) -> RayVerdict {
    let exact = |a: &Answer| a.hit.and(a.triangle).and_then(|(_, tri)| reintersect(ray, &tri));
    let a = Judged { answer: reference, exact: exact(reference) };
    let b = Judged { answer: candidate, exact: exact(candidate) };
    RayVerdict { closest: closest(ray, &a, &b), occlusion: occlusion(ray, &a, &b), exact: [a.exact, b.exact] }
}

fn mismatch(reference: Option<Fault>, candidate: Option<Fault>) -> Option<Verdict> {
    (reference.is_some() || candidate.is_some()).then_some(Verdict::Mismatch { reference, candidate })
}

/// What is wrong with `x`'s closest hit, given `y`'s.
fn closest_fault(ray: &Ray, x: &Judged<'_>, y: &Judged<'_>) -> Option<Fault> {
    let Some(hit) = x.answer.hit else {
        return y.surely_hit(ray).then_some(Fault::MissedHit);
    };
    if x.answer.triangle.is_none() {
        return Some(Fault::UnknownTriangle);
    }
    if let Some(e) = &x.exact {
        if e.surely_outside() {
            return Some(Fault::HitOffTriangle);
        }
        if e.surely_beyond(ray) {
            return Some(Fault::HitOutsideInterval);
        }
        if e.t_error_over_bound(hit.t) > 1.0 {
            return Some(Fault::TBeyondBound);
        }
    }
    if y.key() != x.key() && y.surely_hit(ray) {
        let ey = y.exact.as_ref()?;
        let x_nearest = x.exact.map_or(f64::from(hit.t), |e| e.t - e.t_bound);
        if ey.t + ey.t_bound < x_nearest {
            return Some(Fault::MissedNearerHit);
        }
    }
    None
}

/// Why a hit that one backend has and the other lacks (or has farther) may be missed.
fn excuse(ray: &Ray, e: Option<&Exact>) -> TieReason {
    match e {
        Some(e) if !e.surely_inside() => TieReason::Edge,
        Some(e) if !e.surely_within(ray) => TieReason::IntervalEnd,
        _ => TieReason::Grazing,
    }
}

fn closest(ray: &Ray, a: &Judged<'_>, b: &Judged<'_>) -> Verdict {
    let (ha, hb) = (a.answer.hit, b.answer.hit);
    if ha.is_none() && hb.is_none() {
        return Verdict::Agree(AgreeReason::Identical);
    }
    if let Some(v) = mismatch(closest_fault(ray, a, b), closest_fault(ray, b, a)) {
        return v;
    }
    if ha.is_some() && hb.is_some() && a.key() == b.key() {
        let identical = ha.map(|h| h.t) == hb.map(|h| h.t);
        return Verdict::Agree(if identical { AgreeReason::Identical } else { AgreeReason::SameTriangle });
    }
    match (&a.exact, &b.exact) {
        (Some(ea), Some(eb)) if ha.is_some() && hb.is_some() => {
            if (ea.t - eb.t).abs() <= ea.t_bound + eb.t_bound {
                Verdict::Tie(TieReason::Coincident)
            } else {
                Verdict::Tie(excuse(ray, Some(if ea.t < eb.t { ea } else { eb })))
            }
        }
        _ => {
            // One hit (the other side missed), or a grazing one.
            let only =
                if ha.is_some() && hb.is_some() { None } else { a.exact.as_ref().or(b.exact.as_ref()) };
            Verdict::Tie(excuse(ray, only))
        }
    }
}

fn occlusion(ray: &Ray, a: &Judged<'_>, b: &Judged<'_>) -> Verdict {
    let (oa, ob) = (a.answer.occluded, b.answer.occluded);
    let hits = [a, b].into_iter().filter(|x| x.answer.hit.is_some());
    if !oa && !ob && hits.clone().next().is_none() {
        return Verdict::Agree(AgreeReason::Identical);
    }
    let surely_blocked = hits.clone().any(|x| x.surely_hit(ray));
    // A grazing hit (no bound) might block.
    let maybe_blocked =
        hits.clone().any(|x| x.exact.is_none_or(|e| !e.surely_outside() && !e.surely_beyond(ray)));
    let any_hit = hits.clone().next().is_some();
    let fault = |occluded: bool| {
        if !occluded && surely_blocked {
            Some(Fault::MissedBlocker)
        } else if occluded && !any_hit {
            Some(Fault::OccludedWithoutHit)
        } else if occluded && !maybe_blocked {
            Some(Fault::BlockerOutside)
        } else {
            None
        }
    };
    if let Some(v) = mismatch(fault(oa), fault(ob)) {
        return v;
    }
    if oa == ob {
        return Verdict::Agree(AgreeReason::Identical);
    }
    // Neither surely blocks: the blocker is near an edge or an end of the interval.
    let edge = hits.clone().any(|x| x.exact.is_some_and(|e| !e.surely_inside()));
    let end = hits.clone().any(|x| x.exact.is_some_and(|e| !e.surely_within(ray)));
    Verdict::Tie(if edge {
        TieReason::Edge
    } else if end {
        TieReason::IntervalEnd
    } else {
        TieReason::Grazing
    })
}

impl Verdict {
    /// `agree`, `tie` or `mismatch`, for counting.
    pub fn kind(&self) -> &'static str {
        match self {
            Verdict::Agree(_) => "agree",
            Verdict::Tie(_) => "tie",
            Verdict::Mismatch { .. } => "mismatch",
        }
    }

    /// The reasons, by their JSON names (a mismatch names each wrong side's fault:
    /// `reference_missed_hit`); for reports, not per ray.
    pub fn reasons(&self) -> Vec<String> {
        fn name(v: impl Serialize) -> String {
            serde_json::to_value(v).ok().and_then(|v| v.as_str().map(str::to_owned)).unwrap_or_default()
        }
        match self {
            Verdict::Agree(r) => vec![name(r)],
            Verdict::Tie(r) => vec![name(r)],
            Verdict::Mismatch { reference, candidate } => reference
                .iter()
                .map(|f| format!("reference_{}", name(f)))
                .chain(candidate.iter().map(|f| format!("candidate_{}", name(f))))
                .collect(),
        }
    }
}
