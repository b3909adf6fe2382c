//! Reading a scene file: TOML text -> the raw [`SceneToml`] -> checked [`SceneSpec`], with
//! errors that name the file, line and field. [`SceneFile`] keeps the checked spec with where
//! it came from; command-line overrides make a new `SceneFile` rather than changing one.

use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

use super::animated_gltf::{is_gltf, scene_text_of_gltf};
use super::asset_dir::AssetDir;
use super::count::spread_count;
use super::location::{line_of, syntax_error};
use super::schema::SceneToml;
use super::spec::{SceneInfo, SceneSpec};
use super::validate::{structures_apart, validate, within_body_budget, Problem};
use super::SceneError;

/// A checked scene file: its [`SceneSpec`] plus where it came from. Plain data, built only by
/// parsing (and by the overrides, which return a new one).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFile {
    path: PathBuf,
    source: String,
    source_hash: u64,
    assets: AssetDir,
    spec: SceneSpec,
}

impl SceneFile {
    /// Reads, parses and validates a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        Self::load_with_assets(path, None)
    }

    /// Like [`Self::load`], resolving relative asset paths against `assets` (when given)
    /// instead of the scene's `scene.assets` directory.
    /// A `.glb` or `.gltf` file stands for the scene recorded in it (see
    /// `animated_gltf`).
    pub fn load_with_assets(path: impl AsRef<Path>, assets: Option<&Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        if is_gltf(path) {
            return Self::parse_with_assets(path, scene_text_of_gltf(path, None)?, assets.or(path.parent()));
        }
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Io { file: path.to_path_buf(), source })?;
        Self::parse_with_assets(path, text, assets)
    }

    /// [`Self::load_with_assets`] with the frame rate of a glTF file given as the scene
    /// (`--fps`), which goes into its `[animation]` as a scene file would give it. A scene file
    /// states its own rate: `fps` with one is an error.
    pub fn load_with_fps(
        path: impl AsRef<Path>,
        assets: Option<&Path>,
        fps: Option<f64>,
    ) -> Result<Self, SceneError> {
        let path = path.as_ref();
        match fps {
            None => Self::load_with_assets(path, assets),
            Some(fps) if is_gltf(path) => {
                Self::parse_with_assets(path, scene_text_of_gltf(path, Some(fps))?, assets.or(path.parent()))
            }
            Some(_) => Err(SceneError::Invalid {
                file: path.to_path_buf(),
                line: None,
                field: "--fps".into(),
                message: "applies to a glTF file given as the scene; a scene file gives `fps` in [animation]"
                    .into(),
            }),
        }
    }

    /// Parses and validates scene text; `path` names it in messages and anchors relative
    /// asset paths.
    pub fn parse(path: impl AsRef<Path>, text: impl Into<String>) -> Result<Self, SceneError> {
        Self::parse_with_assets(path, text, None)
    }

    /// Like [`Self::parse`] with an asset directory override.
    pub(crate) fn parse_with_assets(
        path: impl AsRef<Path>,
        text: impl Into<String>,
        assets: Option<&Path>,
    ) -> Result<Self, SceneError> {
        let path = path.as_ref().to_path_buf();
        let source = text.into();
        let raw: SceneToml = toml::from_str(&source).map_err(|e| syntax_error(&path, &source, &e))?;
        let assets = AssetDir::new(&path, raw.scene.assets.as_deref(), assets);
        match validate(&raw, &assets) {
            Ok(spec) => {
                let source_hash = with_animation_bytes(fnv1a64(source.as_bytes()), &spec, &assets)?;
                Ok(SceneFile { source_hash, path, source, assets, spec })
            }
            Err(Problem { field, message }) => {
                Err(SceneError::Invalid { file: path, line: line_of(&source, &field), field, message })
            }
        }
    }

    /// The file the scene was read from (used in messages and to resolve asset paths).
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// The scene text as read.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// FNV-1a 64 hash of the file's bytes, with the overrides applied since folded in;
    /// trajectories record it.
    pub fn source_hash(&self) -> u64 {
        self.source_hash
    }

    /// What the file describes, checked.
    pub fn spec(&self) -> &SceneSpec {
        &self.spec
    }

    /// The file rendered through its camera `name` instead of `render.camera` (`--camera`).
    /// The camera is not physics, so the hash a trajectory records does not change.
    pub fn with_render_camera(mut self, name: &str) -> Result<Self, SceneError> {
        let Some(index) = self.spec.cameras.iter().position(|c| c.name == name) else {
            let names: Vec<&str> = self.spec.cameras.iter().map(|c| c.name.as_str()).collect();
            let message = format!("no camera named {name:?} (the file's cameras: {names:?})");
            return Err(SceneError::Invalid {
                file: self.path,
                line: None,
                field: "--camera".into(),
                message,
            });
        };
        self.spec.render.camera = Some(index);
        Ok(self)
    }

    /// The directory relative asset paths resolve against: the override given when loading,
    /// else `scene.assets` (relative to the scene file), else the scene file's directory.
    pub(crate) fn asset_dir(&self) -> &Path {
        self.assets.path()
    }

    /// An asset path from the file, resolved against [`Self::asset_dir`] (absolute paths are
    /// kept).
    pub fn resolve(&self, relative: &str) -> PathBuf {
        self.assets.resolve(relative)
    }

    /// The 1-based line where the field at `path` (e.g. `spawners[1].count`) is written, if
    /// it is written at all.
    /// A glTF file given as the scene has no lines of its own to point at.
    pub(crate) fn line_of(&self, path: &str) -> Option<usize> {
        if is_gltf(&self.path) {
            return None;
        }
        line_of(&self.source, path)
    }

    /// A [`SceneError::Invalid`] for `field`, with its line.
    pub(crate) fn error(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        let field = field.into();
        SceneError::Invalid {
            file: self.path.clone(),
            line: self.line_of(&field),
            field,
            message: message.into(),
        }
    }

    /// The scene with about `total` dynamic objects: spawners' counts scaled so that they add
    /// up to their share exactly (at least one object per spawner, and no more waves than
    /// objects), structures' arrays to whole copies. Without structures the spawners get all
    /// of `total`; with them, spawners and structures share it in proportion to their bodies.
    /// Projectiles follow their structures' copies. The override is folded into the hash.
    /// `total` must be at least the number of spawners, and grown arrays must not reach
    /// other structures.
    pub fn with_total_count(self, total: u32) -> Result<Self, SceneError> {
        let n = self.spec.spawners.len();
        if n == 0 && self.spec.structures.is_empty() {
            return Err(self.error("spawners", "--count given but the scene has no spawners or structures"));
        }
        if (total as usize) < n {
            return Err(
                self.error("spawners", format!("--count {total} is less than the number of spawners ({n})"))
            );
        }
        let (spawners, structures) = spread_count(&self.spec.spawners, &self.spec.structures, total);
        let spec = SceneSpec { spawners, structures, ..self.spec.clone() };
        // Arrays that grew may reach other structures, and their projectiles grow with them.
        if let Err(Problem { field, message }) =
            structures_apart(&spec.structures).and_then(|()| within_body_budget(&spec))
        {
            return Err(self.error(field, format!("with --count {total}: {message}")));
        }
        // The override changes what is simulated: fold it into the hash.
        let source_hash = fnv1a64_extend(self.source_hash, &total.to_le_bytes());
        Ok(SceneFile { spec, source_hash, ..self })
    }

    /// The scene simulated for `frames` frames instead of `scene.frames`; the override is
    /// folded into the hash.
    pub(crate) fn with_frames(self, frames: NonZeroU32) -> Self {
        let frames = frames.get();
        let source_hash = fnv1a64_extend(self.source_hash, b"frames");
        let source_hash = fnv1a64_extend(source_hash, &frames.to_le_bytes());
        let scene = SceneInfo { frames, ..self.spec.scene };
        SceneFile { spec: SceneSpec { scene, ..self.spec }, source_hash, ..self }
    }
}

/// `hash` with the bytes of an `[animation]` scene's glTF file folded in: the file is the
/// simulation, so a trajectory of it must not replay after it changed.
fn with_animation_bytes(hash: u64, spec: &SceneSpec, assets: &AssetDir) -> Result<u64, SceneError> {
    let Some(animation) = &spec.animation else { return Ok(hash) };
    let file = assets.resolve(&animation.gltf);
    let bytes = std::fs::read(&file).map_err(|source| SceneError::Io { file, source })?;
    Ok(fnv1a64_extend(fnv1a64_extend(hash, b"animation"), &bytes))
}

/// FNV-1a, 64 bit: a small stable hash for scene identity (not for security).
pub(crate) fn fnv1a64(bytes: &[u8]) -> u64 {
    fnv1a64_extend(0xcbf2_9ce4_8422_2325, bytes)
}

fn fnv1a64_extend(mut hash: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        hash ^= b as u64;
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}
