//! `[environment]` and `[[prototypes]]`: what the world is made of.

use std::collections::BTreeSet;

use super::{exactly_the_keys, finite, finite3, non_negative, positive, problem, Checked};
use crate::scene::file::asset_dir::AssetDir;
use crate::scene::file::schema::{EnvironmentToml, PrototypeToml, ShapeKind};
use crate::scene::file::spec::{EnvironmentDef, EnvironmentSource, PrototypeDef, Shape};

/// Exactly one of `gltf` (an existing file) and `generator`; a positive scale, a finite
/// offset, friction not negative, a grid of collider cells of a sensible size.
pub(super) fn environment(e: &EnvironmentToml, assets: &AssetDir) -> Checked<EnvironmentDef> {
    let source = match (&e.gltf, e.generator) {
        (Some(_), Some(_)) => {
            return Err(problem("environment", "give either `gltf` or `generator`, not both"))
        }
        (None, None) => return Err(problem("environment", "give `gltf` (a file) or `generator` (built-in)")),
        (Some(path), None) => {
            if !assets.resolve(path).is_file() {
                let message = format!("file not found: {}", assets.resolve(path).display());
                return Err(problem("environment.gltf", message));
            }
            EnvironmentSource::Gltf(path.clone())
        }
        (None, Some(kind)) => EnvironmentSource::Generator(kind),
    };
    Ok(EnvironmentDef {
        source,
        scale: positive("environment.scale", e.scale)?,
        offset: finite3("environment.offset", e.offset)?,
        friction: non_negative("environment.friction", e.friction)?,
        collider_cells: collider_cells(e.collider_cells)?,
    })
}

/// At least 1 and at most [`EnvironmentDef::MAX_COLLIDER_CELLS`] per axis.
fn collider_cells(cells: u32) -> Checked<u32> {
    let max = EnvironmentDef::MAX_COLLIDER_CELLS;
    if !(1..=max).contains(&cells) {
        return Err(problem("environment.collider_cells", format!("must be within [1, {max}], got {cells}")));
    }
    Ok(cells)
}

/// Unique non-empty names, shapes with the sizes they take, positive density, friction not
/// negative, restitution and colour within [0, 1].
pub(super) fn prototypes(raw: &[PrototypeToml], assets: &AssetDir) -> Checked<Vec<PrototypeDef>> {
    let mut names = BTreeSet::new();
    let mut prototypes = Vec::with_capacity(raw.len());
    for (i, proto) in raw.iter().enumerate() {
        let at = |f: &str| format!("prototypes[{i}].{f}");
        if proto.name.trim().is_empty() {
            return Err(problem(at("name"), "must not be empty"));
        } else if !names.insert(proto.name.as_str()) {
            return Err(problem(at("name"), format!("duplicate prototype name {:?}", proto.name)));
        }
        let shape = shape(proto, assets, &at)?;
        let density = positive(&at("density"), proto.density)?;
        let friction = non_negative(&at("friction"), proto.friction)?;
        let restitution = finite(&at("restitution"), proto.restitution)?;
        if !(0.0..=1.0).contains(&restitution) {
            return Err(problem(at("restitution"), format!("must be within [0, 1], got {restitution}")));
        }
        let color = color(proto, &at)?;
        prototypes.push(PrototypeDef {
            name: proto.name.clone(),
            shape,
            density,
            friction,
            restitution,
            color,
        });
    }
    Ok(prototypes)
}

/// A colour within [0, 1], for a primitive shape only (a glTF mesh has its own materials or a
/// palette colour).
fn color(p: &PrototypeToml, at: &dyn Fn(&str) -> String) -> Checked<Option<[f32; 3]>> {
    let Some(color) = p.color else { return Ok(None) };
    if p.shape == ShapeKind::Gltf {
        return Err(problem(at("color"), "a glTF prototype takes its colours from its file"));
    }
    if finite3(&at("color"), color)?.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(problem(at("color"), format!("must be within [0, 1], got {color:?}")));
    }
    Ok(Some(color))
}

/// The shape with exactly the keys it uses: `half_extents` (all positive) for a box, a
/// positive `radius` (and `half_height` for capsules and cylinders), or an existing `gltf`
/// file; `scale` positive whatever the shape.
fn shape(p: &PrototypeToml, assets: &AssetDir, at: &dyn Fn(&str) -> String) -> Checked<Shape> {
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
    let what = format!("shape {:?}", p.shape);
    exactly_the_keys(&what, wanted, &given, at)?;
    let needs = |name: &str| problem(at(name), format!("{what} needs `{name}`"));
    if let Some(h) = p.half_extents {
        if finite3(&at("half_extents"), h)?.iter().any(|&x| x <= 0.0) {
            return Err(problem(at("half_extents"), format!("must all be greater than 0, got {h:?}")));
        }
    }
    let radius = p.radius.map(|r| positive(&at("radius"), r)).transpose()?;
    let half_height = p.half_height.map(|h| positive(&at("half_height"), h)).transpose()?;
    if let Some(path) = &p.gltf {
        let full = assets.resolve(path);
        if !full.is_file() {
            return Err(problem(at("gltf"), format!("file not found: {}", full.display())));
        }
    }
    let scale = positive(&at("scale"), p.scale)?;
    // Every key the shape needs is present (checked above).
    let radius = || radius.ok_or_else(|| needs("radius"));
    let half_height = || half_height.ok_or_else(|| needs("half_height"));
    Ok(match p.shape {
        ShapeKind::Box => Shape::Box { half_extents: p.half_extents.ok_or_else(|| needs("half_extents"))? },
        ShapeKind::Sphere => Shape::Sphere { radius: radius()? },
        ShapeKind::Capsule => Shape::Capsule { radius: radius()?, half_height: half_height()? },
        ShapeKind::Cylinder => Shape::Cylinder { radius: radius()?, half_height: half_height()? },
        ShapeKind::Gltf => {
            Shape::Gltf { path: p.gltf.clone().ok_or_else(|| needs("gltf"))?, scale, collider: p.collider }
        }
    })
}
