//! Rebuilding the persistent tree into one block from its live meshes' triangles
//! ([`StaticBvh::rebuild`]): what an empty tree, a removal from a shared block or an overlay deeper
//! than [`super::MAX_OVERLAY_HEIGHT`] come to.

use std::sync::Arc;

use super::{stats, Block, Link, StaticBvh};
use crate::accel::bvh::triangle::Tri;
use crate::accel::StaticId;

impl StaticBvh {
    /// Rebuilds the whole tree into one block from the live meshes' triangles.
    pub(crate) fn rebuild(&mut self) {
        let tris = self.live_tris();
        self.rebuild_from(tris);
    }

    /// The triangles of every live mesh, gathered from the blocks.
    pub(super) fn live_tris(&self) -> Vec<Tri> {
        let mut tris = Vec::with_capacity(self.state.triangles);
        if let Some(root) = &self.state.root {
            stats::for_each_block(root, &mut |b| tris.extend(self.live_tris_of(b)));
        }
        tris
    }

    /// The triangles of `block` whose mesh is live and still kept in that block.
    pub(super) fn live_tris_of<'a>(&'a self, block: &'a Block) -> impl Iterator<Item = Tri> + 'a {
        let meshes = &self.state.meshes;
        block
            .mesh
            .tris_in_leaf_order()
            .filter(move |t| meshes.get(&StaticId(t.geom)).is_some_and(|e| e.block == block.id))
            .copied()
    }

    pub(super) fn rebuild_from(&mut self, tris: Vec<Tri>) {
        debug_assert!(tris.iter().all(|t| self.state.meshes.contains_key(&StaticId(t.geom))));
        let n = tris.len();
        let block = self.new_block(tris);
        let meshes = Arc::make_mut(&mut self.state.meshes);
        for e in meshes.values_mut() {
            if e.triangles > 0 {
                e.block = block.id;
                e.shared = true;
            }
        }
        self.state.set_root((n > 0).then_some(Link::Ref(block, 0)));
        self.state.triangles = n;
        self.state.rebuilt_triangles = n;
        self.state.inserted_since_rebuild = 0;
    }
}
