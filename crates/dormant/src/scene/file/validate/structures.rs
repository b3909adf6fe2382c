//! `[[structures]]` and `[[projectiles]]`: what stands asleep from the start, and what is
//! thrown at it.

use std::collections::BTreeSet;

use super::{at_least_one, at_most, exactly_the_keys, finite, finite3, non_negative, problem, Checked};
use crate::geometry::Aabb;
use crate::scene::file::schema::{ArrayToml, ProjectileToml, StructureKind, StructureToml};
use crate::scene::file::spec::{
    ProjectileAim, ProjectileDef, PrototypeDef, Shape, StructureArray, StructureDef, StructureLayout,
};
use crate::scene::limits::MAX_BODIES;

pub(super) fn structures(raw: &[StructureToml], prototypes: &[PrototypeDef]) -> Checked<Vec<StructureDef>> {
    let mut names = BTreeSet::new();
    let mut total = 0u64;
    let mut structures = Vec::with_capacity(raw.len());
    for (i, s) in raw.iter().enumerate() {
        if s.name.trim().is_empty() {
            return Err(problem(format!("structures[{i}].name"), "must not be empty"));
        } else if !names.insert(s.name.as_str()) {
            return Err(problem(
                format!("structures[{i}].name"),
                format!("duplicate structure name {:?}", s.name),
            ));
        }
        let structure = structure(i, s, prototypes)?;
        total += structure.body_count();
        if total > MAX_BODIES {
            let message =
                format!("the structures so far have {total} bodies, more than the {MAX_BODIES} allowed");
            return Err(problem(format!("structures[{i}]"), message));
        }
        structures.push(structure);
    }
    apart(&structures)?;
    Ok(structures)
}

/// Copies of different structures that overlap or touch (by their world-space boxes): the
/// first pair found, sweeping along X.
pub(in crate::scene::file) fn apart(structures: &[StructureDef]) -> Checked<()> {
    let mut boxes: Vec<(Aabb, usize, u32)> = structures
        .iter()
        .enumerate()
        .flat_map(|(i, s)| (0..s.copies()).map(move |copy| (s.copy_bounds(copy), i, copy)))
        .collect();
    boxes.sort_by(|a, b| a.0.min.x.total_cmp(&b.0.min.x));
    let mut open: Vec<usize> = Vec::new();
    for (k, (b, i, copy)) in boxes.iter().enumerate() {
        open.retain(|&j| boxes[j].0.max.x >= b.min.x);
        for &j in &open {
            let (other, oi, ocopy) = &boxes[j];
            if oi != i && (0..3).all(|a| other.min[a] <= b.max[a] && b.min[a] <= other.max[a]) {
                let (first, second) =
                    if oi < i { ((*oi, *ocopy), (*i, *copy)) } else { ((*i, *copy), (*oi, *ocopy)) };
                let message = format!(
                    "copy {} of {:?} overlaps or touches copy {} of {:?}",
                    second.1, structures[second.0].name, first.1, structures[first.0].name
                );
                return Err(problem(format!("structures[{}].origin", second.0), message));
            }
        }
        open.push(k);
    }
    Ok(())
}

/// A box prototype, the layout keys of its kind (counts at least 1), a finite placement, a
/// gap not negative, and copies that do not touch.
fn structure(i: usize, s: &StructureToml, prototypes: &[PrototypeDef]) -> Checked<StructureDef> {
    let at = |f: &str| format!("structures[{i}].{f}");
    let prototype = prototypes
        .iter()
        .position(|p| p.name == s.prototype)
        .ok_or_else(|| problem(at("prototype"), format!("no prototype named {:?}", s.prototype)))?;
    let Shape::Box { half_extents } = prototypes[prototype].shape else {
        let message =
            format!("prototype {:?} is not a box; structures are built of box prototypes", s.prototype);
        return Err(problem(at("prototype"), message));
    };
    let gap = non_negative(&at("gap"), s.gap)?;
    let layout = layout(s, half_extents, gap, &at)?;
    let mut structure = StructureDef {
        name: s.name.clone(),
        prototype,
        half_extents,
        layout,
        origin: finite3(&at("origin"), s.origin)?,
        yaw_degrees: finite(&at("yaw_degrees"), s.yaw_degrees)?,
        gap,
        array: StructureArray { counts: [1, 1], spacing: [0.0, 0.0] },
    };
    if let Some(array) = &s.array {
        structure.array = self::array(array, &structure, &at)?;
    }
    Ok(structure)
}

