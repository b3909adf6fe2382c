//! The `--count` override: a total number of dynamic objects spread over a scene's spawners
//! (exactly, in proportion to their counts) and structures (in whole copies).

use super::spec::{SpawnerDef, StructureArray, StructureDef};

/// `spawners` and `structures` rescaled to about `total` bodies (at least `spawners.len()`).
/// Spawners and structures share `total` in proportion to the bodies they have; spawners
/// get their share exactly (each at least 1), every structure at least one copy.
pub(super) fn spread_count(
    spawners: &[SpawnerDef],
    structures: &[StructureDef],
    total: u32,
) -> (Vec<SpawnerDef>, Vec<StructureDef>) {
    let spawned: u64 = spawners.iter().map(|s| s.count as u64).sum();
    let built: u64 = structures.iter().map(StructureDef::body_count).sum();
    let spawner_share = if built == 0 {
        total as u64
    } else {
        (total as u64 * spawned / (spawned + built)).max(spawners.len() as u64)
    };
    let structure_share = (total as u64).saturating_sub(spawner_share);
    let spawners =
        if spawners.is_empty() { Vec::new() } else { spread_over_spawners(spawners, spawner_share) };
    let structures = structures
        .iter()
        .map(|s| {
            let target = structure_share as f64 * s.body_count() as f64 / built as f64;
            let copies = (target / s.layout.blocks_per_copy() as f64).round().max(1.0);
            StructureDef { array: with_copies(&s.array, copies as u64), ..s.clone() }
        })
        .collect();
    (spawners, structures)
}

/// `spawners` with counts in proportion to theirs adding up to `total` (at least
/// `spawners.len()`), each at least 1, and waves cut to the count.
fn spread_over_spawners(spawners: &[SpawnerDef], total: u64) -> Vec<SpawnerDef> {
    let n = spawners.len();
    debug_assert!(n > 0 && total >= n as u64);
    let old_total: u64 = spawners.iter().map(|s| s.count as u64).sum();
    let mut assigned = 0u64;
    let spread = spawners
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let share =
                if i + 1 == n { total - assigned } else { (total * s.count as u64 / old_total).max(1) };
            let remaining_spawners = (n - i - 1) as u64;
            let share = share.min(total - assigned - remaining_spawners).max(1);
            assigned += share;
            let count = share as u32;
            SpawnerDef { count, waves: s.waves.min(count), ..s.clone() }
        })
        .collect();
    debug_assert_eq!(assigned, total);
    spread
}

/// An array of about `copies` copies with the shape of `array`: a row stays a row, a grid
/// keeps its aspect ratio. Copy 0 stays where it was; the spacing is unchanged.
fn with_copies(array: &StructureArray, copies: u64) -> StructureArray {
    let [nx, nz] = array.counts;
    let clamp = |v: f64| v.round().clamp(1.0, u32::MAX as f64) as u32;
    let counts = if nz == 1 {
        [clamp(copies as f64), 1]
    } else if nx == 1 {
        [1, clamp(copies as f64)]
    } else {
        let z = clamp((copies as f64 * nz as f64 / nx as f64).sqrt());
        [clamp(copies as f64 / z as f64), z]
    };
    StructureArray { counts, ..*array }
}
