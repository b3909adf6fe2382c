//! Turning a scene file's environment and prototypes into plain triangle meshes: built-in
//! generators (a Sponza-like atrium, a courtyard, a ground) and glTF files (for the renderer
//! with their materials, textures and lights). Used by physics for colliders and by the
//! renderer for drawing; builds no physics or render objects.

use std::f32::consts::PI;

use glam::{Affine3A, Quat, Vec3};

use super::parse::SceneFile;
use super::spec::{EnvironmentSource, GeneratorKind, Shape};
use super::SceneError;
use crate::geometry::{primitives, TriangleMesh};
use crate::scene::gltf::{load_gltf, load_gltf_mesh, GltfAsset, GltfError};

/// The static environment in world space (scale and offset applied).
pub fn environment_mesh(file: &SceneFile) -> Result<TriangleMesh, SceneError> {
    Ok(environment(file, false)?.mesh)
}

/// The environment with its glTF materials, textures and punctual lights (a generator's has
/// none), in world space.
pub(crate) fn environment_asset(file: &SceneFile) -> Result<GltfAsset, SceneError> {
    environment(file, true)
}

/// Loads a glTF asset named by `field`, with or without materials.
fn gltf_asset(
    file: &SceneFile,
    field: &str,
    path: &str,
    with_materials: bool,
) -> Result<GltfAsset, SceneError> {
    let path = file.resolve(path);
    let loaded =
        if with_materials { load_gltf(&path) } else { load_gltf_mesh(&path).map(GltfAsset::from_mesh) };
    loaded.map_err(|source: GltfError| SceneError::Asset {
        file: file.path().to_path_buf(),
        line: file.line_of(field),
        field: field.into(),
        source: Box::new(source),
    })
}

fn environment(file: &SceneFile, with_materials: bool) -> Result<GltfAsset, SceneError> {
    let env = &file.spec().environment;
    let asset = match &env.source {
        EnvironmentSource::Gltf(path) => gltf_asset(file, "environment.gltf", path, with_materials)?,
        EnvironmentSource::Generator(kind) => GltfAsset::from_mesh(generate(*kind)),
        // Its static nodes are known only over the sampled frames: `scene::AnimatedScene`.
        EnvironmentSource::Animation => {
            let message = "an [animation] scene's environment is read with its animation, not simulated";
            return Err(file.error("animation", message));
        }
    };
    let xf = Affine3A::from_scale_rotation_translation(
        Vec3::splat(env.scale),
        Quat::IDENTITY,
        Vec3::from_array(env.offset),
    );
    Ok(asset.transformed(&xf))
}

/// Prototype `index`'s mesh in object space (centred as authored; primitives at the origin).
pub fn prototype_mesh(file: &SceneFile, index: usize) -> Result<TriangleMesh, SceneError> {
    Ok(prototype(file, index, false)?.mesh)
}

/// Prototype `index` with its glTF materials and textures (primitive shapes have none). Lights
/// in a prototype's file are dropped: they would have to move with every body.
pub(crate) fn prototype_asset(file: &SceneFile, index: usize) -> Result<GltfAsset, SceneError> {
    let mut asset = prototype(file, index, true)?;
    if !asset.lights.is_empty() {
        tracing::warn!(
            file = %file.path().display(),
            "prototypes[{index}]: {} glTF light(s) ignored (only the environment's lights are used)",
            asset.lights.len()
        );
        asset.lights.clear();
    }
    Ok(asset)
}

fn prototype(file: &SceneFile, index: usize, with_materials: bool) -> Result<GltfAsset, SceneError> {
    let proto = file
        .spec()
        .prototypes
        .get(index)
        .ok_or_else(|| file.error(format!("prototypes[{index}]"), "no such prototype"))?;
    Ok(GltfAsset::from_mesh(match &proto.shape {
        Shape::Box { half_extents } => primitives::cuboid(Vec3::from_array(*half_extents)),
        Shape::Sphere { radius } => primitives::uv_sphere(*radius, 16, 8),
        Shape::Capsule { half_height, radius } => capsule(*half_height, *radius),
        Shape::Cylinder { half_height, radius } => cylinder(*half_height, *radius),
        Shape::Gltf { path, scale, .. } => {
            let field = format!("prototypes[{index}].gltf");
            let asset = gltf_asset(file, &field, path, with_materials)?;
            return Ok(asset.transformed(&Affine3A::from_scale(Vec3::splat(*scale))));
        }
    }))
}

