//! Meaning checks on a parsed scene: finite numbers, positive counts and sizes, references
//! that resolve, asset files that exist. Returns problems by field path; the parser turns
//! them into errors with lines.

use std::collections::BTreeSet;

use super::parse::SceneFile;
use super::schema::{CameraDef, DisturbanceKind, LightKind, PrototypeDef, SceneDocument, ShapeKind};

/// One thing wrong with a scene, at a field path such as `spawners[1].count`.
#[derive(Debug)]
pub(crate) struct Problem {
    pub field: String,
    pub message: String,
}

struct Checker {
    problems: Vec<Problem>,
}

impl Checker {
    fn fail(&mut self, field: impl Into<String>, message: impl Into<String>) {
        self.problems.push(Problem { field: field.into(), message: message.into() });
    }

    fn finite(&mut self, field: &str, v: f32) -> bool {
        if !v.is_finite() {
            self.fail(field, format!("must be a finite number, got {v}"));
            return false;
        }
        true
    }

    fn finite3(&mut self, field: &str, v: [f32; 3]) -> bool {
        if v.iter().any(|x| !x.is_finite()) {
            self.fail(field, format!("must be finite numbers, got {v:?}"));
            return false;
        }
        true
    }

    fn positive(&mut self, field: &str, v: f32) {
        if self.finite(field, v) && v <= 0.0 {
            self.fail(field, format!("must be greater than 0, got {v}"));
        }
    }

    fn non_negative(&mut self, field: &str, v: f32) {
        if self.finite(field, v) && v < 0.0 {
            self.fail(field, format!("must not be negative, got {v}"));
        }
    }

    fn at_least_one(&mut self, field: &str, v: u32) {
        if v == 0 {
            self.fail(field, "must be at least 1, got 0");
        }
    }
}

