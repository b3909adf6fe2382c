//! An `[animation]` scene's file, read for the frames the scene samples: the frame rate and
//! count (the scene file's, else the file's `dormant` extras, else the animation's length),
//! the rest settings, and which nodes are environment and bodies. Both the trajectory
//! (`physics`) and the render assets ([`SceneAssets`]) are made from one of these, so they
//! agree on the bodies and prototypes.

use glam::Vec3;

use super::file::{AnimationDef, SceneError, SceneFile};
use super::gltf::animated::{frame_time, AnimatedGltf, Roles};
use super::gltf::GltfError;
use crate::scene::limits::MAX_FRAMES;

/// See the module docs.
pub(crate) struct AnimatedScene {
    pub(crate) gltf: AnimatedGltf,
    /// Frames per second the file is sampled at.
    pub(crate) fps: f64,
    pub(crate) frames: u32,
    pub(crate) roles: Roles,
    pub(crate) rest_tolerance: f32,
    pub(crate) min_rest_frames: u32,
}

impl AnimatedScene {
    /// The animation of `file`, or `None` when it has no `[animation]`.
    pub(crate) fn load(file: &SceneFile) -> Result<Option<Self>, SceneError> {
        let Some(def) = &file.spec().animation else { return Ok(None) };
        let asset_error = |source| animation_error(file, source);
        let gltf = AnimatedGltf::read(&file.resolve(&def.gltf), def.name.as_deref()).map_err(asset_error)?;
        let fps = def.fps.or(gltf.extras.fps).filter(|f| f.is_finite() && *f > 0.0).ok_or_else(|| {
            file.error(
                "animation.fps",
                "the glTF file records no frame rate: give `fps` in the [animation] of a scene file",
            )
        })?;
        let frames = match file.spec().scene.frames {
            0 => gltf.extras.frames.unwrap_or_else(|| (gltf.duration() as f64 * fps).round() as u32 + 1),
            n => n,
        };
        if frames == 0 || frames > MAX_FRAMES {
            return Err(file.error(
                "scene.frames",
                format!("the animation gives {frames} frames, allowed 1 to {MAX_FRAMES}"),
            ));
        }
        let times: Vec<f32> = (0..frames).map(|i| frame_time(i, fps)).collect();
        let roles = gltf.roles(&times).map_err(asset_error)?;
        Ok(Some(Self {
            fps,
            frames,
            roles,
            rest_tolerance: rest_tolerance(def, &gltf),
            min_rest_frames: min_rest_frames(def, &gltf),
            gltf,
        }))
    }

    /// Seconds per frame.
    pub(crate) fn timestep(&self) -> f32 {
        (1.0 / self.fps) as f32
    }

    /// The time frame `index` samples.
    pub(crate) fn time(&self, index: u32) -> f32 {
        frame_time(index, self.fps)
    }

    /// Every prototype's name, in order.
    pub(crate) fn prototype_names(&self) -> Vec<String> {
        self.roles.prototypes.iter().map(|p| self.prototype_name(p.mesh, p.scale)).collect()
    }

    /// The mesh's name (or `mesh N`), with the scale when it is not 1.
    pub(crate) fn prototype_name(&self, mesh: usize, scale: Vec3) -> String {
        let base = self.gltf.document.meshes().nth(mesh).and_then(|m| m.name().map(str::to_string));
        let base = base.unwrap_or_else(|| format!("mesh {mesh}"));
        if scale == Vec3::ONE {
            base
        } else {
            format!("{base} x{:?}", scale.to_array())
        }
    }
}

/// The scene file's tolerance, else the glTF file's (dormant's own export records 0), else
/// the default.
fn rest_tolerance(def: &AnimationDef, gltf: &AnimatedGltf) -> f32 {
    def.rest_tolerance.or(gltf.extras.rest_tolerance).unwrap_or(AnimationDef::DEFAULT_REST_TOLERANCE)
}

/// The scene file's shortest rest, else the glTF file's, else the default (never below 2).
fn min_rest_frames(def: &AnimationDef, gltf: &AnimatedGltf) -> u32 {
    let frames = def.min_rest_frames.or(gltf.extras.min_rest_frames);
    frames.unwrap_or(AnimationDef::DEFAULT_MIN_REST_FRAMES).max(2)
}

/// The error for `[animation]`'s file that `source` says is wrong.
pub(super) fn animation_error(file: &SceneFile, source: GltfError) -> SceneError {
    SceneError::Asset {
        file: file.path().to_path_buf(),
        line: file.line_of("animation.gltf"),
        field: "animation.gltf".into(),
        source: Box::new(source),
    }
}