/// A built-in environment.
pub(crate) fn generate(kind: GeneratorKind) -> TriangleMesh {
    match kind {
        GeneratorKind::Ground => primitives::ground_plane(50.0, 0.0, 10),
        GeneratorKind::Atrium => atrium(),
        GeneratorKind::Courtyard => courtyard(),
    }
}

/// Appends `part` to `mesh`, moved by `xf`. Keeps normals and UVs only while every part has
/// them.
fn append(mesh: &mut TriangleMesh, part: &TriangleMesh, xf: Affine3A) {
    let part = part.transformed(&xf);
    let base = mesh.positions.len() as u32;
    let first = mesh.positions.is_empty();
    mesh.positions.extend_from_slice(&part.positions);
    mesh.indices.extend(part.indices.iter().map(|t| t.map(|i| i + base)));
    match (first, &mut mesh.normals, &part.normals) {
        (true, _, Some(n)) => mesh.normals = Some(n.clone()),
        (false, Some(dst), Some(n)) => dst.extend_from_slice(n),
        _ => mesh.normals = None,
    }
    match (first, &mut mesh.uvs, &part.uvs) {
        (true, _, Some(uv)) => mesh.uvs = Some(uv.clone()),
        (false, Some(dst), Some(uv)) => dst.extend_from_slice(uv),
        _ => mesh.uvs = None,
    }
}

fn boxed(mesh: &mut TriangleMesh, center: Vec3, half: Vec3, yaw: f32) {
    append(
        mesh,
        &primitives::cuboid(half),
        Affine3A::from_rotation_translation(Quat::from_rotation_y(yaw), center),
    );
}

/// The atrium's layout, shared with the scene files in `scenes/`: a 48 x 32 floor at y = 0,
/// colonnades at z = ±6 (columns every 4 units from x = -20 to 20, 6 high), semicircular
/// arches of radius 2 springing at y = 6, an entablature at y = 8.5, and outer walls 12 high
/// at x = ±24 and z = ±16. The nave is |z| < 6, the aisles 6 < |z| < 16.
fn atrium() -> TriangleMesh {
    let mut m = TriangleMesh::default();
    append(&mut m, &primitives::ground_plane(1.0, 0.0, 1), Affine3A::from_scale(Vec3::new(24.0, 1.0, 16.0)));
    for side in [-1.0f32, 1.0] {
        let z = 6.0 * side;
        for i in 0..=10 {
            let x = -20.0 + 4.0 * i as f32;
            // Column with a plinth and a capital.
            boxed(&mut m, Vec3::new(x, 0.2, z), Vec3::new(0.45, 0.2, 0.45), 0.0);
            boxed(&mut m, Vec3::new(x, 3.0, z), Vec3::new(0.3, 2.8, 0.3), 0.0);
            boxed(&mut m, Vec3::new(x, 5.85, z), Vec3::new(0.45, 0.15, 0.45), 0.0);
            if i < 10 {
                // Arch of 9 voussoirs between this column and the next.
                let cx = x + 2.0;
                for k in 0..9 {
                    let a = PI * (k as f32 + 0.5) / 9.0;
                    let p = Vec3::new(cx - 1.75 * a.cos(), 6.0 + 1.75 * a.sin(), z);
                    append(
                        &mut m,
                        &primitives::cuboid(Vec3::new(0.25, 0.32, 0.3)),
                        Affine3A::from_rotation_translation(Quat::from_rotation_z(a - PI / 2.0), p),
                    );
                }
            }
        }
        // Entablature above the arches.
        boxed(&mut m, Vec3::new(0.0, 8.5, z), Vec3::new(20.5, 0.5, 0.5), 0.0);
        // Outer walls along x.
        boxed(&mut m, Vec3::new(0.0, 6.0, 16.25 * side), Vec3::new(24.5, 6.0, 0.25), 0.0);
        boxed(&mut m, Vec3::new(24.25 * side, 6.0, 0.0), Vec3::new(0.25, 6.0, 16.0), 0.0);
    }
    m
}

