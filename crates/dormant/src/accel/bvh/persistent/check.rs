//! The persistent tree's invariant check, which the property tests (`accel/tests/`) run after
//! every change. Compiled only for tests.

use std::collections::HashMap;

use super::{Link, StaticBvh, MAX_OVERLAY_HEIGHT};
use crate::accel::StaticId;

impl StaticBvh {
    /// Checks the tree's invariants (O(n)): overlay bounds, masks and heights match their
    /// children, every live mesh's triangles are reachable exactly once, nothing else is, and
    /// the traversal view matches the tree.
    pub(crate) fn check_invariants(&self) -> Result<(), String> {
        let s = &self.state;
        let mut per_mesh: HashMap<u32, usize> = HashMap::new();
        let mut refs = 0usize;
        if let Some(root) = &s.root {
            let mut stack = vec![root];
            while let Some(l) = stack.pop() {
                match l {
                    Link::Node(n) => {
                        let [a, b] = &n.kids;
                        if n.aabb != a.aabb().union(b.aabb()) {
                            return Err(format!(
                                "overlay bounds {:?} are not the union of the children",
                                n.aabb
                            ));
                        }
                        if n.mask != a.mask() | b.mask() || n.height != 1 + a.height().max(b.height()) {
                            return Err("overlay mask or height is stale".into());
                        }
                        stack.extend([a, b]);
                    }
                    Link::Ref(b, i) => {
                        refs += 1;
                        let nodes = &b.mesh.bvh.nodes;
                        let mut inner = vec![*i];
                        while let Some(k) = inner.pop() {
                            let n = &nodes[k as usize];
                            if n.is_leaf() {
                                for t in b.mesh.leaf_tris(n.first, n.count) {
                                    if s.meshes.get(&StaticId(t.geom)).is_none_or(|e| e.block != b.id) {
                                        return Err(format!(
                                            "stale triangle of mesh {} in block {}",
                                            t.geom, b.id
                                        ));
                                    }
                                    *per_mesh.entry(t.geom).or_default() += 1;
                                }
                            } else {
                                inner.extend([n.first, n.first + 1]);
                            }
                        }
                    }
                }
            }
        }
        for (id, e) in s.meshes.iter() {
            let found = per_mesh.remove(&id.0).unwrap_or(0);
            if found != e.triangles {
                return Err(format!(
                    "mesh {} has {} triangles reachable, expected {}",
                    id.0, found, e.triangles
                ));
            }
        }
        if !per_mesh.is_empty() {
            return Err(format!("triangles of unknown meshes reachable: {per_mesh:?}"));
        }
        let total: usize = s.meshes.values().map(|e| e.triangles).sum();
        if total != s.triangles {
            return Err(format!("triangle count {} != sum over meshes {}", s.triangles, total));
        }
        if s.view.refs.len() != refs {
            return Err("traversal view is stale".into());
        }
        if s.root.as_ref().is_some_and(|r| r.height() > MAX_OVERLAY_HEIGHT) {
            return Err("overlay too deep".into());
        }
        Ok(())
    }
}
