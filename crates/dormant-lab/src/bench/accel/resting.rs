//! The integration forms of `dormant bench accel` on one backend, with the last island (1% of
//! the bodies) awake and the rest integrated:
//! - **instanced**: every body an instance in the per-frame top level (`never`);
//! - **resting**: the other 99% in the resting scene, the 1% in the top level;
//! - **baked**: the 99% baked into the static scene (the insert benchmark's grown scene
//!   without its last island), the 1% instances in the top level.
//!
//! The same primary and bounce rays are traced through the three (closest hit, single rays; the
//! primary rays also in packets of 8 consecutive pixels, as the renderer traces camera rays),
//! interleaved run by run with the first form rotating so load on the shared machine falls on
//! all alike; the best run of each counts. Also timed: the
//! per-frame commit once the awake bodies moved (all 100% in the top level against the 1%),
//! and a rebuild of the resting scene (one body woken and put back to rest).

use std::ops::Range;

use rayon::prelude::*;
use serde::Serialize;

use super::{timed, trace};
use dormant::accel::{self, AccelError, Accelerator, Backend, LoadedScene, SceneQuery, StaticId};
use dormant::geometry::Ray;
use dormant::scene::SceneDescription;

/// Best trace times of one form, closest hit.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FormTrace {
    pub primary_ms: f64,
    pub bounce_ms: f64,
    /// The primary rays in packets of 8.
    pub primary_packets_ms: f64,
}

impl FormTrace {
    const NONE: FormTrace =
        FormTrace { primary_ms: f64::INFINITY, bounce_ms: f64::INFINITY, primary_packets_ms: f64::INFINITY };

    fn total(&self) -> f64 {
        self.primary_ms + self.bounce_ms
    }

    /// Traces the rays through `query` once and keeps each time if it is the best so far.
    fn run(&mut self, query: &dyn SceneQuery, primary: &[Ray], bounce: &[Ray]) {
        self.primary_ms = self.primary_ms.min(trace(query, primary).0);
        self.bounce_ms = self.bounce_ms.min(trace(query, bounce).0);
        self.primary_packets_ms = self.primary_packets_ms.min(trace_packets(query, primary));
    }
}

/// Traces `rays` (closest hit) in packets of 8 over rayon; returns ms.
fn trace_packets(query: &dyn SceneQuery, rays: &[Ray]) -> f64 {
    let (found, ms) = timed(|| {
        rays.par_chunks(8)
            .map(|chunk| {
                let mut hits = [None; 8];
                query.intersect_packet(chunk, &mut hits[..chunk.len()]);
                hits.iter().flatten().count()
            })
            .sum::<usize>()
    });
    std::hint::black_box(found);
    ms
}

#[derive(Clone, Debug, Serialize)]
pub struct RestingTiming {
    pub backend: Backend,
    pub resting_instances: usize,
    pub awake_instances: usize,
    pub instanced: FormTrace,
    pub resting: FormTrace,
    pub baked: FormTrace,
    /// Rebuild of the resting scene (`commit_static` after its set changed), best run.
    pub resting_rebuild_ms: f64,
    pub resting_rebuild_us_per_instance: f64,
    /// Commit after the awake bodies moved: every body in the top level ...
    pub instanced_commit_ms: f64,
    /// ... and only the awake ones (the rest resting).
    pub resting_commit_ms: f64,
    /// The resting form's trace penalty: resting over instanced, primary and bounce rays.
    pub resting_trace_over_instanced: f64,
    /// The baked form's, on the same rays.
    pub baked_trace_over_instanced: f64,
    /// The resting form's penalty on primary rays in packets.
    pub resting_packets_over_instanced: f64,
    pub instanced_commit_over_resting: f64,
}

/// Every body of `desc` an instance.
fn instanced_scene(
    desc: &SceneDescription,
    backend: Backend,
    threads: Option<usize>,
) -> Result<(Box<dyn Accelerator>, LoadedScene), AccelError> {
    let mut a = accel::create(backend, threads)?;
    let loaded = accel::load_scene(desc, a.as_mut())?;
    a.commit()?;
    Ok((a, loaded))
}

/// Every body of `desc` an instance, all but `awake` resting.
fn resting_scene(
    desc: &SceneDescription,
    backend: Backend,
    threads: Option<usize>,
    awake: &Range<usize>,
) -> Result<(Box<dyn Accelerator>, LoadedScene), AccelError> {
    let mut a = accel::create(backend, threads)?;
    let loaded = accel::load_scene(desc, a.as_mut())?;
    for (i, id) in loaded.instances.iter().enumerate() {
        if !awake.contains(&i) {
            a.set_instance_resting(*id, true)?;
        }
    }
    a.commit()?;
    Ok((a, loaded))
}

