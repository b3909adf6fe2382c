//! The animation channels of a glTF file, read into one [`NodeMotion`] per node: its rest
//! transform and the samplers that animate its translation, rotation and scale. Every
//! accessor is checked before the gltf crate's reader trusts it; a channel on a missing node,
//! a property animated twice, morph-target weights and malformed samplers are errors naming
//! the animation and the channel.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation as GltfInterpolation, Property};

use super::super::checks::{check_accessor, AccessorLayout};
use super::super::GltfError;
use super::sampler::{Interpolation, Sampler};

const TIMES: AccessorLayout = AccessorLayout::new("input", Dimensions::Scalar, &[DataType::F32]);
const VECTORS: AccessorLayout = AccessorLayout::new("output", Dimensions::Vec3, &[DataType::F32]);
const ROTATIONS: AccessorLayout = AccessorLayout::new(
    "output",
    Dimensions::Vec4,
    &[DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16],
);

/// A node's transform without animation, as the file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Rest {
    Matrix(Mat4),
    Trs { translation: Vec3, rotation: Quat, scale: Vec3 },
}

/// One node's motion: its rest transform and what animates it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct NodeMotion {
    pub(crate) rest: Rest,
    pub(crate) translation: Option<Sampler<Vec3>>,
    pub(crate) rotation: Option<Sampler<Quat>>,
    pub(crate) scale: Option<Sampler<Vec3>>,
}

impl NodeMotion {
    fn of(node: &gltf::Node) -> Self {
        let rest = match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => Rest::Matrix(Mat4::from_cols_array_2d(&matrix)),
            gltf::scene::Transform::Decomposed { translation, rotation, scale } => Rest::Trs {
                translation: Vec3::from_array(translation),
                rotation: Quat::from_array(rotation),
                scale: Vec3::from_array(scale),
            },
        };
        Self { rest, translation: None, rotation: None, scale: None }
    }

    /// Whether any channel animates the node.
    pub(crate) fn is_animated(&self) -> bool {
        self.translation.is_some() || self.rotation.is_some() || self.scale.is_some()
    }

    /// The latest key time of its channels (0 without any).
    pub(crate) fn end(&self) -> f32 {
        let ends = [
            self.translation.as_ref().map(Sampler::end),
            self.rotation.as_ref().map(Sampler::end),
            self.scale.as_ref().map(Sampler::end),
        ];
        ends.into_iter().flatten().fold(0.0, f32::max)
    }

    /// Translation, rotation and scale at time `t` (a matrix node cannot be animated).
    pub(crate) fn trs_at(&self, t: f32) -> (Vec3, Quat, Vec3) {
        let (translation, rotation, scale) = match self.rest {
            Rest::Trs { translation, rotation, scale } => (translation, rotation, scale),
            Rest::Matrix(m) => {
                let (s, r, t) = m.to_scale_rotation_translation();
                (t, r, s)
            }
        };
        (
            self.translation.as_ref().map_or(translation, |c| c.at(t)),
            self.rotation.as_ref().map_or(rotation, |c| c.at(t)),
            self.scale.as_ref().map_or(scale, |c| c.at(t)),
        )
    }

    /// The local transform at time `t`.
    pub(crate) fn matrix_at(&self, t: f32) -> Mat4 {
        match (self.rest, self.is_animated()) {
            (Rest::Matrix(m), false) => m,
            _ => {
                let (translation, rotation, scale) = self.trs_at(t);
                Mat4::from_scale_rotation_translation(scale, rotation, translation)
            }
        }
    }
}

