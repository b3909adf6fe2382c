//! A glTF file given where a scene file is expected (`dormant render anim.glb`): the scene
//! file it stands for is the scene recorded in its `dormant` extras (what `dormant export
//! --gltf` writes: cameras, lights, sky, render settings), or a bare `[scene]` named after
//! the file, with `[animation]` pointing at the file itself.

use std::path::Path;

use super::SceneError;
use crate::scene::gltf::animated::scene_extras;

/// Whether `path` names a glTF file (by its extension).
pub(super) fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb") || e.eq_ignore_ascii_case("gltf"))
}

/// The text of the scene file `path` (a glTF file) stands for; `fps`, when given, is its
/// `[animation]`'s frame rate (the command line's `--fps`).
pub(super) fn scene_text_of_gltf(path: &Path, fps: Option<f64>) -> Result<String, SceneError> {
    let asset_error = |source| SceneError::Asset {
        file: path.to_path_buf(),
        line: None,
        field: "scene".into(),
        source: Box::new(source),
    };
    let recorded = scene_extras(path).map_err(asset_error)?;
    let name = path.file_stem().map_or("animation".into(), |s| s.to_string_lossy().into_owned());
    let file_name = path.file_name().map_or(String::new(), |s| s.to_string_lossy().into_owned());
    let foreign = recorded.is_none();
    let mut text = recorded.unwrap_or_else(|| format!("[scene]\nname = {}\n", toml_string(&name)));
    text.push_str(&format!("\n[animation]\ngltf = {}\n", toml_string(&file_name)));
    // dormant's own export records its rate; a bake from another tool (Blender's exporter)
    // records none, and renders at the film rate unless `--fps` says otherwise.
    let fps = fps.or_else(|| {
        foreign.then(|| {
            tracing::warn!(
                "{}: the file records no frame rate: {DEFAULT_GLTF_FPS} fps (give --fps to change it)",
                path.display()
            );
            DEFAULT_GLTF_FPS
        })
    });
    if let Some(fps) = fps {
        text.push_str(&format!("fps = {}\n", toml::Value::Float(fps)));
    }
    Ok(text)
}

/// The frame rate of a glTF file given as the scene that records none.
const DEFAULT_GLTF_FPS: f64 = 24.0;

/// `s` as a TOML basic string.
fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}
