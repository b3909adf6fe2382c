//! Stage 2, integrate: admits sleeping islands into residence. The policy (and under `auto`
//! the cost model) picks them; they go into the static scene baked, or into the resting scene
//! as instances.

use std::sync::Arc;
use std::time::Instant;

use super::reactivate::triangles_in;
use super::slots::{InstanceOwner, Integrated, Placement, StaticOwner};
use super::{ms, Decision, FrameStats, SceneManager};
use crate::accel::AccelError;
use crate::physics::trajectory::ReplayFrame;
use crate::physics::IslandId;
use crate::residency::baked::BakedIsland;
use crate::residency::cost_model::{choose_batch, Candidate, CostEstimate, Outlook, Situation};
use crate::residency::policy::IntegrationPolicy;
use crate::residency::IntegrationForm;

/// A candidate island and what was decided about it.
struct Considered {
    island: IslandId,
    candidate: Candidate,
    estimate: Option<CostEstimate>,
}

/// A candidate, whether to integrate it, and whether the decision is recorded (an island is
/// recorded when integrated, and when first declined).
type Verdict = (Considered, bool, bool);

impl SceneManager {
    /// Returns whether anything was integrated. `decided`: an earlier run's decisions for this
    /// frame (island, integrated), made again instead of asking the policy.
    pub(super) fn integrate(
        &mut self,
        frame: &ReplayFrame<'_>,
        decided: Option<&[(IslandId, bool)]>,
        stats: &mut FrameStats,
    ) -> Result<bool, AccelError> {
        if self.options.policy == IntegrationPolicy::Never {
            return Ok(false);
        }
        // Every sleeping island integrated (those that woke left in stage 1), as in a settled
        // shot: nothing to decide, and no outlook to price (it sorts every sleep so far).
        debug_assert!(self.integrated_islands().all(|i| self.sleeping.contains_key(&i)));
        if self.sleeping.len() == self.integrated.len() + self.resting.len() {
            return Ok(false);
        }
        let verdicts = match decided {
            Some(decided) => self
                .consider(frame, None)
                .into_iter()
                .map(|c| {
                    let recorded = decided.iter().find(|(island, _)| *island == c.island);
                    (c, recorded.is_some_and(|r| r.1), recorded.is_some())
                })
                .collect(),
            None => match self.policy_verdicts(frame) {
                Some(verdicts) => verdicts,
                None => return Ok(false),
            },
        };
        let mut chosen = Vec::new();
        for (c, integrate, record) in verdicts {
            if record {
                stats.decisions.push(Decision {
                    island: c.island,
                    bodies: c.candidate.bodies,
                    triangles: c.candidate.triangles,
                    age: c.candidate.age,
                    integrate,
                    estimate: c.estimate,
                });
                self.sleeping.get_mut(&c.island).expect("candidate is asleep").decided = true;
            }
            if integrate {
                chosen.push(c.island);
            }
        }
        if chosen.is_empty() {
            return Ok(false);
        }
        let moved: usize = chosen.iter().map(|i| self.sleeping[i].bodies.len()).sum();
        let present = frame.present_count();
        self.probe.start(self.options.form, moved, present, self.resting.is_empty(), self.accel.query().ok());
        match self.options.form {
            IntegrationForm::Baked => self.bake_islands(&chosen, stats)?,
            IntegrationForm::Resting => self.rest_islands(&chosen, stats)?,
        }
        Ok(true)
    }

    /// What the policy decides about each candidate this frame; `None` when `auto` cannot
    /// price a decision yet.
    fn policy_verdicts(&mut self, frame: &ReplayFrame<'_>) -> Option<Vec<Verdict>> {
        // `auto` prices the trace penalty in trace time, unknown before a frame was traced: the
        // probe's rays, scaled to the frame's samples, stand in until then (priced at 0 or
        // waited for, the first frames lost):
        // docs/lab/integration.md#2026-12-01-the-cost-models-priors-and-its-first-frame
        if self.options.policy == IntegrationPolicy::Auto && !self.cost.knows_trace() {
            match self.accel.query().ok().and_then(|q| self.probe.frame_trace_estimate(q)) {
                Some(ms) => self.cost.assume_trace(ms),
                None => return None,
            }
        }
        let outlook = (self.options.policy == IntegrationPolicy::Auto).then(|| self.outlook(frame));
        let considered = self.consider(frame, outlook.as_ref());
        let accept = match &outlook {
            Some(outlook) => {
                let estimates: Vec<CostEstimate> = considered.iter().filter_map(|c| c.estimate).collect();
                let positive: Vec<CostEstimate> =
                    estimates.iter().copied().filter(|e| e.net_ms() > 0.0).collect();
                choose_batch(&estimates, outlook.fixed_ms(&positive))
            }
            None => vec![true; considered.len()],
        };
        let verdicts = considered
            .into_iter()
            .zip(accept)
            .map(|(c, integrate)| {
                let record = integrate || !self.sleeping[&c.island].decided;
                (c, integrate, record)
            })
            .collect();
        Some(verdicts)
    }