pub(crate) fn validate(file: &SceneFile) -> Vec<Problem> {
    let d: &SceneDocument = &file.description;
    let mut c = Checker { problems: Vec::new() };

    if d.scene.name.trim().is_empty() {
        c.fail("scene.name", "must not be empty");
    }
    c.at_least_one("scene.frames", d.scene.frames);

    let p = &d.physics;
    c.positive("physics.timestep", p.timestep);
    c.at_least_one("physics.substeps", p.substeps);
    c.finite3("physics.gravity", p.gravity);
    c.non_negative("physics.sleep_linear_threshold", p.sleep_linear_threshold);
    c.non_negative("physics.sleep_angular_threshold", p.sleep_angular_threshold);
    c.non_negative("physics.sleep_time", p.sleep_time);
    c.finite("physics.kill_plane_y", p.kill_plane_y);
    c.at_least_one("physics.solver_iterations", p.solver_iterations);
    c.non_negative("physics.linear_damping", p.linear_damping);
    c.non_negative("physics.angular_damping", p.angular_damping);
    if d.scene.assets.is_some() && !file.has_asset_override() && !file.asset_dir().is_dir() {
        c.fail("scene.assets", format!("directory not found: {}", file.asset_dir().display()));
    }

    let e = &d.environment;
    match (&e.gltf, &e.generator) {
        (Some(_), Some(_)) => c.fail("environment", "give either `gltf` or `generator`, not both"),
        (None, None) => c.fail("environment", "give `gltf` (a file) or `generator` (built-in)"),
        (Some(path), None) => {
            if !file.resolve(path).is_file() {
                c.fail("environment.gltf", format!("file not found: {}", file.resolve(path).display()));
            }
        }
        (None, Some(_)) => {}
    }
    c.positive("environment.scale", e.scale);
    c.finite3("environment.offset", e.offset);
    c.non_negative("environment.friction", e.friction);

    let mut names = BTreeSet::new();
    for (i, proto) in d.prototypes.iter().enumerate() {
        let at = |f: &str| format!("prototypes[{i}].{f}");
        if proto.name.trim().is_empty() {
            c.fail(at("name"), "must not be empty");
        } else if !names.insert(proto.name.as_str()) {
            c.fail(at("name"), format!("duplicate prototype name {:?}", proto.name));
        }
        check_shape(&mut c, file, proto, &at);
        c.positive(&at("density"), proto.density);
        c.non_negative(&at("friction"), proto.friction);
        if c.finite(&at("restitution"), proto.restitution) && !(0.0..=1.0).contains(&proto.restitution) {
            c.fail(at("restitution"), format!("must be within [0, 1], got {}", proto.restitution));
        }
    }

    for (i, s) in d.spawners.iter().enumerate() {
        let at = |f: &str| format!("spawners[{i}].{f}");
        if s.prototypes.is_empty() {
            c.fail(at("prototypes"), "must name at least one prototype");
        }
        for (j, name) in s.prototypes.iter().enumerate() {
            if !names.contains(name.as_str()) {
                c.fail(format!("spawners[{i}].prototypes[{j}]"), format!("no prototype named {name:?}"));
            }
        }
        c.at_least_one(&at("count"), s.count);
        c.at_least_one(&at("waves"), s.waves);
        if s.waves > s.count && s.count > 0 {
            c.fail(at("waves"), format!("{} waves for {} objects: a wave would be empty", s.waves, s.count));
        }
        let (lo, hi) = (s.region.min, s.region.max);
        if c.finite3(&at("region.min"), lo)
            && c.finite3(&at("region.max"), hi)
            && (0..3).any(|k| lo[k] > hi[k])
        {
            c.fail(at("region"), format!("min {lo:?} exceeds max {hi:?}"));
        }
        c.non_negative(&at("wave_interval"), s.wave_interval);
        c.non_negative(&at("start_time"), s.start_time);
        c.finite3(&at("initial_velocity"), s.initial_velocity);
        c.non_negative(&at("velocity_jitter"), s.velocity_jitter);
        c.non_negative(&at("position_jitter"), s.position_jitter);
    }

    let mut kinematic_names = BTreeSet::new();
    for (i, k) in d.kinematics.iter().enumerate() {
        let at = |f: &str| format!("kinematics[{i}].{f}");
        if !kinematic_names.insert(k.name.as_str()) {
            c.fail(at("name"), format!("duplicate kinematic body name {:?}", k.name));
        }
        if !names.contains(k.prototype.as_str()) {
            c.fail(at("prototype"), format!("no prototype named {:?}", k.prototype));
        }
        if k.keyframes.is_empty() {
            c.fail(at("keyframes"), "needs at least one keyframe");
        }
        let mut last = f32::NEG_INFINITY;
        for (j, key) in k.keyframes.iter().enumerate() {
            let kat = |f: &str| format!("kinematics[{i}].keyframes[{j}].{f}");
            if c.finite(&kat("time"), key.time) {
                if key.time < 0.0 {
                    c.fail(kat("time"), "must not be negative");
                } else if key.time <= last {
                    c.fail(kat("time"), format!("keyframe times must increase ({} after {last})", key.time));
                }
                last = key.time;
            }
            c.finite3(&kat("position"), key.position);
            c.finite(&kat("yaw_degrees"), key.yaw_degrees);
        }
        if k.looped && k.keyframes.len() < 2 {
            c.fail(at("looped"), "a looped path needs at least two keyframes");
        }
    }

    for (i, dist) in d.disturbances.iter().enumerate() {
        let at = |f: &str| format!("disturbances[{i}].{f}");
        if dist.frame >= d.scene.frames {
            c.fail(
                at("frame"),
                format!("frame {} is past the last frame ({})", dist.frame, d.scene.frames.saturating_sub(1)),
            );
        }
        c.finite3(&at("center"), dist.center);
        c.positive(&at("radius"), dist.radius);
        match dist.kind {
            DisturbanceKind::Impulse => match dist.impulse {
                Some(v) => {
                    c.finite3(&at("impulse"), v);
                }
                None => c.fail(at("impulse"), "an impulse disturbance needs `impulse`"),
            },
            DisturbanceKind::Explosion => match dist.strength {
                Some(s) => c.positive(&at("strength"), s),
                None => c.fail(at("strength"), "an explosion needs `strength`"),
            },
        }
        if dist.kind == DisturbanceKind::Impulse && dist.strength.is_some() {
            c.fail(at("strength"), "only explosions take `strength`");
        }
        if dist.kind == DisturbanceKind::Explosion && dist.impulse.is_some() {
            c.fail(at("impulse"), "only impulses take `impulse`");
        }
    }

    let mut camera_names = BTreeSet::new();
    for (i, cam) in d.cameras.iter().enumerate() {
        if !camera_names.insert(cam.name.as_str()) {
            c.fail(format!("cameras[{i}].name"), format!("duplicate camera name {:?}", cam.name));
        }
        check_camera(&mut c, i, cam);
    }

    if let Some(sky) = &d.sky {
        let gradient = [("zenith", sky.zenith), ("horizon", sky.horizon), ("ground", sky.ground)];
        for (name, v) in gradient.iter().chain([("color", sky.color)].iter()) {
            if let Some(v) = v {
                let field = format!("sky.{name}");
                if c.finite3(&field, *v) && v.iter().any(|x| *x < 0.0) {
                    c.fail(field, format!("radiance must not be negative, got {v:?}"));
                }
            }
        }
        if sky.color.is_some() && gradient.iter().any(|(_, v)| v.is_some()) {
            c.fail("sky.color", "a constant sky (`color`) takes no `zenith`, `horizon` or `ground`");
        }
        c.non_negative("sky.intensity", sky.intensity);
    }

    for (i, light) in d.lights.iter().enumerate() {
        let at = |f: &str| format!("lights[{i}].{f}");
        match light.kind {
            LightKind::Directional => match light.direction {
                Some(v) => {
                    if c.finite3(&at("direction"), v) && v == [0.0; 3] {
                        c.fail(at("direction"), "must not be the zero vector");
                    }
                }
                None => c.fail(at("direction"), "a directional light needs `direction`"),
            },
            LightKind::Point | LightKind::Spot => {
                match light.position {
                    Some(v) => {
                        c.finite3(&at("position"), v);
                    }
                    None => c.fail(at("position"), format!("a {:?} light needs `position`", light.kind)),
                }
                if light.kind == LightKind::Spot {
                    match light.direction {
                        Some(v) => {
                            if c.finite3(&at("direction"), v) && v == [0.0; 3] {
                                c.fail(at("direction"), "must not be the zero vector");
                            }
                        }
                        None => c.fail(at("direction"), "a spot light needs `direction`"),
                    }
                } else if light.direction.is_some() {
                    c.fail(at("direction"), "a point light has no `direction`");
                }
            }
        }
        if light.kind == LightKind::Directional && light.position.is_some() {
            c.fail(at("position"), "a directional light has no `position`");
        }
        if light.kind == LightKind::Spot {
            let inner = light.inner_cone_degrees.unwrap_or(0.0);
            let outer = light.outer_cone_degrees.unwrap_or(45.0);
            if c.finite(&at("inner_cone_degrees"), inner) && c.finite(&at("outer_cone_degrees"), outer) {
                if !(outer > 0.0 && outer <= 90.0) {
                    c.fail(at("outer_cone_degrees"), format!("must be within (0, 90], got {outer}"));
                } else if !(0.0..outer).contains(&inner) {
                    c.fail(
                        at("inner_cone_degrees"),
                        format!("must be at least 0 and less than outer_cone_degrees ({outer}), got {inner}"),
                    );
                }
            }
        } else {
            for (key, v) in [
                ("inner_cone_degrees", light.inner_cone_degrees),
                ("outer_cone_degrees", light.outer_cone_degrees),
            ] {
                if v.is_some() {
                    c.fail(at(key), "only spot lights take cone angles");
                }
            }
        }
        if c.finite3(&at("color"), light.color) && light.color.iter().any(|&x| x < 0.0) {
            c.fail(at("color"), "must not be negative");
        }
        c.non_negative(&at("intensity"), light.intensity);
    }

    let r = &d.render;
    c.at_least_one("render.width", r.width);
    c.at_least_one("render.height", r.height);
    c.at_least_one("render.samples_per_pixel", r.samples_per_pixel);
    c.at_least_one("render.frame_step", r.frame_step);
    if let Some(name) = &r.camera {
        if !camera_names.contains(name.as_str()) {
            c.fail("render.camera", format!("no camera named {name:?}"));
        }
    }

    c.problems
}