/// The layout of `s.kind` from exactly the keys it takes.
fn layout(
    s: &StructureToml,
    half_extents: [f32; 3],
    gap: f32,
    at: &dyn Fn(&str) -> String,
) -> Checked<StructureLayout> {
    let wanted: &[&str] = match s.kind {
        StructureKind::Tower | StructureKind::Wall => &["layers", "per_layer"],
        StructureKind::Dominoes => &["count", "spacing"],
        StructureKind::Grid => &["counts"],
    };
    let given = [
        ("layers", s.layers.is_some()),
        ("per_layer", s.per_layer.is_some()),
        ("count", s.count.is_some()),
        ("spacing", s.spacing.is_some()),
        ("counts", s.counts.is_some()),
    ];
    exactly_the_keys(&format!("a {:?} structure", s.kind), wanted, &given, at)?;
    // Every key the kind needs is present (checked above).
    let count =
        |name: &str, v: Option<u32>| at_most(&at(name), at_least_one(&at(name), v.unwrap_or(0))?, MAX_BODIES);
    Ok(match s.kind {
        StructureKind::Tower => StructureLayout::Tower {
            layers: count("layers", s.layers)?,
            per_layer: count("per_layer", s.per_layer)?,
        },
        StructureKind::Wall => StructureLayout::Wall {
            layers: count("layers", s.layers)?,
            per_layer: count("per_layer", s.per_layer)?,
        },
        StructureKind::Dominoes => {
            let spacing = finite(&at("spacing"), s.spacing.unwrap_or(0.0))?;
            let depth = 2.0 * half_extents[2] + gap;
            if spacing <= depth {
                let message = format!("{spacing} would make dominoes {depth} deep (gap included) overlap");
                return Err(problem(at("spacing"), message));
            }
            StructureLayout::Dominoes { count: count("count", s.count)?, spacing }
        }
        StructureKind::Grid => {
            let counts = s.counts.unwrap_or([0; 3]);
            if counts.contains(&0) {
                return Err(problem(at("counts"), format!("must all be at least 1, got {counts:?}")));
            }
            within_bodies(&at("counts"), &counts)?;
            StructureLayout::Grid { counts }
        }
    })
}

/// Counts at least 1, and a spacing wider than a copy's footprint along every axis with more
/// than one copy (copies that touched would wake each other).
fn array(a: &ArrayToml, structure: &StructureDef, at: &dyn Fn(&str) -> String) -> Checked<StructureArray> {
    if a.counts.contains(&0) {
        return Err(problem(at("array.counts"), format!("must all be at least 1, got {:?}", a.counts)));
    }
    within_bodies(&at("array.counts"), &a.counts)?;
    let size = structure.footprint().size();
    for axis in 0..2 {
        let spacing = finite(&at("array.spacing"), a.spacing[axis])?;
        if a.counts[axis] > 1 && spacing <= size[axis] {
            let message = format!(
                "copies would touch: spacing {:?} is not wider than a copy's footprint [{}, {}]",
                a.spacing, size[0], size[1]
            );
            return Err(problem(at("array.spacing"), message));
        }
    }
    Ok(StructureArray { counts: a.counts, spacing: a.spacing })
}

/// Counts whose product (blocks, or copies of at least one block each) is within
/// [`MAX_BODIES`], so that every later product of counts fits its integer.
fn within_bodies(field: &str, counts: &[u32]) -> Checked<()> {
    let product = counts.iter().try_fold(1u64, |p, &c| p.checked_mul(c as u64).filter(|&p| p <= MAX_BODIES));
    if product.is_none() {
        let message =
            format!("{counts:?} make more than the {MAX_BODIES} bodies allowed (see docs/errors.md)");
        return Err(problem(field, message));
    }
    Ok(())
}

pub(super) fn projectiles(
    raw: &[ProjectileToml],
    prototypes: &[PrototypeDef],
    structures: &[StructureDef],
    frames: u32,
) -> Checked<Vec<ProjectileDef>> {
    raw.iter().enumerate().map(|(i, p)| projectile(i, p, prototypes, structures, frames)).collect()
}

/// A prototype that exists, a first frame the scene reaches, a finite position and velocity,
/// and the keys of its aim: `structure` (one that exists) with `every` and `count`, or
/// world-space launches with `count` and `step`.
fn projectile(
    i: usize,
    p: &ProjectileToml,
    prototypes: &[PrototypeDef],
    structures: &[StructureDef],
    frames: u32,
) -> Checked<ProjectileDef> {
    let at = |f: &str| format!("projectiles[{i}].{f}");
    let prototype = prototypes
        .iter()
        .position(|proto| proto.name == p.prototype)
        .ok_or_else(|| problem(at("prototype"), format!("no prototype named {:?}", p.prototype)))?;
    if p.frame >= frames {
        let message = format!("frame {} is past the last frame ({})", p.frame, frames.saturating_sub(1));
        return Err(problem(at("frame"), message));
    }
    let count =
        p.count.map(|c| at_most(&at("count"), at_least_one(&at("count"), c)?, MAX_BODIES)).transpose()?;
    let aim = match &p.structure {
        Some(name) => {
            if p.step.is_some() {
                return Err(problem(
                    at("step"),
                    "`step` moves world-space launches; with `structure` each copy is a target",
                ));
            }
            let structure = structures
                .iter()
                .position(|s| &s.name == name)
                .ok_or_else(|| problem(at("structure"), format!("no structure named {name:?}")))?;
            let every = at_least_one(&at("every"), p.every.unwrap_or(1))?;
            ProjectileAim::Structure { structure, every, count }
        }
        None => {
            if p.every.is_some() {
                return Err(problem(at("every"), "`every` picks copies of a `structure`, and none is given"));
            }
            let step = finite3(&at("step"), p.step.unwrap_or([0.0; 3]))?;
            ProjectileAim::World { count: count.unwrap_or(1), step }
        }
    };
    Ok(ProjectileDef {
        prototype,
        frame: p.frame,
        interval_frames: p.interval_frames,
        position: finite3(&at("position"), p.position)?,
        velocity: finite3(&at("velocity"), p.velocity)?,
        aim,
    })
}
