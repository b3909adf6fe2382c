//! `[[cameras]]`, `[sky]`, `[[lights]]` and `[render]`: how the scene is seen.

use std::collections::BTreeSet;

use super::{at_least_one, at_most, finite, finite3, non_negative, positive, problem, Checked};
use crate::scene::file::schema::{CameraToml, LightTag, LightToml, RenderToml, SkyToml};
use crate::scene::file::spec::{
    CameraDef, CameraKeyframeDef, CameraPlacement, LightDef, LightKind, RenderDef, SkyDef,
};
use crate::scene::limits::{image_size_problem, shutter_problem, MAX_IMAGE_SIDE, MAX_SAMPLES_PER_PIXEL};

/// Unique names, each camera fixed or key-framed.
pub(super) fn cameras(raw: &[CameraToml]) -> Checked<Vec<CameraDef>> {
    let mut names = BTreeSet::new();
    let mut cameras = Vec::with_capacity(raw.len());
    for (i, cam) in raw.iter().enumerate() {
        if !names.insert(cam.name.as_str()) {
            return Err(problem(
                format!("cameras[{i}].name"),
                format!("duplicate camera name {:?}", cam.name),
            ));
        }
        cameras.push(camera(i, cam)?);
    }
    Ok(cameras)
}

/// `position` and `look_at`, or `keyframes` (times increasing); a field of view within
/// (0, 180), an aperture not negative, a positive focus distance.
fn camera(i: usize, cam: &CameraToml) -> Checked<CameraDef> {
    let at = |f: &str| format!("cameras[{i}].{f}");
    let fixed = cam.position.is_some() || cam.look_at.is_some();
    let placement = match (fixed, cam.keyframes.is_empty()) {
        (true, false) => {
            return Err(problem(at("keyframes"), "give `position`/`look_at` or `keyframes`, not both"))
        }
        (false, true) => {
            return Err(problem(at("position"), "a camera needs `position` and `look_at`, or `keyframes`"))
        }
        (true, true) => {
            let point = |f: &str, v: Option<[f32; 3]>| match v {
                Some(v) => finite3(&at(f), v),
                None => Err(problem(at(f), format!("a fixed camera needs `{f}`"))),
            };
            let position = point("position", cam.position)?;
            CameraPlacement::Fixed { position, look_at: point("look_at", cam.look_at)? }
        }
        (false, false) => {
            camera_keyframes(i, &cam.keyframes)?;
            CameraPlacement::Keyframed(cam.keyframes.clone())
        }
    };
    let fov_degrees = finite(&at("fov_degrees"), cam.fov_degrees)?;
    if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
        return Err(problem(at("fov_degrees"), format!("must be within (0, 180), got {fov_degrees}")));
    }
    Ok(CameraDef {
        name: cam.name.clone(),
        placement,
        fov_degrees,
        aperture_radius: non_negative(&at("aperture_radius"), cam.aperture_radius)?,
        focus_distance: cam.focus_distance.map(|d| positive(&at("focus_distance"), d)).transpose()?,
    })
}

fn camera_keyframes(i: usize, keys: &[CameraKeyframeDef]) -> Checked<()> {
    let mut last = f32::NEG_INFINITY;
    for (j, k) in keys.iter().enumerate() {
        let at = |f: &str| format!("cameras[{i}].keyframes[{j}].{f}");
        if finite(&at("time"), k.time)? <= last {
            return Err(problem(at("time"), "keyframe times must increase"));
        }
        last = k.time;
        finite3(&at("position"), k.position)?;
        finite3(&at("look_at"), k.look_at)?;
    }
    Ok(())
}

/// Radiances finite and not negative, `color` alone or a gradient, intensity not negative.
pub(super) fn sky(sky: &SkyToml) -> Checked<SkyDef> {
    let gradient = [("zenith", sky.zenith), ("horizon", sky.horizon), ("ground", sky.ground)];
    for (name, v) in gradient.iter().chain([("color", sky.color)].iter()) {
        if let Some(v) = v {
            let field = format!("sky.{name}");
            if finite3(&field, *v)?.iter().any(|x| *x < 0.0) {
                return Err(problem(field, format!("radiance must not be negative, got {v:?}")));
            }
        }
    }
    if sky.color.is_some() && gradient.iter().any(|(_, v)| v.is_some()) {
        return Err(problem(
            "sky.color",
            "a constant sky (`color`) takes no `zenith`, `horizon` or `ground`",
        ));
    }
    let intensity = non_negative("sky.intensity", sky.intensity)?;
    Ok(match sky.color {
        Some(color) => SkyDef::Constant { color, intensity },
        None => SkyDef::Gradient { zenith: sky.zenith, horizon: sky.horizon, ground: sky.ground, intensity },
    })
}

pub(super) fn lights(raw: &[LightToml]) -> Checked<Vec<LightDef>> {
    raw.iter().enumerate().map(|(i, l)| light(i, l)).collect()
}

