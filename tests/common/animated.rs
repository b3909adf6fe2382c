//! A small animated glTF written by hand, as a rigid-body bake from another tool would be: a
//! static ground, and unit cubes that are bodies (two fall and land together, one spins, one
//! appears late and stays). [`AnimatedFile`] holds its JSON and binary buffer so tests can
//! break one field and write the result as a `.glb`.

use std::path::Path;

use serde_json::{json, Value};

/// Frames per second the keys are written at.
pub const FPS: f64 = 24.0;
/// Frames with keys (0..FRAMES).
pub const FRAMES: u32 = 48;
/// The first frame the two falling cubes rest at (y = 3 - 5 t² reaches 0.5 at t = 0.707 s).
pub const LANDING: u32 = 17;
/// The frame the late cube appears at.
pub const APPEARS: u32 = 10;

/// A glTF document and its one binary buffer.
pub struct AnimatedFile {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl AnimatedFile {
    /// Adds `values` (f32) to the buffer as an accessor of `kind` (`SCALAR`, `VEC3`, `VEC4`);
    /// returns its index.
    pub fn accessor(&mut self, values: &[f32], kind: &str) -> usize {
        let width = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            _ => 4,
        };
        let offset = self.bin.len();
        self.bin.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": values.len() * 4}));
        let view = views.len() - 1;
        let mut accessor =
            json!({"bufferView": view, "componentType": 5126, "count": values.len() / width, "type": kind});
        if kind == "VEC3" && values.len() >= 3 {
            let axis = |a: usize| values.iter().skip(a).step_by(3).copied();
            let min: Vec<f32> = (0..3).map(|a| axis(a).fold(f32::INFINITY, f32::min)).collect();
            let max: Vec<f32> = (0..3).map(|a| axis(a).fold(f32::NEG_INFINITY, f32::max)).collect();
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        accessors.push(accessor);
        accessors.len() - 1
    }

    /// Adds u32 triangle indices; returns the accessor's index.
    fn indices(&mut self, indices: &[u32]) -> usize {
        let offset = self.bin.len();
        self.bin.extend(indices.iter().flat_map(|v| v.to_le_bytes()));
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": indices.len() * 4}));
        let view = views.len() - 1;
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        accessors.push(
            json!({"bufferView": view, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}),
        );
        accessors.len() - 1
    }

    /// Adds a channel of `node`'s `path` with keys at `times` (seconds); returns the channel's
    /// index in animation 0.
    pub fn channel(
        &mut self,
        node: usize,
        path: &str,
        interpolation: &str,
        times: &[f32],
        values: &[f32],
    ) -> usize {
        let kind = if path == "rotation" { "VEC4" } else { "VEC3" };
        let input = self.accessor(times, "SCALAR");
        let output = self.accessor(values, kind);
        let animation = &mut self.json["animations"][0];
        let samplers = animation["samplers"].as_array_mut().unwrap();
        samplers.push(json!({"input": input, "output": output, "interpolation": interpolation}));
        let sampler = samplers.len() - 1;
        let channels = animation["channels"].as_array_mut().unwrap();
        channels.push(json!({"sampler": sampler, "target": {"node": node, "path": path}}));
        channels.len() - 1
    }

    /// Gives sampler `sampler` of animation 0 new output `values` (keys at the same times).
    pub fn set_output(&mut self, sampler: usize, values: &[f32]) {
        let kind = if values.len() % 4 == 0 && values.len() % 3 != 0 { "VEC4" } else { "VEC3" };
        let output = self.accessor(values, kind);
        self.json["animations"][0]["samplers"][sampler]["output"] = output.into();
    }

    /// The accessor sampler `sampler` of animation 0 reads its output from.
    pub fn output_accessor(&self, sampler: usize) -> usize {
        self.json["animations"][0]["samplers"][sampler]["output"].as_u64().unwrap() as usize
    }

