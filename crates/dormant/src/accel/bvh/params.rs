//! Build parameters shared by every BVH in this backend, with named presets.

/// How a binned-SAH build trades build time for trace speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildParams {
    /// Centroid bins per axis when searching for a split (2..=64).
    pub(crate) bins: usize,
    /// Largest leaf the builder may make; bigger ranges are always split.
    pub(crate) max_leaf_size: usize,
    /// SAH cost of visiting an interior node (relative to `intersection_cost`).
    pub(crate) traversal_cost: f32,
    /// SAH cost of one ray-primitive test.
    pub(crate) intersection_cost: f32,
    /// Ranges with at least this many primitives build their two halves in parallel.
    pub(crate) parallel_threshold: usize,
    /// The SAH counts primitives in blocks of this many (Embree's block counting): triangle
    /// leaves are tested four at a time ([`crate::accel::bvh::triangle::Tri4`]), so a leaf
    /// of four costs what a leaf of one does. 1 for structures whose leaves are tested one
    /// item at a time (the top level).
    pub(crate) leaf_block: usize,
}

impl BuildParams {
    /// Few bins, larger leaves: for structures rebuilt often (the top level).
    pub const FAST: BuildParams = BuildParams {
        bins: 8,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        intersection_cost: 1.0,
        parallel_threshold: 4096,
        leaf_block: 4,
    };

    /// For the top level over instances: one instance per leaf, since entering an instance
    /// (transforming the ray) costs far more than testing its world box.
    pub(crate) const TOP_LEVEL: BuildParams = BuildParams {
        bins: 16,
        max_leaf_size: 1,
        traversal_cost: 1.0,
        intersection_cost: 4.0,
        parallel_threshold: 4096,
        leaf_block: 1,
    };

    /// The default for meshes: good trees at moderate cost.
    pub(crate) const BALANCED: BuildParams = BuildParams {
        bins: 16,
        max_leaf_size: 4,
        traversal_cost: 1.0,
        intersection_cost: 1.0,
        parallel_threshold: 4096,
        leaf_block: 4,
    };

    /// More bins: for structures built once and traced a lot. Leaves of up to 8 triangles (two
    /// packets; the SAH counts blocks of four, so a leaf grows past one packet only where that
    /// pays): builds faster than leaves of 4, traces about the same:
    /// docs/lab/bvh-build.md#2026-12-02-where-the-builds-time-goes-in-a-fresh-process-node-slots-leaves-of-8
    /// Blocks of eight (`leaf_block: 8`, so that a leaf of up to eight costs one AVX2 test)
    /// made fewer, fuller leaves that traced slower:
    /// docs/lab/accelerators.md#2026-12-03-a-leafs-two-packets-in-one-avx2-test-cachegrind
    pub const QUALITY: BuildParams = BuildParams {
        bins: 32,
        max_leaf_size: 8,
        traversal_cost: 1.2,
        intersection_cost: 1.0,
        parallel_threshold: 2048,
        leaf_block: 4,
    };

    /// SAH cost of a leaf of `count` primitives: `intersection_cost` per block of
    /// `leaf_block` (the builder's sweep counts its sides the same way).
    pub(crate) fn leaf_cost(&self, count: usize) -> f32 {
        self.intersection_cost * count.div_ceil(self.leaf_block.max(1)) as f32
    }

    /// Clamps fields to workable values (at least two bins, leaves of at least one primitive).
    pub(crate) fn sanitized(self) -> Self {
        Self {
            bins: self.bins.clamp(2, 64),
            max_leaf_size: self.max_leaf_size.clamp(1, 64),
            traversal_cost: if self.traversal_cost.is_finite() && self.traversal_cost >= 0.0 {
                self.traversal_cost
            } else {
                1.0
            },
            intersection_cost: if self.intersection_cost.is_finite() && self.intersection_cost > 0.0 {
                self.intersection_cost
            } else {
                1.0
            },
            parallel_threshold: self.parallel_threshold.max(64),
            leaf_block: self.leaf_block.max(1),
        }
    }
}

impl Default for BuildParams {
    fn default() -> Self {
        Self::BALANCED
    }
}

/// Items per rayon task when building (copying triangles, their boxes, primitive references).
pub(crate) const PAR_CHUNK: usize = 16 * 1024;
