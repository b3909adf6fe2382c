//! The raw TOML shape to the checked [`SceneSpec`]: finite numbers, positive counts and
//! sizes, references resolved to indices, asset files that exist. One function per section:
//! scene, physics and the asset directory here; `world`: environment and prototypes;
//! `motion`: spawners, kinematic bodies and disturbances; `structures`: structures and
//! projectiles; `view`: cameras, sky, lights and render settings. [`validate`] checks them in that order and stops at the first problem,
//! which it reports by field path (the parser adds file and line).

mod animation;
mod motion;
mod structures;
mod view;
mod world;

pub(super) use structures::apart as structures_apart;

use super::asset_dir::AssetDir;
use super::schema::SceneToml;
use super::spec::{PhysicsSettings, ProjectileAim, ProjectileDef, SceneInfo, SceneSpec, StructureDef};
use crate::scene::limits::{MAX_BODIES, MAX_FRAMES};

/// One thing wrong with a scene, at a field path such as `spawners[1].count`.
#[derive(Debug)]
pub(super) struct Problem {
    pub field: String,
    pub message: String,
}

/// A checked value, or the first problem found on the way to it.
type Checked<T> = Result<T, Problem>;

/// Checks `raw` section by section and builds the spec; relative asset paths resolve
/// against `assets`.
pub(super) fn validate(raw: &SceneToml, assets: &AssetDir) -> Result<SceneSpec, Problem> {
    let scene = scene(&raw.scene, raw.animation.is_some())?;
    let physics = physics(&raw.physics)?;
    if raw.scene.assets.is_some() && !assets.is_overridden() && !assets.path().is_dir() {
        return Err(problem("scene.assets", format!("directory not found: {}", assets.path().display())));
    }
    let (environment, animation) = animation::world_source(raw, assets)?;
    let prototypes = world::prototypes(&raw.prototypes, assets)?;
    let spawners = motion::spawners(&raw.spawners, &prototypes)?;
    let kinematics = motion::kinematics(&raw.kinematics, &prototypes)?;
    let disturbances = motion::disturbances(&raw.disturbances, scene.frames)?;
    let structures = structures::structures(&raw.structures, &prototypes)?;
    let projectiles = structures::projectiles(&raw.projectiles, &prototypes, &structures, scene.frames)?;
    let cameras = view::cameras(&raw.cameras)?;
    let sky = raw.sky.as_ref().map(view::sky).transpose()?;
    let lights = view::lights(&raw.lights)?;
    let render = view::render(&raw.render, &cameras)?;
    let spec = SceneSpec {
        scene,
        physics,
        environment,
        animation,
        prototypes,
        spawners,
        kinematics,
        disturbances,
        structures,
        projectiles,
        cameras,
        lights,
        sky,
        render,
    };
    within_body_budget(&spec)?;
    Ok(spec)
}

/// All dynamic bodies together (spawned, built, thrown and key-framed) within
/// [`MAX_BODIES`]; the error names the section whose bodies pass it. Each section's counts
/// were bounded on their own, so the sums cannot overflow.
pub(super) fn within_body_budget(spec: &SceneSpec) -> Checked<()> {
    let thrown = |p: &ProjectileDef| match p.aim {
        ProjectileAim::World { count, .. } => count as u64,
        ProjectileAim::Structure { structure, every, count } => {
            let copies = (spec.structures[structure].copies() as u64).div_ceil(every as u64);
            count.map_or(copies, |c| copies.min(c as u64))
        }
    };
    let sections: [(&str, u64); 4] = [
        ("spawners", spec.spawners.iter().map(|s| s.count as u64).sum()),
        ("structures", spec.structures.iter().map(StructureDef::body_count).sum()),
        ("projectiles", spec.projectiles.iter().map(thrown).sum()),
        ("kinematics", spec.kinematics.len() as u64),
    ];
    let mut total = 0u64;
    for (section, bodies) in sections {
        total += bodies;
        if total > MAX_BODIES {
            let message = format!(
                "the scene would have {total} bodies with these {section}, more than the {MAX_BODIES} allowed \
                 (what simulates in the memory of a 24 GiB machine; see docs/errors.md)"
            );
            return Err(problem(section, message));
        }
    }
    Ok(())
}

