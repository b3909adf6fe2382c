//! `[animation]`: a scene whose bodies and environment come from an animated glTF file. Such
//! a scene has no `[environment]` and nothing that makes bodies (prototypes, spawners,
//! structures, projectiles, kinematics, disturbances): the file is the simulation.

use super::{at_least_one, non_negative, problem, Checked};
use crate::scene::file::asset_dir::AssetDir;
use crate::scene::file::schema::{AnimationToml, SceneToml};
use crate::scene::file::spec::{AnimationDef, EnvironmentDef, EnvironmentSource};

/// The environment and the animation of `raw`: exactly one of `[environment]` and
/// `[animation]`, and with `[animation]` no tables that make bodies.
pub(super) fn world_source(
    raw: &SceneToml,
    assets: &AssetDir,
) -> Checked<(EnvironmentDef, Option<AnimationDef>)> {
    match (&raw.environment, &raw.animation) {
        (Some(e), None) => Ok((super::world::environment(e, assets)?, None)),
        (None, Some(a)) => {
            no_bodies_besides(raw)?;
            Ok((EnvironmentDef::of_animation(), Some(animation(a, assets)?)))
        }
        (Some(_), Some(_)) => Err(problem(
            "animation",
            "an [animation] scene takes its environment from the glTF file's static nodes: leave out [environment]",
        )),
        (None, None) => Err(problem("environment", "missing: give [environment] (or [animation] for an animated glTF)")),
    }
}

fn animation(a: &AnimationToml, assets: &AssetDir) -> Checked<AnimationDef> {
    if !assets.resolve(&a.gltf).is_file() {
        return Err(problem(
            "animation.gltf",
            format!("file not found: {}", assets.resolve(&a.gltf).display()),
        ));
    }
    if let Some(fps) = a.fps {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(problem(
                "animation.fps",
                format!("must be a finite number greater than 0, got {fps}"),
            ));
        }
    }
    if let Some(tolerance) = a.rest_tolerance {
        non_negative("animation.rest_tolerance", tolerance)?;
    }
    if let Some(frames) = a.min_rest_frames {
        if at_least_one("animation.min_rest_frames", frames)? < 2 {
            let message = "must be at least 2 (a rest is a pose held from one frame to the next)";
            return Err(problem("animation.min_rest_frames", message));
        }
    }
    Ok(AnimationDef {
        gltf: a.gltf.clone(),
        fps: a.fps,
        name: a.name.clone(),
        rest_tolerance: a.rest_tolerance,
        min_rest_frames: a.min_rest_frames,
    })
}

/// Refuses the tables that make bodies: in an `[animation]` scene the file has them all.
fn no_bodies_besides(raw: &SceneToml) -> Checked<()> {
    let tables = [
        ("prototypes", raw.prototypes.is_empty()),
        ("spawners", raw.spawners.is_empty()),
        ("structures", raw.structures.is_empty()),
        ("projectiles", raw.projectiles.is_empty()),
        ("kinematics", raw.kinematics.is_empty()),
        ("disturbances", raw.disturbances.is_empty()),
    ];
    match tables.iter().find(|(_, empty)| !empty) {
        Some((table, _)) => Err(problem(
            *table,
            "an [animation] scene takes its bodies and their motion from the glTF file: leave this out",
        )),
        None => Ok(()),
    }
}

impl EnvironmentDef {
    /// The environment of an `[animation]` scene: the file's static nodes as they are placed.
    fn of_animation() -> Self {
        Self {
            source: EnvironmentSource::Animation,
            scale: 1.0,
            offset: [0.0; 3],
            friction: 0.6,
            collider_cells: 1,
        }
    }
}