    /// The file as GLB bytes.
    pub fn glb(&self) -> Vec<u8> {
        let mut json = self.json.clone();
        json["buffers"] = json!([{"byteLength": self.bin.len()}]);
        let mut text = serde_json::to_vec(&json).unwrap();
        text.resize(text.len().next_multiple_of(4), b' ');
        let mut bin = self.bin.clone();
        bin.resize(bin.len().next_multiple_of(4), 0);
        let total = 12 + 8 + text.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((text.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(text);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out
    }

    /// Writes the GLB to `path`.
    pub fn write(&self, path: &Path) {
        std::fs::write(path, self.glb()).unwrap();
    }
}

/// The time of frame `i` as the importer samples it.
pub fn time(i: u32) -> f32 {
    (i as f64 / FPS) as f32
}

/// The scene described in the module docs. Nodes: 0 ground, 1 and 2 the falling cubes, 3 the
/// spinning cube, 4 the late cube, 5 the camera.
pub fn falling_cubes() -> AnimatedFile {
    let mut file = AnimatedFile {
        json: json!({
            "asset": {"version": "2.0", "generator": "dormant tests"},
            "scene": 0,
            "scenes": [{"nodes": [0, 1, 2, 3, 4, 5]}],
            "accessors": [], "bufferViews": [], "meshes": [],
            "materials": [
                {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1.0], "metallicFactor": 0.0}},
                {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.1, 1.0], "metallicFactor": 0.0}}
            ],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}],
            "animations": [{"name": "bake", "samplers": [], "channels": []}]
        }),
        bin: Vec::new(),
    };
    let ground =
        file.accessor(&[-10.0, 0.0, -10.0, 10.0, 0.0, -10.0, 10.0, 0.0, 10.0, -10.0, 0.0, 10.0], "VEC3");
    let ground_indices = file.indices(&[0, 2, 1, 0, 3, 2]);
    let (cube, cube_indices) = cube(&mut file);
    file.json["meshes"] = json!([
        {"name": "ground", "primitives": [{"attributes": {"POSITION": ground}, "indices": ground_indices, "material": 0}]},
        {"name": "cube", "primitives": [{"attributes": {"POSITION": cube}, "indices": cube_indices, "material": 1}]}
    ]);
    let pitch = (-0.3f32 / 2.0).sin();
    file.json["nodes"] = json!([
        {"name": "ground", "mesh": 0},
        {"name": "left", "mesh": 1},
        {"name": "right", "mesh": 1},
        {"name": "spinner", "mesh": 1, "translation": [0.0, 0.5, 3.0]},
        {"name": "late", "mesh": 1, "translation": [0.0, 0.5, -3.0]},
        {"name": "camera", "camera": 0, "translation": [0.0, 4.0, 12.0], "rotation": [pitch, 0.0, 0.0, (1.0 - pitch * pitch).sqrt()]}
    ]);
    let times: Vec<f32> = (0..FRAMES).map(time).collect();
    for (node, x) in [(1, -1.5f32), (2, 1.5)] {
        let fall: Vec<f32> = times.iter().flat_map(|&t| [x, (3.0 - 5.0 * t * t).max(0.5), 0.0]).collect();
        file.channel(node, "translation", "LINEAR", &times, &fall);
    }
    let spin: Vec<f32> = times.iter().flat_map(|&t| [0.0, (t / 2.0).sin(), 0.0, (t / 2.0).cos()]).collect();
    file.channel(3, "rotation", "LINEAR", &times, &spin);
    file.channel(4, "scale", "STEP", &[0.0, time(APPEARS)], &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    file
}

/// A unit cube (half size 0.5): positions and indices accessors.
fn cube(file: &mut AnimatedFile) -> (usize, usize) {
    let mut positions = Vec::new();
    for i in 0..8u32 {
        positions.extend([(i & 1) as f32 - 0.5, ((i >> 1) & 1) as f32 - 0.5, ((i >> 2) & 1) as f32 - 0.5]);
    }
    let faces: [[u32; 4]; 6] =
        [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let indices: Vec<u32> = faces.iter().flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]]).collect();
    (file.accessor(&positions, "VEC3"), file.indices(&indices))
}

/// A scene file for `glb` (beside it) sampled at [`FPS`], with `extra` lines appended to
/// its `[animation]` table.
pub fn scene_toml(extra: &str) -> String {
    format!(
        "[scene]\nname = \"falling cubes\"\n\n[animation]\ngltf = \"cubes.glb\"\nfps = {FPS:?}\n{extra}\n"
    )
}