/// `[scene]`: a name and at least one frame (or, in an `[animation]` scene, none given: the
/// animation's length).
fn scene(s: &SceneInfo, animated: bool) -> Checked<SceneInfo> {
    if s.name.trim().is_empty() {
        return Err(problem("scene.name", "must not be empty"));
    }
    if !(animated && s.frames == 0) {
        at_most("scene.frames", at_least_one("scene.frames", s.frames)?, MAX_FRAMES)?;
    }
    Ok(s.clone())
}

/// `[physics]`: a positive timestep, at least one substep and solver iteration, finite
/// gravity and kill plane, thresholds, times and damping not negative.
fn physics(p: &PhysicsSettings) -> Checked<PhysicsSettings> {
    positive("physics.timestep", p.timestep)?;
    at_least_one("physics.substeps", p.substeps)?;
    finite3("physics.gravity", p.gravity)?;
    non_negative("physics.sleep_linear_threshold", p.sleep_linear_threshold)?;
    non_negative("physics.sleep_angular_threshold", p.sleep_angular_threshold)?;
    non_negative("physics.sleep_time", p.sleep_time)?;
    finite("physics.kill_plane_y", p.kill_plane_y)?;
    at_least_one("physics.solver_iterations", p.solver_iterations)?;
    non_negative("physics.linear_damping", p.linear_damping)?;
    non_negative("physics.angular_damping", p.angular_damping)?;
    Ok(p.clone())
}

/// A table whose variant (`what`, e.g. "shape Box") takes the keys `wanted` of the optional
/// keys `given` (name, written?): each must be written exactly when wanted.
fn exactly_the_keys(
    what: &str,
    wanted: &[&str],
    given: &[(&str, bool)],
    at: &dyn Fn(&str) -> String,
) -> Checked<()> {
    for &(name, present) in given {
        let needed = wanted.contains(&name);
        if needed && !present {
            return Err(problem(at(name), format!("{what} needs `{name}`")));
        } else if !needed && present {
            return Err(problem(at(name), format!("{what} does not use `{name}`")));
        }
    }
    Ok(())
}

fn problem(field: impl Into<String>, message: impl Into<String>) -> Problem {
    Problem { field: field.into(), message: message.into() }
}

fn finite(field: &str, v: f32) -> Checked<f32> {
    if !v.is_finite() {
        return Err(problem(field, format!("must be a finite number, got {v}")));
    }
    Ok(v)
}

fn finite3(field: &str, v: [f32; 3]) -> Checked<[f32; 3]> {
    if v.iter().any(|x| !x.is_finite()) {
        return Err(problem(field, format!("must be finite numbers, got {v:?}")));
    }
    Ok(v)
}

fn positive(field: &str, v: f32) -> Checked<f32> {
    if finite(field, v)? <= 0.0 {
        return Err(problem(field, format!("must be greater than 0, got {v}")));
    }
    Ok(v)
}

fn non_negative(field: &str, v: f32) -> Checked<f32> {
    if finite(field, v)? < 0.0 {
        return Err(problem(field, format!("must not be negative, got {v}")));
    }
    Ok(v)
}

/// `v` no more than `max`, the bound of [`crate::scene::limits`] that `field` falls under.
fn at_most(field: &str, v: u32, max: impl Into<u64>) -> Checked<u32> {
    let max = max.into();
    if v as u64 > max {
        return Err(problem(field, format!("must be at most {max}, got {v} (see docs/errors.md)")));
    }
    Ok(v)
}

fn at_least_one(field: &str, v: u32) -> Checked<u32> {
    if v == 0 {
        return Err(problem(field, "must be at least 1, got 0"));
    }
    Ok(v)
}
