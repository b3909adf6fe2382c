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
