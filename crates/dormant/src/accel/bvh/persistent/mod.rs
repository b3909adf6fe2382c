//! The static scene as a persistent BVH: world-space meshes that can be inserted and removed
//! after the first build without rebuilding, with O(1) snapshots.
//!
//! # Layout and trade-off
//!
//! The tree has two kinds of parts:
//! - **blocks**: immutable flattened BVHs ([`MeshBvh`]: 32-byte binary nodes, their 8-wide
//!   traversal copy, triangles and their leaf order) behind an `Arc`. The first build makes one block of everything (the *base*); each
//!   mesh inserted later gets its own small block, built by binned SAH.
//! - **overlay**: immutable binary nodes behind `Arc`s on top of the blocks. A link is either
//!   an overlay node or a reference to a node *inside* a block.
//!
//! Inserting a block's subtree next to some node deep in the base copies only the path from the
//! root to that node into the overlay (path copying); everything else, overlay or block, is
//! shared. So a snapshot is an `Arc` clone of the root (O(1)), an old snapshot never sees later
//! changes, and an insert of k triangles costs O(k) for the block plus O(log n) overlay nodes per
//! inserted subtree. Traversal stays fast because rays spend nearly all their time inside
//! blocks, which are the same cache-friendly arrays as any other BVH here; only the few overlay
//! nodes are pointer-chased.
//!
//! A commit ([`StaticBvh::apply`], what the accelerator calls) does not insert one block at a
//! time: it builds the new meshes' blocks and then the whole overlay afresh over every live
//! block, *re-braided* ([`rebraid`]): top-down by binned SAH over pieces of the blocks, the
//! environment opened into subtrees the size of the islands around it, so the overlay's
//! shape never depends on the order of the changes, and a ray aimed at an island is not walked
//! through the whole environment subtree around it first. That costs O(p log p) for p pieces
//! (at most four per block) per commit, not per mesh. The single-mesh [`StaticBvh::insert`]
//! and [`StaticBvh::remove`] still insert by path copying and unlink and refit (collapsing path
//! copies back into block references where they match again). Past
//! [`StaticBvh::rebuild_fraction`] new triangles a commit relinks ([`StaticBvh::relink`]):
//! the blocks that will never be removed are merged into one rebuilt block first. Removing a
//! mesh that shares a rebuilt block rebuilds everything into one block, as an overlay deeper
//! than [`MAX_OVERLAY_HEIGHT`] does.
//!
//! For traversal, every new root also gets a flattened copy of its overlay (a *view*: overlay
//! nodes as ordinary 32-byte nodes whose leaves name block subtrees), so rays chase no
//! pointers; it costs O(overlay nodes) per change and is shared by snapshots. A reference into
//! a block enters the block's 8-wide tree at the matching node.
//!
//! Mesh bookkeeping (id -> block) is an `Arc<HashMap>` cloned on first write after a snapshot,
//! so that part of a change is O(number of static meshes), once per commit.
//!
//! This file holds the types and the mesh bookkeeping; each operation on the tree has a file of
//! its own: `apply.rs` (a commit), `insert.rs`, `remove.rs`, `rebraid.rs` (the overlay over
//! every live block), `relink.rs` (merging what never wakes), `rebuild.rs` (one block), and
//! `traverse.rs` (ray queries), `stats.rs` (counts and walks).

mod apply;
#[cfg(test)]
mod check;
mod insert;
mod rebraid;
mod rebuild;
mod relink;
mod remove;
mod stats;
mod traverse;

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use super::flat::MeshBvh;
use super::triangle::Tri;
use super::BuildParams;
use crate::accel::StaticId;
use crate::geometry::Aabb;

/// Deepest overlay allowed before a rebuild; also bounds the overlay traversal stack.
pub(crate) const MAX_OVERLAY_HEIGHT: u32 = 64;

/// An immutable BVH over some static triangles.
#[derive(Debug)]
pub(crate) struct Block {
    pub id: u32,
    pub mesh: MeshBvh,
}

/// A child pointer: an overlay node, or a node inside a block.
#[derive(Clone, Debug)]
pub(crate) enum Link {
    Node(Arc<ONode>),
    Ref(Arc<Block>, u32),
}

/// An overlay node. Never modified after creation.
#[derive(Debug)]
pub(crate) struct ONode {
    pub(crate) aabb: Aabb,
    pub(crate) kids: [Link; 2],
    /// Bit `block.id % 64` is set for every block referenced below: prunes removal walks.
    pub mask: u64,
    /// Overlay levels below and including this node (block references count 0).
    pub height: u32,
    /// When this node is a path copy of a block node: that block and node, so it can collapse
    /// back into a reference once its children are the block's own again.
    pub origin: Option<(u32, u32)>,
}

