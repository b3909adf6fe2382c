//! `dormant render`'s settings rule: each setting from its flag when one is given, else from
//! `--preset`, else from the scene file's `[render]`, else the built-in default; each kept with
//! where it came from (stats.json's `run.settings_from`).

use std::collections::BTreeMap;

use super::{CliError, RenderArgs, RenderMode};
use dormant::render::{AdaptiveSampling, ImageSize, RenderSettings};
use dormant::scene::file::spec::RenderDef;

/// `--preset`: a named set of settings, between the flags and the scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// A quick look: direct light only (`--mode shaded`), 320x180, 1 spp, every frame, no
    /// adaptive sampling.
    Preview,
    /// The scene file's own settings (as without a preset).
    Final,
}

/// Where a setting came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Source {
    Flag,
    Preset,
    Scene,
    Default,
}

impl Source {
    /// The name stats.json records.
    fn name(self) -> &'static str {
        match self {
            Source::Flag => "flag",
            Source::Preset => "preset",
            Source::Scene => "scene",
            Source::Default => "default",
        }
    }
}

/// A setting's value and where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Setting<T> {
    pub value: T,
    pub from: Source,
}

/// The first of `flag`, `preset` and `scene` that is given, else `default`.
fn pick<T>(flag: Option<T>, preset: Option<T>, scene: Option<T>, default: T) -> Setting<T> {
    match (flag, preset, scene) {
        (Some(value), _, _) => Setting { value, from: Source::Flag },
        (None, Some(value), _) => Setting { value, from: Source::Preset },
        (None, None, Some(value)) => Setting { value, from: Source::Scene },
        (None, None, None) => Setting { value: default, from: Source::Default },
    }
}

/// A preset's values; `None` where it leaves the setting to the scene file.
#[derive(Default)]
struct PresetValues {
    size: Option<ImageSize>,
    spp: Option<u32>,
    mode: Option<RenderMode>,
    frame_step: Option<u32>,
    noise_threshold: Option<f32>,
}

impl Preset {
    fn values(self) -> PresetValues {
        match self {
            Preset::Preview => PresetValues {
                size: Some(ImageSize { width: 320, height: 180 }),
                spp: Some(1),
                mode: Some(RenderMode::Shaded),
                frame_step: Some(1),
                noise_threshold: Some(0.0),
            },
            Preset::Final => PresetValues::default(),
        }
    }
}

/// The settings of a render run, each with its source.
#[derive(Clone, Copy, Debug)]
pub(super) struct Settings {
    pub size: Setting<ImageSize>,
    pub spp: Setting<u32>,
    pub mode: Setting<RenderMode>,
    /// Every n-th frame (sequences only).
    pub frame_step: Setting<u32>,
    pub noise_threshold: Setting<f32>,
    /// Adaptive sampling's minimum; `None`: max(8, √spp).
    pub min_spp: Setting<Option<u32>>,
    /// Motion blur's shutter (sequences only).
    pub shutter: Setting<f32>,
}

impl Settings {
    /// The settings of `args`, its preset, and `scene` (a scene file's `[render]`; `None` for
    /// the built-in scene and asset piles).
    pub fn resolve(args: &RenderArgs, scene: Option<&RenderDef>) -> Settings {
        let preset = args.preset.map(Preset::values).unwrap_or_default();
        let none = RenderDef::default();
        let scene = scene.unwrap_or(&none);
        let default = RenderSettings::default();
        let scene_size = scene.size.map(|(width, height)| ImageSize { width, height });
        Settings {
            size: pick(
                args.size,
                preset.size,
                scene_size,
                ImageSize { width: default.width, height: default.height },
            ),
            spp: pick(args.spp, preset.spp, scene.samples_per_pixel, default.spp),
            mode: pick(args.mode, preset.mode, None, RenderMode::Path),
            frame_step: pick(args.frame_step, preset.frame_step, scene.frame_step, 1),
            noise_threshold: pick(args.noise_threshold, preset.noise_threshold, scene.noise_threshold, 0.0),
            min_spp: pick(args.min_spp.map(Some), None, scene.min_spp.map(Some), None),
            shutter: pick(args.shutter, None, scene.shutter, 0.0),
        }
    }

    /// Adaptive sampling of these settings, checked against the samples per pixel; a problem
    /// names the flag or scene field its value came from.
    pub fn adaptive(&self) -> Result<AdaptiveSampling, CliError> {
        let threshold = self.noise_threshold.value;
        if !(threshold.is_finite() && threshold >= 0.0) {
            return Err(CliError::Input(format!(
                "--noise-threshold {threshold}: must be a number, 0 (off) or more"
            )));
        }
        let adaptive = AdaptiveSampling { noise_threshold: threshold, min_spp: self.min_spp.value };
        if !adaptive.is_on() {
            return match self.min_spp.from {
                Source::Flag => Err(CliError::Input(
                    "--min-spp needs adaptive sampling: --noise-threshold (or the scene's \
                     render.noise_threshold) above 0"
                        .into(),
                )),
                _ => Ok(AdaptiveSampling::OFF),
            };
        }
        let spp = self.spp.value;
        match adaptive.min_spp {
            Some(min) if min == 0 || min > spp => {
                let from = match self.min_spp.from {
                    Source::Flag => "--min-spp",
                    _ => "the scene's render.min_spp",
                };
                let spp_from = match self.spp.from {
                    Source::Flag => "--spp".to_string(),
                    Source::Preset => "the preset's spp".to_string(),
                    Source::Scene => "the scene's render.samples_per_pixel".to_string(),
                    Source::Default => "the default spp".to_string(),
                };
                Err(CliError::Input(format!("{from} {min}: must be from 1 to {spp_from} ({spp})")))
            }
            _ => Ok(adaptive),
        }
    }

    /// Where each setting came from, by the name stats.json gives the setting.
    pub fn sources(&self) -> BTreeMap<String, String> {
        [
            ("size", self.size.from),
            ("spp", self.spp.from),
            ("mode", self.mode.from),
            ("frame_step", self.frame_step.from),
            ("noise_threshold", self.noise_threshold.from),
            ("min_spp", self.min_spp.from),
            ("shutter", self.shutter.from),
        ]
        .into_iter()
        .map(|(name, from)| (name.to_string(), from.name().to_string()))
        .collect()
    }
}