/// A 30 x 30 courtyard: floor, a ring of pillars, low walls and a central fountain block.
fn courtyard() -> TriangleMesh {
    let mut m = TriangleMesh::default();
    append(&mut m, &primitives::ground_plane(15.0, 0.0, 4), Affine3A::IDENTITY);
    for i in 0..12 {
        let a = 2.0 * PI * i as f32 / 12.0;
        boxed(&mut m, Vec3::new(10.0 * a.cos(), 2.0, 10.0 * a.sin()), Vec3::new(0.35, 2.0, 0.35), a);
    }
    for (x, z, yaw) in [(-6.0, 12.5, 0.0), (6.0, -12.5, 0.0), (12.5, 5.0, PI / 2.0), (-12.5, -5.0, PI / 2.0)]
    {
        boxed(&mut m, Vec3::new(x, 0.5, z), Vec3::new(3.0, 0.5, 0.2), yaw);
    }
    boxed(&mut m, Vec3::new(0.0, 0.4, 0.0), Vec3::new(1.5, 0.4, 1.5), PI / 4.0);
    for side in [-1.0f32, 1.0] {
        boxed(&mut m, Vec3::new(0.0, 2.0, 15.2 * side), Vec3::new(15.4, 2.0, 0.2), 0.0);
        boxed(&mut m, Vec3::new(15.2 * side, 2.0, 0.0), Vec3::new(0.2, 2.0, 15.0), 0.0);
    }
    m
}

/// A capsule along Y: a cylinder of `half_height` capped by hemispheres of `radius`.
fn capsule(half_height: f32, radius: f32) -> TriangleMesh {
    let mut m = primitives::uv_sphere(radius, 16, 8);
    for p in &mut m.positions {
        p.y += half_height * p.y.signum();
    }
    m
}

/// A closed cylinder along Y.
fn cylinder(half_height: f32, radius: f32) -> TriangleMesh {
    const N: u32 = 24;
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..N {
        let a = 2.0 * PI * i as f32 / N as f32;
        let (s, c) = a.sin_cos();
        positions.push(Vec3::new(radius * c, -half_height, radius * s));
        positions.push(Vec3::new(radius * c, half_height, radius * s));
    }
    let bottom = positions.len() as u32;
    positions.push(Vec3::new(0.0, -half_height, 0.0));
    positions.push(Vec3::new(0.0, half_height, 0.0));
    for i in 0..N {
        let (a0, a1) = (2 * i, 2 * ((i + 1) % N));
        indices.push([a0, a0 + 1, a1]);
        indices.push([a1, a0 + 1, a1 + 1]);
        indices.push([bottom, a0, a1]);
        indices.push([bottom + 1, a1 + 1, a0 + 1]);
    }
    TriangleMesh::new(positions, indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(mesh: &TriangleMesh) -> bool {
        (0..mesh.triangle_count()).all(|i| {
            let [a, b, c] = mesh.triangle(i);
            (b - a).cross(c - a).dot((a + b + c) / 3.0) > 0.0
        })
    }

    #[test]
    fn closed_primitives_wind_outward() {
        assert!(outward(&cylinder(1.0, 0.5)));
        assert!(outward(&capsule(0.5, 0.3)));
    }

    #[test]
    fn generators_produce_valid_meshes() {
        for kind in [GeneratorKind::Ground, GeneratorKind::Atrium, GeneratorKind::Courtyard] {
            let m = generate(kind);
            assert!(m.validate().is_ok(), "{kind:?}");
            assert!(m.triangle_count() > 0);
        }
    }
}