/// Moves the awake bodies a little (back and forth with `round`) and times the commit.
fn timed_frame_commit(
    a: &mut dyn Accelerator,
    desc: &SceneDescription,
    loaded: &LoadedScene,
    awake: &Range<usize>,
    round: u32,
) -> Result<f64, AccelError> {
    let lift = glam::Affine3A::from_translation(glam::Vec3::Y * 1e-3 * (round % 2) as f32);
    for i in awake.clone() {
        a.set_instance_transform(loaded.instances[i], lift * desc.bodies[i].transform)?;
    }
    let (report, ms) = timed(|| a.commit());
    report?;
    Ok(ms)
}

/// Wakes one resting body and puts it back to rest, so the set counts as changed, and times
/// the rebuild (`commit_static`); then publishes it.
fn timed_resting_rebuild(a: &mut dyn Accelerator, loaded: &LoadedScene) -> Result<f64, AccelError> {
    let id = loaded.instances[0];
    a.set_instance_resting(id, false)?;
    a.set_instance_resting(id, true)?;
    let (report, ms) = timed(|| a.commit_static());
    report?;
    a.commit()?;
    Ok(ms)
}

/// `grown` (every body baked, in islands of 1%) without the island `last`, whose bodies
/// (`awake`) become instances again.
fn baked_scene(
    desc: &SceneDescription,
    mut grown: Box<dyn Accelerator>,
    last: StaticId,
    awake: &Range<usize>,
) -> Result<Box<dyn Accelerator>, AccelError> {
    grown.remove_static(last)?;
    let mut protos = Vec::with_capacity(desc.prototypes.len());
    for p in &desc.prototypes {
        protos.push(grown.add_prototype(&p.mesh)?);
    }
    for b in &desc.bodies[awake.clone()] {
        grown.add_instance(protos[b.prototype as usize], b.transform)?;
    }
    grown.commit()?;
    Ok(grown)
}

/// The three forms of one backend. `grown` is the insert benchmark's scene (every body baked
/// in islands of 1%) and `last` its last island, whose bodies (`awake`) stay awake in every
/// form.
pub(super) fn resting_timing(
    desc: &SceneDescription,
    (grown, last): (Box<dyn Accelerator>, StaticId),
    awake: Range<usize>,
    rays: (&[Ray], &[Ray]),
    runs: u32,
    threads: Option<usize>,
) -> Result<RestingTiming, AccelError> {
    let backend = grown.backend();
    debug_assert!(awake.start > 0 && awake.end <= desc.bodies.len(), "body 0 rests");
    let baked = baked_scene(desc, grown, last, &awake)?;
    let (mut instanced, loaded) = instanced_scene(desc, backend, threads)?;
    let (mut resting, _) = resting_scene(desc, backend, threads, &awake)?;
    let (primary, bounce) = rays;
    let mut best = [FormTrace::NONE; 3];
    let (mut rebuild_ms, mut commit_ms) = (f64::INFINITY, [f64::INFINITY; 2]);
    for round in 0..runs.max(1) {
        let forms = [instanced.as_ref(), resting.as_ref(), baked.as_ref()];
        for k in 0..3 {
            let form = (round as usize + k) % 3;
            best[form].run(forms[form].query()?, primary, bounce);
        }
        commit_ms[0] =
            commit_ms[0].min(timed_frame_commit(instanced.as_mut(), desc, &loaded, &awake, round)?);
        commit_ms[1] = commit_ms[1].min(timed_frame_commit(resting.as_mut(), desc, &loaded, &awake, round)?);
        rebuild_ms = rebuild_ms.min(timed_resting_rebuild(resting.as_mut(), &loaded)?);
    }
    let resting_instances = desc.bodies.len() - awake.len();
    let [instanced_trace, resting_trace, baked_trace] = best;
    tracing::info!(
        "{backend}: resting/instanced trace {:.3}, baked/instanced {:.3}",
        resting_trace.total() / instanced_trace.total(),
        baked_trace.total() / instanced_trace.total()
    );
    Ok(RestingTiming {
        backend,
        resting_instances,
        awake_instances: awake.len(),
        instanced: instanced_trace,
        resting: resting_trace,
        baked: baked_trace,
        resting_rebuild_ms: rebuild_ms,
        resting_rebuild_us_per_instance: rebuild_ms * 1e3 / resting_instances.max(1) as f64,
        instanced_commit_ms: commit_ms[0],
        resting_commit_ms: commit_ms[1],
        resting_trace_over_instanced: resting_trace.total() / instanced_trace.total(),
        baked_trace_over_instanced: baked_trace.total() / instanced_trace.total(),
        resting_packets_over_instanced: resting_trace.primary_packets_ms / instanced_trace.primary_packets_ms,
        instanced_commit_over_resting: commit_ms[0] / commit_ms[1],
    })
}
