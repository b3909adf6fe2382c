//! The SAH cost of a built tree, to compare trees made different ways (insertion vs rebuild).

use super::Node;
use crate::accel::bvh::BuildParams;

/// Unnormalised SAH sum of the subtree at `root`: over its nodes, surface area times
/// `traversal_cost` (interior) or [`BuildParams::leaf_cost`] (leaf).
pub(crate) fn subtree_cost(nodes: &[Node], root: u32, params: &BuildParams) -> f64 {
    let mut sum = 0.0f64;
    if nodes.is_empty() {
        return sum;
    }
    let mut stack = vec![root];
    while let Some(i) = stack.pop() {
        let n = &nodes[i as usize];
        let c = if n.is_leaf() {
            params.leaf_cost(n.count as usize)
        } else {
            stack.push(n.first);
            stack.push(n.first + 1);
            params.traversal_cost
        };
        sum += f64::from(n.aabb().surface_area()) * f64::from(c);
    }
    sum
}

/// SAH cost of a whole tree, normalised by its root's area; 0 for an empty tree.
pub(crate) fn sah_cost(nodes: &[Node], params: &BuildParams) -> f32 {
    let Some(root) = nodes.first() else {
        return 0.0;
    };
    let root_area = f64::from(root.aabb().surface_area()).max(f64::from(f32::MIN_POSITIVE));
    (subtree_cost(nodes, 0, params) / root_area) as f32
}
