//! The `asset` object with dormant's extras: the format, frame rate and count, and the scene
//! file's TOML without what the glTF file itself holds (meshes, bodies and their physics), so
//! that the importer takes the exact cameras, lights, sky and render settings from it; and the
//! simulation's islands and kinematic bodies, so that it replays the same rests.

use serde_json::{json, Value};

use super::{GltfExportError, GLTF_FORMAT};
use crate::physics::trajectory::Trajectory;
use crate::physics::{BodyKind, IslandEvent};

/// Top-level tables of the scene file the glTF file replaces.
const REMOVED_TABLES: [&str; 8] = [
    "environment",
    "prototypes",
    "spawners",
    "kinematics",
    "disturbances",
    "structures",
    "projectiles",
    "physics",
];

/// Keys of the `[scene]` table the glTF file replaces.
const REMOVED_SCENE_KEYS: [&str; 2] = ["frames", "assets"];

/// The simulation's islands as `[first frame, frame it woke or null, [bodies]]`, and its
/// kinematic bodies: rests and kinds the glTF animation alone cannot give back exactly.
pub(super) fn simulation(trajectory: &Trajectory) -> Value {
    let mut islands: Vec<(u32, Option<u32>, Vec<u32>)> = Vec::new();
    let mut index_of = std::collections::HashMap::new();
    for (f, frame) in trajectory.frames.iter().enumerate() {
        for event in &frame.events {
            match event {
                IslandEvent::Slept { island, bodies, .. } => {
                    index_of.insert(*island, islands.len());
                    islands.push((f as u32, None, bodies.iter().map(|b| b.0).collect()));
                }
                IslandEvent::Woke { island } => {
                    if let Some(&i) = index_of.get(island) {
                        islands[i].1 = Some(f as u32);
                    }
                }
            }
        }
    }
    let kinematic: Vec<u32> = (0..trajectory.bodies.len() as u32)
        .filter(|&b| trajectory.bodies[b as usize].kind == BodyKind::Kinematic)
        .collect();
    json!({ "islands": islands, "kinematic": kinematic })
}

/// The glTF `asset` object.
pub(super) fn asset(
    fps: f64,
    frames: u32,
    scene_source: &str,
    simulation: Value,
) -> Result<Value, GltfExportError> {
    Ok(json!({
        "version": "2.0",
        "generator": concat!("dormant ", env!("CARGO_PKG_VERSION")),
        "extras": { "dormant": {
            "format": GLTF_FORMAT,
            "fps": fps,
            "frames": frames,
            "rest_tolerance": 0.0,
            "min_rest_frames": 2,
            "scene": scene_toml(scene_source)?,
            "simulation": simulation,
        } },
    }))
}

/// `source` (a scene file) without the tables and keys the glTF file replaces.
pub(super) fn scene_toml(source: &str) -> Result<String, GltfExportError> {
    let mut table: toml::Table =
        source.parse().map_err(|e: toml::de::Error| GltfExportError::SceneToml(e.to_string()))?;
    for key in REMOVED_TABLES {
        table.remove(key);
    }
    if let Some(toml::Value::Table(scene)) = table.get_mut("scene") {
        for key in REMOVED_SCENE_KEYS {
            scene.remove(key);
        }
    }
    toml::to_string(&table).map_err(|e| GltfExportError::SceneToml(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::scene_toml;

    #[test]
    fn the_recorded_scene_keeps_cameras_lights_and_render_settings_only() {
        let source = "[scene]\nname = \"t\"\nframes = 10\nassets = \"a\"\nseed = 3\n\n[physics]\ntimestep = 0.01\n\n\
                      [environment]\ngenerator = \"ground\"\n\n[[prototypes]]\nname = \"b\"\nshape = \"box\"\n\n\
                      [[cameras]]\nname = \"main\"\nposition = [0.0, 1.0, 2.0]\nlook_at = [0.0, 0.0, 0.0]\n\n\
                      [render]\nwidth = 32\n";
        let table: toml::Table = scene_toml(source).unwrap().parse().unwrap();
        let sorted = |t: &toml::Table| {
            let mut keys: Vec<String> = t.keys().cloned().collect();
            keys.sort();
            keys
        };
        assert_eq!(sorted(&table), ["cameras", "render", "scene"]);
        assert_eq!(sorted(table["scene"].as_table().unwrap()), ["name", "seed"]);
        assert_eq!(table["cameras"][0]["position"][2].as_float(), Some(2.0));
    }
}
