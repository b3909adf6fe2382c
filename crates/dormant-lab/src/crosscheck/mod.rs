//! Cross-checking accelerators: the same rays through two backends, each disagreement judged
//! against an f64 re-intersection of the triangles hit: agreements, ties (different answers
//! both right within the f32 error bound) and mismatches (one wrong beyond it). The bound and
//! the rules are in docs/crosscheck.md. `dormant verify` is built on this.

mod compare;
mod exact;
mod rays;
mod verdict;

pub use compare::{compare, HitSummary, MappedQuery, Mismatch, VerdictCounts, VerifyReport};
pub use exact::{reintersect, BoundConstants, Exact, BOUND, UNIT_ROUNDOFF};
pub use rays::{camera_rays, shadow_rays, surface_rays, with_random_times};
pub use verdict::{judge, AgreeReason, Answer, Fault, RayVerdict, TieReason, TriangleKey, Verdict};