fn check_shape(c: &mut Checker, file: &SceneFile, p: &PrototypeDef, at: &dyn Fn(&str) -> String) {
    let wanted: &[&str] = match p.shape {
        ShapeKind::Box => &["half_extents"],
        ShapeKind::Sphere => &["radius"],
        ShapeKind::Capsule | ShapeKind::Cylinder => &["radius", "half_height"],
        ShapeKind::Gltf => &["gltf"],
    };
    let given = [
        ("half_extents", p.half_extents.is_some()),
        ("radius", p.radius.is_some()),
        ("half_height", p.half_height.is_some()),
        ("gltf", p.gltf.is_some()),
    ];
    for (name, present) in given {
        let needed = wanted.contains(&name);
        if needed && !present {
            c.fail(at(name), format!("shape {:?} needs `{name}`", p.shape));
        } else if !needed && present {
            c.fail(at(name), format!("shape {:?} does not use `{name}`", p.shape));
        }
    }
    if let Some(h) = p.half_extents {
        if c.finite3(&at("half_extents"), h) && h.iter().any(|&x| x <= 0.0) {
            c.fail(at("half_extents"), format!("must all be greater than 0, got {h:?}"));
        }
    }
    if let Some(r) = p.radius {
        c.positive(&at("radius"), r);
    }
    if let Some(h) = p.half_height {
        c.positive(&at("half_height"), h);
    }
    if let Some(path) = &p.gltf {
        let full = file.resolve(path);
        if !full.is_file() {
            c.fail(at("gltf"), format!("file not found: {}", full.display()));
        }
    }
    c.positive(&at("scale"), p.scale);
}

