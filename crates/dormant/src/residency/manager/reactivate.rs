//! Stage 1, reactivate: integrated islands that woke leave the static or resting scene.

use std::collections::BTreeSet;
use std::time::Instant;

use super::slots::{CachedScene, Integrated, Placement, StaticOwner};
use super::{ms, FrameStats, ReactivationPath, ReactivationStrategy, SceneManager};
use crate::accel::AccelError;
use crate::physics::IslandId;
use crate::residency::cache::CacheOutcome;

impl SceneManager {
    /// Returns whether anything changed.
    pub(super) fn reactivate(&mut self, stats: &mut FrameStats) -> Result<bool, AccelError> {
        if self.woken.is_empty() {
            return Ok(false);
        }
        let (resting, baked): (Vec<IslandId>, Vec<IslandId>) =
            std::mem::take(&mut self.woken).into_iter().partition(|i| self.resting.contains_key(i));
        if !resting.is_empty() {
            for island in &resting {
                self.wake_resting(*island)?;
            }
            // The resting scene is rebuilt without them now.
            self.commit_static_timed(stats)?;
            stats.reactivation_path = Some(ReactivationPath::Removal);
        }
        if !baked.is_empty() {
            self.reactivate_baked(&baked, stats)?;
        }
        stats.islands_reactivated += (resting.len() + baked.len()) as u32;
        Ok(true)
    }

    /// A resting island's instances go back to the top level, at the poses they rested in
    /// (the update stage moves them on).
    fn wake_resting(&mut self, island: IslandId) -> Result<(), AccelError> {
        let bodies = self.resting.remove(&island).unwrap_or_default();
        self.touched.extend(bodies.iter().map(|b| b.0 as usize));
        for b in bodies {
            let slot = &mut self.bodies[b.0 as usize];
            if let Placement::Resting { id, pose, .. } = slot.placement {
                self.accel.set_instance_resting(id, false)?;
                self.instance_owner.set_resting(id, false);
                slot.placement = Placement::Instance { id, pose };
            }
        }
        Ok(())
    }

    /// Baked islands leave by removal from the live scene, or by restoring a cached scene
    /// without them and adding back the islands it lacks, whichever builds fewer triangles
    /// (or the cache whenever the strategy says so).
    fn reactivate_baked(&mut self, woken: &[IslandId], stats: &mut FrameStats) -> Result<(), AccelError> {
        let request: BTreeSet<IslandId> =
            self.integrated.keys().copied().filter(|i| !woken.contains(i)).collect();
        // The update stage turns their bodies back into instances.
        let parts = woken.iter().flat_map(|i| &self.integrated[i].baked.parts);
        self.touched.extend(parts.map(|p| p.body.0 as usize));
        // Removing from the live scene costs what the accelerator says (a detach or an unlink
        // is free; removing from a shared structure rebuilds it) ...
        let removal_cost =
            woken.iter().map(|i| self.accel.static_removal_cost(self.integrated[i].id)).max().unwrap_or(0);
        // ... restoring a saved scene costs building the requested islands it lacks.
        let restore = self.cheapest_restore(&request);
        let t = Instant::now();
        let cache_first = self.options.reactivation == ReactivationStrategy::CacheFirst;
        match restore.filter(|(_, cost, _)| cache_first || *cost < removal_cost) {
            Some((entry, _, outcome)) => {
                self.restore(&entry, &request, stats)?;
                for island in woken {
                    self.integrated.remove(island);
                }
                stats.reactivation_path = Some(ReactivationPath::Cache(outcome));
            }
            None => {
                for island in woken {
                    let gone = self.integrated.remove(island).expect("woken islands are integrated");
                    self.accel.remove_static(gone.id)?;
                    self.static_owner.remove(gone.id);
                }
                stats.built_triangles += removal_cost;
                stats.reactivation_path = Some(ReactivationPath::Removal);
            }
        }
        self.accel.commit_static()?;
        if stats.built_triangles > 0 {
            self.cost.record_build(stats.built_triangles, ms(t));
        }
        Ok(())
    }

    /// The cached (or pristine) scene that serves `request`, the triangles it lacks, and how
    /// the cache answered; `None` without a restorable scene.
    fn cheapest_restore(
        &mut self,
        request: &BTreeSet<IslandId>,
    ) -> Option<(CachedScene, usize, CacheOutcome)> {
        let cache = self.cache.as_mut()?;
        let hit = cache.lookup(request);
        if let Some(entry) = hit.snapshot.filter(|e| e.snapshot.is_some()) {
            let missing = triangles_in(&self.integrated, request.difference(hit.held));
            Some((entry.clone(), missing, hit.outcome))
        } else if self.pristine.snapshot.is_some() {
            let all = triangles_in(&self.integrated, request.iter());
            Some((self.pristine.clone(), all, CacheOutcome::Miss))
        } else {
            None
        }
    }

    /// Makes `entry` the static scene and adds back the requested islands it lacks.
    fn restore(
        &mut self,
        entry: &CachedScene,
        request: &BTreeSet<IslandId>,
        stats: &mut FrameStats,
    ) -> Result<(), AccelError> {
        let snapshot = entry.snapshot.as_ref().expect("restorable entries only");
        self.accel.restore_static_scene(snapshot)?;
        // The scene is now the environment plus the entry's islands, under the ids they had in
        // it; the other requested islands are added again.
        self.static_owner.retain_environment();
        for island in request {
            let baked = self.integrated[island].baked.clone();
            let id = match entry.ids.get(island) {
                Some(id) => *id,
                None => {
                    stats.built_triangles += baked.triangle_count();
                    self.accel.add_static(&baked.mesh)?
                }
            };
            self.static_owner.insert(id, StaticOwner::Island(baked.clone()));
            self.integrated.insert(*island, Integrated { id, baked });
        }
        Ok(())
    }

    /// The static scene now, for the cache.
    pub(super) fn current_scene(&self) -> CachedScene {
        CachedScene {
            snapshot: self.accel.snapshot_static_scene(),
            ids: self.integrated.iter().map(|(i, x)| (*i, x.id)).collect(),
        }
    }
}

pub(super) fn triangles_in<'a>(
    integrated: &std::collections::BTreeMap<IslandId, Integrated>,
    ids: impl Iterator<Item = &'a IslandId>,
) -> usize {
    ids.map(|i| integrated[i].baked.triangle_count()).sum()
}