impl ONode {
    pub(crate) fn new(kids: [Link; 2], origin: Option<(u32, u32)>) -> Self {
        Self {
            aabb: kids[0].aabb().union(kids[1].aabb()),
            mask: kids[0].mask() | kids[1].mask(),
            height: 1 + kids[0].height().max(kids[1].height()),
            kids,
            origin,
        }
    }
}

impl Link {
    pub(crate) fn aabb(&self) -> Aabb {
        match self {
            Link::Node(n) => n.aabb,
            Link::Ref(b, i) => b.mesh.bvh.nodes[*i as usize].aabb(),
        }
    }

    pub(crate) fn mask(&self) -> u64 {
        match self {
            Link::Node(n) => n.mask,
            Link::Ref(b, _) => 1u64 << (b.id % 64),
        }
    }

    pub(crate) fn height(&self) -> u32 {
        match self {
            Link::Node(n) => n.height,
            Link::Ref(..) => 0,
        }
    }

    /// The two children, or `None` for a block leaf.
    pub(crate) fn children(&self) -> Option<[Link; 2]> {
        match self {
            Link::Node(n) => Some(n.kids.clone()),
            Link::Ref(b, i) => {
                let n = &b.mesh.bvh.nodes[*i as usize];
                (!n.is_leaf()).then(|| [Link::Ref(b.clone(), n.first), Link::Ref(b.clone(), n.first + 1)])
            }
        }
    }

    /// The block node this link is (or copies), for rebuilding a parent on a path.
    pub(crate) fn origin(&self) -> Option<(u32, u32)> {
        match self {
            Link::Node(n) => n.origin,
            Link::Ref(b, i) => Some((b.id, *i)),
        }
    }
}

/// What the tree knows about one static mesh.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshEntry {
    pub(crate) block: u32,
    /// The block also holds other meshes (a rebuild's block): removal needs a rebuild.
    pub(crate) shared: bool,
    pub triangles: usize,
}

/// An immutable version of the static tree. Cloning is O(1).
#[derive(Clone, Debug, Default)]
pub struct StaticSnapshot {
    pub(crate) root: Option<Link>,
    pub(crate) meshes: Arc<HashMap<StaticId, MeshEntry>>,
    pub(crate) triangles: usize,
    pub(crate) rebuilt_triangles: usize,
    pub(crate) inserted_since_rebuild: usize,
    /// The overlay flattened for traversal, rebuilt with every new root.
    pub(crate) view: Arc<traverse::View>,
}

impl StaticSnapshot {
    fn set_root(&mut self, root: Option<Link>) {
        self.view = Arc::new(traverse::View::new(root.as_ref()));
        self.root = root;
    }

    /// Triangles in this version.
    pub fn triangles(&self) -> usize {
        self.triangles
    }

    /// Whether `id` is part of this version.
    pub(crate) fn contains(&self, id: StaticId) -> bool {
        self.meshes.contains_key(&id)
    }

    /// Block subtrees the overlay's leaves name: how many pieces rays find the tree in (1 for a
    /// tree that is one block, 0 for an empty one).
    pub fn block_subtrees(&self) -> usize {
        self.view.refs.len()
    }

    /// Blocks the tree is made of (1 for a tree that is one block, 0 for an empty one): the
    /// rebuilt base plus one per mesh that keeps a block of its own (inserted since the last
    /// rebuild, or removable and so kept apart at the last relink). O(overlay nodes).
    pub fn blocks(&self) -> usize {
        let mut n = 0;
        if let Some(root) = &self.root {
            stats::for_each_block(root, &mut |_| n += 1);
        }
        n
    }

    /// This version's live triangles rebuilt into one block with `params`: the tree a fresh
    /// build of the same scene makes. `self` is unchanged.
    pub(crate) fn rebuilt(&self, params: BuildParams) -> StaticSnapshot {
        let mut tree = StaticBvh::new(params);
        tree.restore(self.clone());
        tree.rebuild();
        tree.snapshot()
    }
}

/// What [`StaticBvh::apply`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StaticUpdate {
    /// Triangles put into new blocks (all live triangles after a rebuild).
    pub(crate) built_triangles: usize,
    /// Triangles skipped as degenerate or not finite.
    pub skipped_triangles: usize,
    /// Whether the update rebuilt the tree from scratch.
    pub rebuilt: bool,
    /// Whether the overlay was rebuilt over the existing blocks ([`StaticBvh::relink`]).
    pub(crate) relinked: bool,
}

