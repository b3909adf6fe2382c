//! The BVH's persistent static tree at its most fragmented point of a `bench integration` run,
//! against a fresh build of the same triangles (the target: within 5% of a fresh build).
//!
//! The end of a run says nothing about how the overlay places blocks: the last relink may have
//! merged them all into one rebuilt block, the fresh build's own tree (`static_variants` in the
//! report). The frame where the tree is made of the most blocks (one per mesh inserted since
//! the last rebuild or relink, just before a relink merges them) does: that snapshot is kept
//! while the run goes (O(1) to take; it keeps that version's blocks in memory to the end of
//! the run) and traced after it against a one-block rebuild of its own triangles.

use serde::Serialize;

use super::accel as accel_bench;
use crate::crosscheck::camera_rays;
use dormant::accel::bvh::StaticSnapshot;
use dormant::accel::{self, AccelError, Backend, StaticSceneSnapshot};
use dormant::residency::SceneManager;
use dormant::scene::SceneDescription;

/// The persistent tree's most fragmented snapshot seen so far in a run.
#[derive(Default)]
pub(crate) struct MostFragmented {
    seen: Option<(u32, usize, StaticSceneSnapshot)>,
}

impl MostFragmented {
    /// Looks at `manager`'s static scene after trajectory frame `frame`; keeps it if the BVH's
    /// tree is made of more blocks than any kept before.
    pub fn observe(&mut self, frame: u32, manager: &SceneManager) {
        let Some(snapshot) = manager.static_snapshot() else {
            return;
        };
        let Some(blocks) = snapshot.bvh_tree().map(StaticSnapshot::blocks) else {
            return;
        };
        if self.seen.as_ref().is_none_or(|(_, most, _)| blocks > *most) {
            self.seen = Some((frame, blocks, snapshot));
        }
    }

    /// Traces the kept snapshot and a fresh build of its triangles with the same rays;
    /// `None` if no BVH snapshot was seen. `template` gives the camera.
    pub fn measure(
        self,
        template: &SceneDescription,
        threads: Option<usize>,
    ) -> Result<Option<FragmentedTree>, AccelError> {
        let Some((frame, blocks, snapshot)) = self.seen else {
            return Ok(None);
        };
        let (Some(tree), Some(rebuilt)) = (snapshot.bvh_tree(), snapshot.bvh_rebuilt()) else {
            return Ok(None);
        };
        let mut accels = Vec::new();
        for s in [&snapshot, &rebuilt] {
            let mut a = accel::create(Backend::Bvh, threads)?;
            a.restore_static_scene(s)?;
            a.commit()?;
            accels.push(a);
        }
        let primary = camera_rays(template, 640, 360);
        let bounce = accel_bench::bounce_rays(accels[1].query()?, &primary);
        let queries = [accels[0].query()?, accels[1].query()?];
        let best = accel_bench::best_traces(&queries, &primary, &bounce);
        let (persistent, fresh) = (best[0], best[1]);
        Ok(Some(FragmentedTree {
            frame,
            blocks,
            block_subtrees: tree.block_subtrees(),
            triangles: tree.triangles(),
            persistent_sah: accels[0].static_sah_cost(),
            fresh_sah: accels[1].static_sah_cost(),
            persistent_ms: persistent,
            fresh_ms: fresh,
            primary: persistent.0 / fresh.0,
            bounce: persistent.1 / fresh.1,
        }))
    }
}

/// The persistent tree where a run left it in the most pieces, against a fresh build.
#[derive(Clone, Debug, Serialize)]
pub struct FragmentedTree {
    /// Trajectory frame after which the snapshot was taken.
    pub frame: u32,
    /// Blocks the tree is made of (1 for a tree that is one block).
    pub blocks: usize,
    /// Block subtrees under the overlay: the pieces rays find the tree in.
    pub block_subtrees: usize,
    pub triangles: usize,
    pub persistent_sah: Option<f32>,
    pub fresh_sah: Option<f32>,
    /// Primary and bounce trace milliseconds, best of nine, round robin.
    pub persistent_ms: (f64, f64),
    pub fresh_ms: (f64, f64),
    /// Persistent over fresh trace time, primary rays (the target: at most 1.05).
    pub primary: f64,
    /// The same for diffuse bounces from the fresh build's primary hits.
    pub bounce: f64,
}