fn check_camera(c: &mut Checker, i: usize, cam: &CameraDef) {
    let at = |f: &str| format!("cameras[{i}].{f}");
    let fixed = cam.position.is_some() || cam.look_at.is_some();
    match (fixed, cam.keyframes.is_empty()) {
        (true, false) => c.fail(at("keyframes"), "give `position`/`look_at` or `keyframes`, not both"),
        (false, true) => c.fail(at("position"), "a camera needs `position` and `look_at`, or `keyframes`"),
        (true, true) => {
            for (f, v) in [("position", cam.position), ("look_at", cam.look_at)] {
                match v {
                    Some(v) => {
                        c.finite3(&at(f), v);
                    }
                    None => c.fail(at(f), format!("a fixed camera needs `{f}`")),
                }
            }
        }
        (false, false) => {
            let mut last = f32::NEG_INFINITY;
            for (j, k) in cam.keyframes.iter().enumerate() {
                let kat = |f: &str| format!("cameras[{i}].keyframes[{j}].{f}");
                if c.finite(&kat("time"), k.time) {
                    if k.time <= last {
                        c.fail(kat("time"), "keyframe times must increase");
                    }
                    last = k.time;
                }
                c.finite3(&kat("position"), k.position);
                c.finite3(&kat("look_at"), k.look_at);
            }
        }
    }
    if c.finite(&at("fov_degrees"), cam.fov_degrees) && !(cam.fov_degrees > 0.0 && cam.fov_degrees < 180.0) {
        c.fail(at("fov_degrees"), format!("must be within (0, 180), got {}", cam.fov_degrees));
    }
    c.non_negative(&at("aperture_radius"), cam.aperture_radius);
    if let Some(d) = cam.focus_distance {
        c.positive(&at("focus_distance"), d);
    }
}