/// The persistent static BVH. See the module docs for its layout.
#[derive(Debug)]
pub struct StaticBvh {
    state: StaticSnapshot,
    params: BuildParams,
    next_block: u32,
    /// Relink ([`Self::relink`]) once the triangles inserted since the last rebuild or relink
    /// exceed this fraction of the triangles the tree then held. Default 0.5.
    pub rebuild_fraction: f32,
    /// Meshes the caller says will never be removed ([`Self::set_permanent`]).
    permanent: HashSet<StaticId>,
}

impl Default for StaticBvh {
    fn default() -> Self {
        Self::new(BuildParams::QUALITY)
    }
}

impl StaticBvh {
    pub fn new(params: BuildParams) -> Self {
        Self {
            state: StaticSnapshot::default(),
            params,
            next_block: 0,
            rebuild_fraction: 0.5,
            permanent: HashSet::new(),
        }
    }

    pub fn params(&self) -> &BuildParams {
        &self.params
    }

    /// The current version, O(1). Later changes to `self` never affect it.
    pub fn snapshot(&self) -> StaticSnapshot {
        self.state.clone()
    }

    /// Makes `snapshot` the current version, O(1).
    pub fn restore(&mut self, snapshot: StaticSnapshot) {
        self.state = snapshot;
    }

    pub fn triangles(&self) -> usize {
        self.state.triangles
    }

    pub(crate) fn contains(&self, id: StaticId) -> bool {
        self.state.contains(id)
    }

    /// Declares that mesh `id` (present or about to be inserted) will never be removed, so the
    /// next [`Self::relink`] may merge its block into one rebuilt block with the other
    /// permanent meshes and the rebuilt base. The caller knows the future (an offline render's
    /// lookahead: the island never wakes). If it is removed after all, that costs a rebuild, as
    /// removing a mesh of the base does.
    pub(crate) fn set_permanent(&mut self, id: StaticId) {
        self.permanent.insert(id);
    }

    /// Whether removing `id` needs a rebuild (it shares a block with other meshes) rather
    /// than an unlink and refit.
    pub(crate) fn removal_rebuilds(&self, id: StaticId) -> bool {
        self.state.meshes.get(&id).is_some_and(|e| e.shared && e.triangles > 0)
    }

    pub fn is_empty(&self) -> bool {
        self.state.root.is_none()
    }

    pub fn bounds(&self) -> Aabb {
        self.state.root.as_ref().map_or(Aabb::EMPTY, Link::aabb)
    }

    fn new_block(&mut self, tris: Vec<Tri>) -> Arc<Block> {
        let id = self.next_block;
        self.next_block = self.next_block.wrapping_add(1);
        Arc::new(Block { id, mesh: MeshBvh::build(tris, self.params) })
    }

    /// Records mesh `id` (which must not be present) with its own block of `tris`, not linked
    /// into the tree yet; returns the block (`None` for a mesh without usable triangles).
    fn add_mesh(&mut self, id: StaticId, tris: Vec<Tri>) -> Option<Arc<Block>> {
        debug_assert!(!self.state.meshes.contains_key(&id));
        let n = tris.len();
        let block = (n > 0).then(|| self.new_block(tris));
        let entry =
            MeshEntry { block: block.as_ref().map_or(u32::MAX, |b| b.id), shared: false, triangles: n };
        Arc::make_mut(&mut self.state.meshes).insert(id, entry);
        self.state.triangles += n;
        self.state.inserted_since_rebuild += n;
        block
    }

    /// Drops mesh `id`'s entry (not its triangles from the tree); returns it if it was present.
    fn forget(&mut self, id: StaticId) -> Option<MeshEntry> {
        // An absent `id` keeps its declaration: it may be made permanent before it is inserted.
        if !self.state.meshes.contains_key(&id) {
            return None;
        }
        self.permanent.remove(&id);
        let entry = Arc::make_mut(&mut self.state.meshes).remove(&id)?;
        self.state.triangles -= entry.triangles;
        Some(entry)
    }

    /// The blocks of the current tree that hold live meshes.
    fn live_blocks(&self) -> Vec<Arc<Block>> {
        let live: HashSet<u32> =
            self.state.meshes.values().filter(|e| e.triangles > 0).map(|e| e.block).collect();
        let mut blocks = Vec::new();
        if let Some(root) = &self.state.root {
            stats::for_each_block(root, &mut |b| {
                if live.contains(&b.id) {
                    blocks.push(b.clone());
                }
            });
        }
        blocks
    }
}