/// Every node's motion under the animations that play: all of them, or the one named
/// `only` (an error naming the file's animations when none has that name).
pub(crate) fn read_motions(
    path: &Path,
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    only: Option<&str>,
) -> Result<Vec<NodeMotion>, GltfError> {
    let mut motions: Vec<NodeMotion> = document.nodes().map(|n| NodeMotion::of(&n)).collect();
    let playing: Vec<gltf::Animation> = match only {
        None => document.animations().collect(),
        Some(name) => {
            let named: Vec<_> = document.animations().filter(|a| a.name() == Some(name)).collect();
            if named.is_empty() {
                let names: Vec<String> =
                    document.animations().map(|a| a.name().unwrap_or("(unnamed)").to_string()).collect();
                let message = format!("no animation named {name:?} (the file's animations: {names:?})");
                return Err(GltfError::new(path, "animations", message));
            }
            named
        }
    };
    for animation in playing {
        for channel in animation.channels() {
            let element = format!("{}.channels[{}]", animation_element(&animation), channel.index());
            read_channel(path, &element, &channel, buffers, &mut motions)?;
        }
    }
    Ok(motions)
}

/// `animations[i]` or `animations[i] ("name")`, as errors name an animation.
pub(crate) fn animation_element(animation: &gltf::Animation) -> String {
    match animation.name() {
        Some(name) => format!("animations[{}] ({name:?})", animation.index()),
        None => format!("animations[{}]", animation.index()),
    }
}

/// Reads one channel into its node's motion.
fn read_channel(
    path: &Path,
    element: &str,
    channel: &gltf::animation::Channel,
    buffers: &[gltf::buffer::Data],
    motions: &mut [NodeMotion],
) -> Result<(), GltfError> {
    let error = |message: String| GltfError::new(path, element, message);
    let node = channel.target().node();
    let motion = &mut motions[node.index()];
    if matches!(motion.rest, Rest::Matrix(_)) {
        return Err(error(format!(
            "animates nodes[{}], which has a matrix (animated nodes need TRS)",
            node.index()
        )));
    }
    let sampler = channel.sampler();
    let interpolation = match sampler.interpolation() {
        GltfInterpolation::Step => Interpolation::Step,
        GltfInterpolation::Linear => Interpolation::Linear,
        GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let property = channel.target().property();
    let layout = match property {
        Property::Rotation => &ROTATIONS,
        Property::Translation | Property::Scale => &VECTORS,
        Property::MorphTargetWeights => {
            return Err(error(format!(
                "animates the morph-target weights of nodes[{}] (not supported)",
                node.index()
            )))
        }
    };
    for (accessor, layout) in [(sampler.input(), &TIMES), (sampler.output(), layout)] {
        check_accessor(&accessor, layout, buffers)
            .map_err(|m| error(format!("{} (accessors[{}]) {m}", layout.what(), accessor.index())))?;
    }
    let reader = channel.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let times: Vec<f32> = reader.read_inputs().ok_or_else(|| error("input cannot be read".into()))?.collect();
    let outputs = reader.read_outputs().ok_or_else(|| error("output cannot be read".into()))?;
    set_sampler(motion, outputs, interpolation, times, node.index()).map_err(error)
}

/// Stores the sampler of `outputs` (keys at `times`) as `motion`'s; the error is the cause.
fn set_sampler(
    motion: &mut NodeMotion,
    outputs: ReadOutputs,
    interpolation: Interpolation,
    times: Vec<f32>,
    node: usize,
) -> Result<(), String> {
    let twice = |what: &str| format!("animates the {what} of nodes[{node}] a second time");
    match outputs {
        ReadOutputs::Translations(values) if motion.translation.is_none() => {
            let values = values.map(Vec3::from_array).collect();
            motion.translation = Some(Sampler::new(interpolation, times, values)?);
        }
        ReadOutputs::Scales(values) if motion.scale.is_none() => {
            let values = values.map(Vec3::from_array).collect();
            motion.scale = Some(Sampler::new(interpolation, times, values)?);
        }
        ReadOutputs::Rotations(values) if motion.rotation.is_none() => {
            let values = values.into_f32().map(Quat::from_array).collect();
            motion.rotation = Some(Sampler::new(interpolation, times, values)?);
        }
        ReadOutputs::Translations(_) => return Err(twice("translation")),
        ReadOutputs::Scales(_) => return Err(twice("scale")),
        ReadOutputs::Rotations(_) => return Err(twice("rotation")),
        ReadOutputs::MorphTargetWeights(_) => return Err("morph-target weights (not supported)".into()),
    }
    Ok(())
}
