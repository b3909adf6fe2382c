//! Relinking the persistent tree ([`StaticBvh::relink`], once a commit's new triangles pass
//! [`StaticBvh::rebuild_fraction`]): the blocks that will never be removed merged into one
//! rebuilt block, the overlay re-braided over it and the blocks that stay removable.

use std::collections::HashSet;
use std::sync::Arc;

use super::{Block, StaticBvh};
use crate::accel::bvh::triangle::Tri;

impl StaticBvh {
    /// Rebuilds the overlay over the existing blocks ([`super::rebraid`]) after merging the blocks
    /// that will never be removed (the rebuilt base and the blocks of meshes declared with
    /// [`Self::set_permanent`]) into one rebuilt block. Every other mesh keeps its own block
    /// and stays removable without a rebuild. What growth past [`Self::rebuild_fraction`]
    /// triggers: the environment and the islands that stay are then one tree again, whose
    /// order is the SAH's and not the overlay's. Returns the triangles built into the merged
    /// block (0 when there was nothing to merge), or `None` when it fell back to a full rebuild
    /// (the overlay came out deeper than [`MAX_OVERLAY_HEIGHT`]).
    ///
    /// Merging only what never wakes keeps the best of both: merging everything, as a full
    /// rebuild does, makes every later removal a full rebuild, and keeping every island's
    /// block leaves hundreds of small, overlapping blocks that rays enter one at a time.
    /// Merging only when a cost estimate said it pays left a tree slower than either:
    /// docs/lab/persistent-tree.md#2026-12-02-the-persistent-static-tree-after-the-atriums-run
    ///
    /// `blocks`: every live block, each whole (none of them may hold a removed mesh's
    /// triangles).
    pub(super) fn relink(&mut self, blocks: Vec<Arc<Block>>) -> Option<usize> {
        let (merge, keep) = self.mergeable(&blocks);
        let (order, built) = match (merge.len() > 1).then(|| self.merge_blocks(&merge)).flatten() {
            Some(merged) => {
                let built = merged.mesh.tris.len();
                (std::iter::once(merged).chain(keep).collect(), built)
            }
            None => (blocks, 0),
        };
        self.state.rebuilt_triangles = self.state.triangles;
        self.state.inserted_since_rebuild = 0;
        (!self.braid_or_rebuild(&order)).then_some(built)
    }

    /// Splits `blocks` into those that will never be removed on their own (every live mesh in
    /// them is shared or permanent) and the rest.
    fn mergeable(&self, blocks: &[Arc<Block>]) -> (Vec<Arc<Block>>, Vec<Arc<Block>>) {
        let mut removable = HashSet::new();
        for (id, e) in self.state.meshes.iter() {
            if e.triangles > 0 && !e.shared && !self.permanent.contains(id) {
                removable.insert(e.block);
            }
        }
        blocks.iter().cloned().partition(|b| !removable.contains(&b.id))
    }

    /// Builds one block from the live triangles of `blocks` and marks their meshes as sharing it.
    fn merge_blocks(&mut self, blocks: &[Arc<Block>]) -> Option<Arc<Block>> {
        let ids: HashSet<u32> = blocks.iter().map(|b| b.id).collect();
        let tris: Vec<Tri> = blocks.iter().flat_map(|b| self.live_tris_of(b)).collect();
        if tris.is_empty() {
            return None;
        }
        let block = self.new_block(tris);
        for e in Arc::make_mut(&mut self.state.meshes).values_mut() {
            if e.triangles > 0 && ids.contains(&e.block) {
                e.block = block.id;
                e.shared = true;
            }
        }
        Some(block)
    }
}
