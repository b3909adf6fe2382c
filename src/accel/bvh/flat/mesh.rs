//! A flattened BVH over triangles: the bottom level of a prototype and each immutable block of
//! the static tree. Triangles are stored in leaf order next to the nodes.

use super::{build, BoxRay, FlatBvh, Wide};
use crate::accel::bvh::triangle::{RayTri, Tri};
use crate::accel::bvh::BuildParams;
use crate::geometry::Aabb;

/// Closest triangle found so far, in the space it was tested in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PrimHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    /// The triangle (copied, so the caller can read its ids and normal).
    pub tri: Tri,
}

/// Triangles plus the tree over them.
#[derive(Clone, Debug, Default)]
pub(crate) struct MeshBvh {
    pub bvh: FlatBvh,
    /// The 4-wide copy rays traverse.
    pub wide: Wide,
    pub tris: Vec<Tri>,
}

impl MeshBvh {
    /// Builds over `tris`, which must all be valid (see [`crate::accel::bvh::triangle::extract`]).
    pub fn build(tris: Vec<Tri>, params: BuildParams) -> Self {
        let bounds: Vec<Aabb> = tris.iter().map(Tri::bounds).collect();
        let (bvh, order) = build(&bounds, params);
        let tris = order.iter().map(|&i| tris[i as usize]).collect();
        let wide = Wide::new(&bvh);
        Self { bvh, wide, tris }
    }

    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    pub fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes() + self.wide.memory_bytes() + self.tris.len() * std::mem::size_of::<Tri>()
    }

    /// Closest hit in the subtree at `root` with `t <= *t_max`; lowers `*t_max` and overwrites
    /// `best` when it finds one. Returns whether it found one.
    #[inline]
    pub fn intersect_from(
        &self,
        root: u32,
        bray: &BoxRay,
        tray: &RayTri,
        t_max: &mut f32,
        best: &mut Option<PrimHit>,
    ) -> bool {
        let mut found = false;
        self.wide.traverse(&self.bvh, root, bray, t_max, &mut |first, count, t_max| {
            for tri in &self.tris[first as usize..(first + count) as usize] {
                if let Some(h) = tray.intersect(&tri.p, *t_max) {
                    // Strictly closer only: ties keep the first triangle found.
                    if best.is_none_or(|b| h.t < b.t) {
                        *t_max = h.t;
                        *best = Some(PrimHit { t: h.t, u: h.u, v: h.v, tri: *tri });
                        found = true;
                    }
                }
            }
            false
        });
        found
    }

    /// Whether any triangle of the subtree at `root` is hit within `[t_min, t_max]`.
    #[inline]
    pub fn occluded_from(&self, root: u32, bray: &BoxRay, tray: &RayTri, t_max: f32) -> bool {
        let mut t_max = t_max;
        self.wide.traverse(&self.bvh, root, bray, &mut t_max, &mut |first, count, t_max| {
            self.tris[first as usize..(first + count) as usize]
                .iter()
                .any(|tri| tray.intersect(&tri.p, *t_max).is_some())
        })
    }
}
