//! `[[spawners]]`, `[[kinematics]]` and `[[disturbances]]`: what moves, and when.

use std::collections::BTreeSet;

use super::{at_least_one, at_most, finite, finite3, non_negative, positive, problem, Checked};
use crate::scene::file::schema::{DisturbanceTag, DisturbanceToml, KinematicToml, SpawnerToml};
use crate::scene::file::spec::{
    DisturbanceDef, DisturbanceKind, KeyframeDef, KinematicDef, PrototypeDef, SpawnerDef,
};
use crate::scene::limits::MAX_BODIES;

/// The index of the prototype called `name`.
fn prototype_index(prototypes: &[PrototypeDef], name: &str) -> Option<usize> {
    prototypes.iter().position(|p| p.name == name)
}

pub(super) fn spawners(raw: &[SpawnerToml], prototypes: &[PrototypeDef]) -> Checked<Vec<SpawnerDef>> {
    raw.iter().enumerate().map(|(i, s)| spawner(i, s, prototypes)).collect()
}

/// Prototypes that exist (at least one), a count and waves with no empty wave, a region
/// whose `min` is nowhere above its `max`, times and jitters not negative.
fn spawner(i: usize, s: &SpawnerToml, prototypes: &[PrototypeDef]) -> Checked<SpawnerDef> {
    let at = |f: &str| format!("spawners[{i}].{f}");
    if s.prototypes.is_empty() {
        return Err(problem(at("prototypes"), "must name at least one prototype"));
    }
    let indices = s
        .prototypes
        .iter()
        .enumerate()
        .map(|(j, name)| {
            prototype_index(prototypes, name).ok_or_else(|| {
                problem(format!("spawners[{i}].prototypes[{j}]"), format!("no prototype named {name:?}"))
            })
        })
        .collect::<Checked<Vec<_>>>()?;
    let count = at_most(&at("count"), at_least_one(&at("count"), s.count)?, MAX_BODIES)?;
    let waves = at_least_one(&at("waves"), s.waves)?;
    if waves > count {
        return Err(problem(
            at("waves"),
            format!("{waves} waves for {count} objects: a wave would be empty"),
        ));
    }
    let (lo, hi) = (finite3(&at("region.min"), s.region.min)?, finite3(&at("region.max"), s.region.max)?);
    if (0..3).any(|k| lo[k] > hi[k]) {
        return Err(problem(at("region"), format!("min {lo:?} exceeds max {hi:?}")));
    }
    let wave_interval = non_negative(&at("wave_interval"), s.wave_interval)?;
    let start_time = non_negative(&at("start_time"), s.start_time)?;
    let initial_velocity = finite3(&at("initial_velocity"), s.initial_velocity)?;
    let velocity_jitter = non_negative(&at("velocity_jitter"), s.velocity_jitter)?;
    let position_jitter = non_negative(&at("position_jitter"), s.position_jitter)?;
    Ok(SpawnerDef {
        prototypes: indices,
        count,
        region: s.region,
        pattern: s.pattern,
        position_jitter,
        waves,
        wave_interval,
        start_time,
        seed: s.seed.unwrap_or(i as u64),
        initial_velocity,
        velocity_jitter,
        random_rotation: s.random_rotation,
    })
}

/// Unique names, prototypes that exist, and key-framed paths (two keys at least when looped).
pub(super) fn kinematics(raw: &[KinematicToml], prototypes: &[PrototypeDef]) -> Checked<Vec<KinematicDef>> {
    let mut names = BTreeSet::new();
    let mut kinematics = Vec::with_capacity(raw.len());
    for (i, k) in raw.iter().enumerate() {
        let at = |f: &str| format!("kinematics[{i}].{f}");
        if !names.insert(k.name.as_str()) {
            return Err(problem(at("name"), format!("duplicate kinematic body name {:?}", k.name)));
        }
        let prototype = prototype_index(prototypes, &k.prototype)
            .ok_or_else(|| problem(at("prototype"), format!("no prototype named {:?}", k.prototype)))?;
        if k.keyframes.is_empty() {
            return Err(problem(at("keyframes"), "needs at least one keyframe"));
        }
        keyframes(i, &k.keyframes)?;
        if k.looped && k.keyframes.len() < 2 {
            return Err(problem(at("looped"), "a looped path needs at least two keyframes"));
        }
        kinematics.push(KinematicDef {
            name: k.name.clone(),
            prototype,
            keyframes: k.keyframes.clone(),
            looped: k.looped,
        });
    }
    Ok(kinematics)
}

/// Key times not negative and increasing, finite positions and headings.
fn keyframes(i: usize, keys: &[KeyframeDef]) -> Checked<()> {
    let mut last = f32::NEG_INFINITY;
    for (j, key) in keys.iter().enumerate() {
        let at = |f: &str| format!("kinematics[{i}].keyframes[{j}].{f}");
        let time = finite(&at("time"), key.time)?;
        if time < 0.0 {
            return Err(problem(at("time"), "must not be negative"));
        } else if time <= last {
            return Err(problem(at("time"), format!("keyframe times must increase ({time} after {last})")));
        }
        last = time;
        finite3(&at("position"), key.position)?;
        finite(&at("yaw_degrees"), key.yaw_degrees)?;
    }
    Ok(())
}

/// A frame the scene reaches, a finite centre, a positive radius, and exactly the field the
/// kind takes (`impulse`, finite; `strength`, positive).
pub(super) fn disturbances(raw: &[DisturbanceToml], frames: u32) -> Checked<Vec<DisturbanceDef>> {
    let mut disturbances = Vec::with_capacity(raw.len());
    for (i, d) in raw.iter().enumerate() {
        let at = |f: &str| format!("disturbances[{i}].{f}");
        if d.frame >= frames {
            let message = format!("frame {} is past the last frame ({})", d.frame, frames.saturating_sub(1));
            return Err(problem(at("frame"), message));
        }
        let center = finite3(&at("center"), d.center)?;
        let radius = positive(&at("radius"), d.radius)?;
        let kind = match d.kind {
            DisturbanceTag::Impulse => {
                let impulse =
                    d.impulse.ok_or_else(|| problem(at("impulse"), "an impulse disturbance needs `impulse`"));
                let impulse = finite3(&at("impulse"), impulse?)?;
                if d.strength.is_some() {
                    return Err(problem(at("strength"), "only explosions take `strength`"));
                }
                DisturbanceKind::Impulse { impulse }
            }
            DisturbanceTag::Explosion => {
                let strength =
                    d.strength.ok_or_else(|| problem(at("strength"), "an explosion needs `strength`"));
                let strength = positive(&at("strength"), strength?)?;
                if d.impulse.is_some() {
                    return Err(problem(at("impulse"), "only impulses take `impulse`"));
                }
                DisturbanceKind::Explosion { strength }
            }
        };
        disturbances.push(DisturbanceDef { frame: d.frame, center, radius, kind });
    }
    Ok(disturbances)
}