/// Exactly the fields the kind takes, then a colour and intensity not negative.
fn light(i: usize, light: &LightToml) -> Checked<LightDef> {
    let at = |f: &str| format!("lights[{i}].{f}");
    let kind = light_kind(light, &at)?;
    if finite3(&at("color"), light.color)?.iter().any(|&x| x < 0.0) {
        return Err(problem(at("color"), "must not be negative"));
    }
    let intensity = non_negative(&at("intensity"), light.intensity)?;
    Ok(LightDef { kind, color: light.color, intensity })
}

/// A directional light's direction, a point light's position, or a spot light's position,
/// direction and cone (0 <= inner < outer <= 90 degrees); directions are not zero.
fn light_kind(light: &LightToml, at: &dyn Fn(&str) -> String) -> Checked<LightKind> {
    let direction = |kind: &str| {
        let Some(v) = light.direction else {
            return Err(problem(at("direction"), format!("a {kind} light needs `direction`")));
        };
        if finite3(&at("direction"), v)? == [0.0; 3] {
            return Err(problem(at("direction"), "must not be the zero vector"));
        }
        Ok(v)
    };
    let position = || match light.position {
        Some(v) => finite3(&at("position"), v),
        None => Err(problem(at("position"), format!("a {:?} light needs `position`", light.kind))),
    };
    let no_cones = || {
        for (key, v) in [
            ("inner_cone_degrees", light.inner_cone_degrees),
            ("outer_cone_degrees", light.outer_cone_degrees),
        ] {
            if v.is_some() {
                return Err(problem(at(key), "only spot lights take cone angles"));
            }
        }
        Ok(())
    };
    match light.kind {
        LightTag::Directional => {
            let direction = direction("directional")?;
            if light.position.is_some() {
                return Err(problem(at("position"), "a directional light has no `position`"));
            }
            no_cones()?;
            Ok(LightKind::Directional { direction })
        }
        LightTag::Point => {
            let position = position()?;
            if light.direction.is_some() {
                return Err(problem(at("direction"), "a point light has no `direction`"));
            }
            no_cones()?;
            Ok(LightKind::Point { position })
        }
        LightTag::Spot => {
            let (position, direction) = (position()?, direction("spot")?);
            let inner = finite(&at("inner_cone_degrees"), light.inner_cone_degrees.unwrap_or(0.0))?;
            let outer = finite(&at("outer_cone_degrees"), light.outer_cone_degrees.unwrap_or(45.0))?;
            if !(outer > 0.0 && outer <= 90.0) {
                return Err(problem(
                    at("outer_cone_degrees"),
                    format!("must be within (0, 90], got {outer}"),
                ));
            } else if !(0.0..outer).contains(&inner) {
                let message =
                    format!("must be at least 0 and less than outer_cone_degrees ({outer}), got {inner}");
                return Err(problem(at("inner_cone_degrees"), message));
            }
            Ok(LightKind::Spot { position, direction, inner_cone_degrees: inner, outer_cone_degrees: outer })
        }
    }
}

/// Sizes, samples and frame step at least 1 (width and height both or neither); a shutter
/// from 0 to 1; a camera that exists; a noise threshold not negative. Keys the file does not
/// give stay `None`.
pub(super) fn render(r: &RenderToml, cameras: &[CameraDef]) -> Checked<RenderDef> {
    let samples_per_pixel = match r.samples_per_pixel {
        None => None,
        Some(n) => Some(at_most(
            "render.samples_per_pixel",
            at_least_one("render.samples_per_pixel", n)?,
            MAX_SAMPLES_PER_PIXEL,
        )?),
    };
    let camera = match &r.camera {
        None => None,
        Some(name) => Some(
            cameras
                .iter()
                .position(|c| &c.name == name)
                .ok_or_else(|| problem("render.camera", format!("no camera named {name:?}")))?,
        ),
    };
    let min_spp = match r.min_spp {
        None => None,
        Some(m) => {
            Some(at_most("render.min_spp", at_least_one("render.min_spp", m)?, MAX_SAMPLES_PER_PIXEL)?)
        }
    };
    if let Some(message) = r.shutter.and_then(shutter_problem) {
        return Err(problem("render.shutter", message));
    }
    Ok(RenderDef {
        size: render_size(r)?,
        samples_per_pixel,
        camera,
        frame_step: r.frame_step.map(|n| at_least_one("render.frame_step", n)).transpose()?,
        noise_threshold: r.noise_threshold.map(|t| non_negative("render.noise_threshold", t)).transpose()?,
        min_spp,
        shutter: r.shutter,
    })
}

/// `render.width` and `render.height`: both or neither, each at least 1, within the image
/// limits.
fn render_size(r: &RenderToml) -> Checked<Option<(u32, u32)>> {
    let (width, height) = match (r.width, r.height) {
        (None, None) => return Ok(None),
        (Some(w), Some(h)) => (at_least_one("render.width", w)?, at_least_one("render.height", h)?),
        (Some(_), None) => return Err(problem("render.height", "missing: render.width needs it too")),
        (None, Some(_)) => return Err(problem("render.width", "missing: render.height needs it too")),
    };
    if let Some(message) = image_size_problem(width, height) {
        let field = if height > MAX_IMAGE_SIDE { "render.height" } else { "render.width" };
        return Err(problem(field, message));
    }
    Ok(Some((width, height)))
}