    /// The sleeping islands not integrated yet, with the cost model's estimate under `auto`.
    fn consider(&self, frame: &ReplayFrame<'_>, outlook: Option<&Outlook>) -> Vec<Considered> {
        let lookahead = self.options.lookahead.as_deref();
        let mut considered = Vec::new();
        for (island, s) in &self.sleeping {
            if self.is_integrated(island) {
                continue;
            }
            // Baking waits until the island is chosen: the decision only needs its size.
            let triangles: usize = s
                .bodies
                .iter()
                .map(|b| self.prototypes[self.bodies[b.0 as usize].prototype as usize].triangle_count())
                .sum();
            let candidate = Candidate {
                bodies: s.bodies.len(),
                triangles,
                age: self.rendered - s.slept_at,
                remaining: lookahead.map(|l| l.remaining_sleep(*island, frame.index)),
            };
            let estimate = outlook.map(|o| o.estimate(&candidate));
            considered.push(Considered { island: *island, candidate, estimate });
        }
        considered
    }

    /// The cost model's outlook for this frame.
    fn outlook(&self, frame: &ReplayFrame<'_>) -> Outlook {
        let frames_left = match (&self.options.lookahead, self.options.planned_frames) {
            (Some(l), _) => f64::from(l.frames_left(frame.index)),
            (None, Some(n)) => f64::from(n.saturating_sub(self.rendered)),
            (None, None) => f64::INFINITY,
        };
        let situation = Situation {
            form: self.options.form,
            present_bodies: frame.present_count(),
            resting_instances: self.resting.values().map(Vec::len).sum(),
            frames_left,
        };
        self.cost.outlook(situation, self.sleeping.values().map(|s| f64::from(self.rendered - s.slept_at)))
    }

    /// Moves `chosen`'s bodies into the resting scene as instances at the poses they fell
    /// asleep in, then rebuilds the resting scene.
    fn rest_islands(&mut self, chosen: &[IslandId], stats: &mut FrameStats) -> Result<(), AccelError> {
        for island in chosen {
            let s = &self.sleeping[island];
            for (b, pose) in s.bodies.iter().zip(&s.poses) {
                let slot = &mut self.bodies[b.0 as usize];
                let xf = pose.to_affine();
                let id = match slot.placement {
                    Placement::Instance { id, pose: old } => {
                        if old != *pose {
                            self.accel.set_instance_transform(id, xf)?;
                        }
                        id
                    }
                    _ => self.accel.add_instance(self.prototype_ids[slot.prototype as usize], xf)?,
                };
                self.accel.set_instance_resting(id, true)?;
                self.instance_owner.set(id, Some(InstanceOwner::at(*b, slot.prototype, xf, true)));
                slot.placement = Placement::Resting { island: *island, id, pose: *pose };
            }
            self.touched.extend(s.bodies.iter().map(|b| b.0 as usize));
            self.resting.insert(*island, s.bodies.clone());
            stats.islands_integrated += 1;
        }
        self.commit_static_timed(stats)
    }

    /// Bakes `chosen` into the static scene and takes their bodies out of the top level.
    fn bake_islands(&mut self, chosen: &[IslandId], stats: &mut FrameStats) -> Result<(), AccelError> {
        // With snapshots, each island goes in with its own static build, so the cache can
        // record the scene before it; without (Embree), one build takes them all and the cache
        // records key-only entries: it answers lookups but never restores (docs/design.md).
        let per_island = self.pristine.snapshot.is_some() && self.cache.is_some();
        let (mut batch, mut t) = (0, Instant::now());
        for island in chosen {
            let s = &self.sleeping[island];
            let bodies: Vec<_> = s
                .bodies
                .iter()
                .zip(&s.poses)
                .map(|(b, p)| (*b, self.bodies[b.0 as usize].prototype, *p))
                .collect();
            let baked = Arc::new(BakedIsland::bake(&bodies, &self.prototypes));
            if self.cache.is_some() {
                self.record_in_cache();
                if per_island {
                    t = Instant::now();
                }
            }
            let id = self.accel.add_static(&baked.mesh)?;
            if self.options.lookahead.as_ref().is_some_and(|l| l.wake_frame(*island).is_none()) {
                self.accel.set_static_permanent(id);
            }
            for part in &baked.parts {
                let slot = &mut self.bodies[part.body.0 as usize];
                if let Placement::Instance { id, .. } = slot.placement {
                    self.accel.remove_instance(id)?;
                    self.instance_owner.set(id, None);
                }
                slot.placement = Placement::Baked(*island);
            }
            self.touched.extend(baked.parts.iter().map(|p| p.body.0 as usize));
            self.static_owner.insert(id, StaticOwner::Island(baked.clone()));
            stats.built_triangles += baked.triangle_count();
            batch += baked.triangle_count();
            self.integrated.insert(*island, Integrated { id, baked });
            stats.islands_integrated += 1;
            if per_island {
                // A commit may also merge blocks (the BVH's relink): count what it built.
                let built = self.accel.commit_static()?.built_triangles;
                self.cost.record_build(built.max(batch), ms(t));
                batch = 0;
            }
        }
        if !per_island {
            let built = self.accel.commit_static()?.built_triangles;
            self.cost.record_build(built.max(batch), ms(t));
        }
        Ok(())
    }

    /// Records the static scene as it is now in the geometry cache.
    fn record_in_cache(&mut self) {
        let scene = self.current_scene();
        let triangles = triangles_in(&self.integrated, scene.ids.keys());
        let key = scene.ids.keys().copied().collect();
        if let Some(cache) = &mut self.cache {
            cache.record(&key, scene, triangles, |e| e.snapshot.as_ref().map_or(0, |s| s.unique_bytes()));
        }
    }
}
