//! Scene files the program carries or writes itself: the atrium of the paper's experiment
//! (compiled in from `scenes/atrium.toml`) and an "asset rain" over any environment glTF, the
//! monastery variant of `dormant bench paper`. Both go through the ordinary parser and
//! validation, so they are plain [`SceneFile`]s like any on disk.

use std::path::{Path, PathBuf};

use super::parse::SceneFile;
use super::SceneError;
use crate::geometry::Aabb;
use crate::scene::gltf::load_gltf_mesh;

const ATRIUM_TOML: &str = include_str!("../../../../../scenes/atrium.toml");

/// Objects are scaled so their largest extent is this fraction of the environment's width:
/// `scenes/monastery-rain.toml`'s hand-picked scales (ducks, teddies and balls of about 0.8
/// units in a 123-unit monastery) as a rule.
const OBJECT_FRACTION_OF_WIDTH: f32 = 1.0 / 150.0;
/// Objects spawn over this central fraction of the environment's width and depth.
const SPAWN_FRACTION: f32 = 0.6;
/// Gap between the two spawn quadrants and the centre lines, as a fraction of the extent.
const SPAWN_GAP_FRACTION: f32 = 0.04;
/// Height of the spawn plane above the environment's top, in object sizes.
const SPAWN_CLEARANCE_OBJECTS: f32 = 5.0;

impl SceneFile {
    /// The paper's atrium (8,000 objects raining onto a Sponza-like atrium), as compiled in.
    pub fn atrium() -> SceneFile {
        SceneFile::parse("scenes/atrium.toml (built in)", ATRIUM_TOML)
            .expect("the compiled-in atrium scene is valid (tests/bench_paper.rs)")
    }

    /// `count` copies of the `objects` glTFs (picked at random) raining in eight waves over two
    /// opposite quadrants of the `env` glTF, simulated for `frames` frames: `scenes/monastery-rain.toml` for any assets.
    /// Objects get convex-hull colliders and a scale relative to the environment's width.
    pub fn asset_rain(
        env: &Path,
        objects: &[PathBuf],
        count: u32,
        frames: u32,
    ) -> Result<SceneFile, SceneError> {
        let bounds = |path: &Path, field: &str| {
            load_gltf_mesh(path).map(|m| m.bounds()).map_err(|source| SceneError::Asset {
                file: path.to_path_buf(),
                line: None,
                field: field.into(),
                source: Box::new(source),
            })
        };
        // Absolute paths: the generated file has no directory to resolve relative ones against.
        let absolute = |p: &Path, field: &str| {
            std::path::absolute(p).map_err(|e| SceneError::Invalid {
                file: p.to_path_buf(),
                line: None,
                field: field.into(),
                message: e.to_string(),
            })
        };
        let env = absolute(env, "--env")?;
        let env = env.as_path();
        let env_bounds = bounds(env, "--env")?;
        let width = env_bounds.extent().x.max(env_bounds.extent().z);
        let object_size = width * OBJECT_FRACTION_OF_WIDTH;
        let quoted = |p: &Path| serde_json::to_string(&p.to_string_lossy()).expect("strings serialise");

        let mut text = format!(
            "# Written by SceneFile::asset_rain for {env}.\n\
             [scene]\nname = \"asset-rain\"\nseed = 11\nframes = {frames}\n\n\
             [physics]\ntimestep = 0.016666667\nangular_damping = 0.8\nlinear_damping = 0.05\n\
             sleep_linear_threshold = 0.15\nkill_plane_y = {kill}\n\n\
             [environment]\ngltf = {env_path}\nfriction = 0.7\n\n",
            env = env.display(),
            kill = env_bounds.min.y - 20.0,
            env_path = quoted(env),
        );
        let mut names = Vec::new();
        for (i, object) in objects.iter().enumerate() {
            let object = absolute(object, "--object")?;
            let object = object.as_path();
            let extent = bounds(object, "--object")?.extent().max_element().max(1e-6);
            let name = format!("object-{i}");
            text += &format!(
                "[[prototypes]]\nname = \"{name}\"\nshape = \"gltf\"\ngltf = {path}\nscale = {scale}\n\
                 collider = \"convex_hull\"\n\n",
                path = quoted(object),
                scale = object_size / extent,
            );
            names.push(format!("\"{name}\""));
        }
        text += &rain_spawners(&env_bounds, object_size, &names, count);
        let centre = env_bounds.center();
        let eye = centre + glam::Vec3::new(0.0, 0.55 * width, 0.85 * width);
        text += &format!(
            "[[cameras]]\nname = \"overview\"\nposition = [{}, {}, {}]\nlook_at = [{}, {}, {}]\n\
             fov_degrees = 50.0\n\n\
             [[lights]]\nkind = \"directional\"\ndirection = [-0.4, -1.0, -0.2]\nintensity = 4.0\n\n\
             [render]\ncamera = \"overview\"\n",
            eye.x, eye.y, eye.z, centre.x, env_bounds.min.y, centre.z
        );
        let name = format!("asset rain over {}", env.display());
        SceneFile::parse(name, text)
    }
}

/// Two `[[spawners]]` over opposite quadrants of the central area of `env`, half the `count`
/// objects each, the second a little later, as scenes/monastery-rain.toml does: one region
/// over the centre left many of them awake on roofs
/// (docs/lab/paper.md#2026-11-22-the-first-committed-bench-paper-run).
/// `names` are the prototypes' quoted names.
fn rain_spawners(env: &Aabb, object_size: f32, names: &[String], count: u32) -> String {
    let centre = env.center();
    let half = env.extent() * (0.5 * SPAWN_FRACTION);
    let gap = env.extent() * SPAWN_GAP_FRACTION;
    let y = env.max.y + SPAWN_CLEARANCE_OBJECTS * object_size;
    let quadrants = [(-1.0f32, -1.0f32, 0.0f32), (1.0, 1.0, 0.3)];
    let mut text = String::new();
    for (k, (sx, sz, start)) in quadrants.into_iter().enumerate() {
        let (xa, xb) = (centre.x + sx * gap.x, centre.x + sx * half.x);
        let (za, zb) = (centre.z + sz * gap.z, centre.z + sz * half.z);
        text += &format!(
            "[[spawners]]\nprototypes = [{names}]\ncount = {count}\n\
             region = {{ min = [{x0}, {y}, {z0}], max = [{x1}, {y}, {z1}] }}\n\
             waves = 8\nwave_interval = 0.75\nstart_time = {start}\nposition_jitter = {jitter}\n\n",
            names = names.join(", "),
            count = count / 2 + (count % 2) * u32::from(k == 0),
            x0 = xa.min(xb),
            x1 = xa.max(xb),
            z0 = za.min(zb),
            z1 = za.max(zb),
            jitter = 0.1 * object_size,
        );
    }
    text
}
