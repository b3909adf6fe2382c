//! glTF materials, textures and lights, end to end: glTF files written by the tests (a quad
//! with a checker texture, emission, a missing image, unsupported extensions, malformed
//! data), the duck from ../shared/assets when present, and punctual lights against their
//! closed forms.

use crate::common;

use std::path::{Path, PathBuf};

use common::cli::{dormant, exits_with, succeeds};
use common::encoding::base64;
use common::render::{backend, empty_scene, render, BLACK_SKY, NO_SUN, WHITE_SKY};
use dormant::geometry::{primitives, Ray};
use dormant::render::{DirectLighting, PathTracer, PinholeCamera};
use dormant::scene::file::SceneFile;
use dormant::scene::gltf::{load_gltf, load_gltf_mesh};
use dormant::scene::SceneAssets;
use dormant::scene::{Body, Camera, Light, Material, SceneDescription, Sky, StaticMesh, Sun};
use glam::{Affine3A, Vec3};
use serde_json::json;

/// A scene with nothing in it yet, seen by `camera` under `sky` and no sun.
fn scene(camera: Camera, sky: Sky) -> SceneDescription {
    empty_scene(camera, NO_SUN, sky)
}

/// Looking straight down at the origin from `height`, a little off centre: a pixel centre
/// exactly on the two-triangle ground plane's diagonal can miss with Embree (its default,
/// non-robust intersector is not watertight there), which is not what these tests test.
fn top_down(height: f32, vfov_deg: f32) -> Camera {
    let off = Vec3::new(0.0123, 0.0, 0.0371);
    Camera::pinhole(Vec3::new(0.0, height, 0.0) + off, off, Vec3::Z, vfov_deg)
}

/// Where the centre of pixel (x, y) sees the plane y = 0.
fn plane_point(camera: &Camera, size: u32, x: u32, y: u32) -> Vec3 {
    let ray: Ray = PinholeCamera::new(camera, size, size).ray(x as f32 + 0.5, y as f32 + 0.5);
    ray.at(-ray.origin.y / ray.dir.y)
}

/// The quad's vertex data: positions on y = 0 over [-1, 1]², normals +Y, UVs `x + 1, z + 1`
/// (so they run over [0, 2]), two triangles.
fn quad_buffer() -> Vec<u8> {
    let corners = [[-1.0f32, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]];
    let mut b = Vec::new();
    for c in corners {
        c.iter().for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
    }
    for _ in corners {
        [0.0f32, 1.0, 0.0].iter().for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
    }
    for c in corners {
        [c[0] + 1.0, c[2] + 1.0].iter().for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
    }
    for i in [0u16, 3, 2, 0, 2, 1] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    debug_assert_eq!(b.len(), 140);
    b
}

/// Writes `quad.bin` and a `.gltf` named `name` with one material and the given images,
/// textures and samplers; `patch` edits the JSON last.
fn write_quad(
    dir: &Path,
    name: &str,
    material: serde_json::Value,
    images: serde_json::Value,
    patch: impl FnOnce(&mut serde_json::Value),
) -> PathBuf {
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let mut doc = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 },
            "indices": 3,
            "material": 0
        }] }],
        "materials": [material],
        "buffers": [{ "uri": "quad.bin", "byteLength": 140 }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 128, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    if !images.is_null() {
        doc["images"] = images;
        doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
        // REPEAT on both axes.
        doc["samplers"] = json!([{ "wrapS": 10497, "wrapT": 10497 }]);
    }
    patch(&mut doc);
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    path
}

const RED: [u8; 4] = [255, 0, 0, 255];
const BLUE: [u8; 4] = [0, 0, 255, 255];

/// A 16 x 16 PNG of 2 x 2 blocks: red at the top-left and bottom-right, blue elsewhere.
fn write_checker(dir: &Path) {
    let img = image::RgbaImage::from_fn(16, 16, |x, y| {
        image::Rgba(if (x / 8 + y / 8) % 2 == 0 { RED } else { BLUE })
    });
    img.save(dir.join("checker.png")).unwrap();
}

fn textured_quad(dir: &Path, image_uri: &str, patch: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    write_quad(
        dir,
        "quad.gltf",
        json!({ "pbrMetallicRoughness": {
            "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0, "roughnessFactor": 1.0
        } }),
        json!([{ "uri": image_uri }]),
        patch,
    )
}

/// The quad as the only static mesh of a scene seen from above under `sky`.
fn quad_scene(path: &Path, camera: Camera, sky: Sky) -> SceneDescription {
    let mut asset = load_gltf(path).unwrap();
    let mut desc = scene(camera, sky);
    desc.materials = asset.take_materials(&mut desc.textures);
    desc.statics.push(StaticMesh { mesh: asset.mesh, material: 0 });
    desc
}

#[test]
fn textured_quad_repeats_its_checker_beyond_the_unit_square() {
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |_| {});
    let camera = top_down(4.0, 24.0);
    // Lambertian preview under a uniform white sky: every pixel is the base colour itself.
    let size = 64;
    let film = render(&quad_scene(&path, camera, WHITE_SKY), backend(), &DirectLighting, size, size, 1);
    let mut checked = 0;
    for y in 0..size {
        for x in 0..size {
            let p = plane_point(&camera, size, x, y);
            let (u, v) = (p.x + 1.0, p.z + 1.0);
            // UVs run over [0, 2]: the 2 x 2 checker repeats twice per axis, blocks of 0.5.
            let (bu, bv) = ((u * 2.0).floor() as i32, (v * 2.0).floor() as i32);
            let (fu, fv) = ((u * 2.0).fract(), (v * 2.0).fract());
            if !(0.15..0.85).contains(&fu) || !(0.15..0.85).contains(&fv) {
                continue; // near a block edge, where bilinear filtering blends
            }
            let expected = if (bu + bv) % 2 == 0 { Vec3::X } else { Vec3::Z };
            let got = film.pixels[(y * size + x) as usize];
            assert!((got - expected).abs().max_element() < 0.02, "pixel ({x}, {y}) at uv ({u}, {v}): {got}");
            checked += 1;
        }
    }
    assert!(checked > 1000, "only {checked} pixels checked");
    // Blocks with u > 1 exist in the image, so wrapping was exercised.
    assert!(plane_point(&camera, size, size - 1, 0).x.abs() > 0.5);
}

#[test]
fn emissive_quad_shows_its_emission() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_quad(
        dir.path(),
        "glow.gltf",
        json!({
            "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0 },
            "emissiveFactor": [1.0, 0.5, 0.25],
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 2.0 } }
        }),
        serde_json::Value::Null,
        |doc| doc["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]),
    );
    let desc = quad_scene(&path, top_down(4.0, 20.0), BLACK_SKY);
    let film = render(&desc, backend(), &PathTracer::default(), 8, 8, 4);
    for p in &film.pixels {
        assert!((*p - Vec3::new(2.0, 1.0, 0.5)).abs().max_element() < 1e-3, "{p}");
    }
}

#[test]
fn missing_texture_is_magenta_with_a_warning_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = textured_quad(dir.path(), "missing.png", |doc| {
        doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
    });
    let asset = load_gltf(&path).unwrap();
    assert_eq!(asset.textures.len(), 1);
    assert_eq!(asset.textures[0].texels, vec![[255, 0, 255, 255]]);
    let film =
        render(&quad_scene(&path, top_down(4.0, 20.0), WHITE_SKY), backend(), &DirectLighting, 8, 8, 1);
    for p in &film.pixels {
        assert!((*p - Vec3::new(1.0, 0.0, 1.0)).abs().max_element() < 1e-3, "{p}");
    }
    // The command line says so on stderr and still renders.
    let out = dir.path().join("out");
    let stderr = exits_with(
        dormant()
            .args(["render", "--size", "16x16", "--spp", "1", "--count", "1", "--env"])
            .arg(&path)
            .arg("--object")
            .arg(&path)
            .arg("--out")
            .arg(&out),
        0,
    );
    assert!(stderr.contains("images[0]") && stderr.contains("magenta"), "{stderr}");
    assert!(stderr.contains("KHR_texture_transform"), "{stderr}");
    assert!(out.join("frame_0000.png").is_file());
}

#[test]
fn undecodable_and_empty_images_fall_back_to_magenta() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("garbage.png"), b"this is not an image").unwrap();
    let path = textured_quad(dir.path(), "garbage.png", |_| {});
    assert_eq!(load_gltf(&path).unwrap().textures[0].texels, vec![[255, 0, 255, 255]]);
    std::fs::write(dir.path().join("empty.png"), b"").unwrap();
    let path = textured_quad(dir.path(), "empty.png", |_| {});
    assert_eq!(load_gltf(&path).unwrap().textures[0].texels, vec![[255, 0, 255, 255]]);
}

#[test]
fn required_unsupported_extension_is_an_error_naming_file_and_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = textured_quad(dir.path(), "checker.png", |doc| {
        doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
        doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    });
    let err = load_gltf(&path).unwrap_err().to_string();
    assert!(err.contains("quad.gltf") && err.contains("KHR_draco_mesh_compression"), "{err}");
    assert!(load_gltf_mesh(&path).is_err());
}

#[test]
fn malformed_geometry_is_an_error_naming_file_and_element() {
    let dir = tempfile::tempdir().unwrap();
    let material = json!({ "pbrMetallicRoughness": { "metallicFactor": 0.0 } });
    // An index past the last vertex.
    let path = write_quad(dir.path(), "bad-index.gltf", material.clone(), serde_json::Value::Null, |_| {});
    let mut bin = quad_buffer();
    bin[138..140].copy_from_slice(&9u16.to_le_bytes());
    std::fs::write(dir.path().join("quad.bin"), &bin).unwrap();
    let err = load_gltf(&path).unwrap_err().to_string();
    assert!(err.contains("bad-index.gltf") && err.contains("meshes[0].primitives[0]"), "{err}");
    // A NaN vertex.
    let mut bin = quad_buffer();
    bin[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(dir.path().join("quad.bin"), &bin).unwrap();
    let err = load_gltf(&path).unwrap_err().to_string();
    assert!(err.contains("meshes[0].primitives[0]") && err.contains("non-finite"), "{err}");
    // An accessor reading past its buffer view.
    let path = write_quad(dir.path(), "bad-accessor.gltf", material, serde_json::Value::Null, |doc| {
        doc["accessors"][0]["count"] = json!(40);
    });
    let err = load_gltf(&path).unwrap_err().to_string();
    assert!(err.contains("bad-accessor.gltf") && err.contains("accessors[0]"), "{err}");
}

#[test]
fn duck_in_a_scene_file_renders_with_its_texture_not_the_palette() {
    let Some(duck) = common::shared_assets().map(|d| d.join("duck.glb")) else { return };
    let dir = tempfile::tempdir().unwrap();
    let toml = format!(
        "[scene]\nname = \"duck\"\nframes = 1\n\n[environment]\ngenerator = \"ground\"\n\n\
         [[prototypes]]\nname = \"duck\"\nshape = \"gltf\"\ngltf = {:?}\n\n\
         [[prototypes]]\nname = \"box\"\nshape = \"box\"\nhalf_extents = [0.5, 0.5, 0.5]\n",
        duck.display().to_string()
    );
    let file = SceneFile::parse(dir.path().join("duck.toml"), toml).unwrap();
    let assets = SceneAssets::load(&file).unwrap();
    let mut desc = assets.describe(0.0);
    // The duck keeps its glTF material and texture; the box still gets a palette colour.
    let duck_material = desc.materials[desc.prototypes[0].material as usize];
    assert!(duck_material.base_color_texture.is_some());
    let box_material = desc.materials[desc.prototypes[1].material as usize];
    assert!(box_material.base_color_texture.is_none());
    assert_eq!(desc.textures.len(), 1);
    let mean = desc.textures[0].mean_rgb();
    assert!(mean.x > mean.z && mean.y > mean.z, "duck texture mean {mean}");

    // Frame the duck from the front-left, above the ground.
    let bounds = desc.prototypes[0].mesh.bounds();
    let lift = Affine3A::from_translation(Vec3::new(0.0, -bounds.min.y, 0.0));
    desc.bodies.push(Body { prototype: 0, transform: lift });
    let centre = lift.transform_point3(bounds.center());
    let r = bounds.extent().length();
    desc.camera = Camera::pinhole(centre + Vec3::new(0.6, 0.4, 1.0) * r, centre, Vec3::Y, 25.0);
    desc.sun = Sun {
        direction: Vec3::new(0.3, 1.0, 0.6).normalize(),
        irradiance: Vec3::splat(3.0),
        angular_radius_deg: 1.0,
    };
    let start = std::time::Instant::now();
    let film = render(&desc, backend(), &PathTracer::default(), 96, 96, 16);
    eprintln!("duck 96x96 at 16 spp: {:.3} s", start.elapsed().as_secs_f64());
    // The central quarter of the image is mostly duck.
    let mut sum = Vec3::ZERO;
    for y in 36..60 {
        for x in 36..60 {
            sum += film.pixels[y * 96 + x];
        }
    }
    let mean = sum / (24.0 * 24.0);
    assert!(mean.x > 1.4 * mean.z && mean.y > 1.2 * mean.z, "duck mean colour {mean} is not yellowish");
    assert!(mean.y > 0.5 * mean.x, "duck mean colour {mean} looks like the red palette colour");
}

#[test]
fn point_light_lit_plane_matches_the_closed_form() {
    // L = albedo / pi * I cos(theta) / r^2 for a Lambertian plane under a point light.
    let camera = top_down(5.0, 40.0);
    let light = Vec3::new(0.3, 2.0, -0.2);
    let intensity = 6.0;
    let mut desc = scene(camera, BLACK_SKY);
    desc.materials.push(Material::lambertian(Vec3::splat(0.5)));
    desc.statics.push(StaticMesh { mesh: primitives::ground_plane(100.0, 0.0, 1), material: 0 });
    desc.lights.push(Light::Point { position: light, intensity: Vec3::splat(intensity) });
    let size = 24;
    let film = render(&desc, backend(), &PathTracer::default(), size, size, 1);
    for y in 0..size {
        for x in 0..size {
            let p = plane_point(&camera, size, x, y);
            let d = light - p;
            let r2 = d.length_squared();
            let expected = 0.5 / std::f32::consts::PI * intensity * (d.y / r2.sqrt()) / r2;
            let got = film.pixels[(y * size + x) as usize];
            assert!(
                (got.x - expected).abs() < 2e-3 * expected,
                "pixel ({x}, {y}): {got}, expected {expected}"
            );
        }
    }
}

#[test]
fn spot_light_lights_its_cone_only() {
    let camera = top_down(5.0, 40.0);
    let (height, intensity) = (2.0f32, 4.0f32);
    let (cos_inner, cos_outer) = (15f32.to_radians().cos(), 25f32.to_radians().cos());
    let mut desc = scene(camera, BLACK_SKY);
    desc.materials.push(Material::lambertian(Vec3::splat(0.5)));
    desc.statics.push(StaticMesh { mesh: primitives::ground_plane(100.0, 0.0, 1), material: 0 });
    desc.lights.push(Light::Spot {
        position: Vec3::new(0.0, height, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(intensity),
        cos_inner,
        cos_outer,
    });
    let size = 32;
    let film = render(&desc, backend(), &PathTracer::default(), size, size, 1);
    let (mut inside, mut outside) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let p = plane_point(&camera, size, x, y);
            let d = Vec3::new(0.0, height, 0.0) - p;
            let cos = d.y / d.length();
            let got = film.pixels[(y * size + x) as usize].x;
            if cos >= cos_inner {
                let expected = 0.5 / std::f32::consts::PI * intensity * cos / d.length_squared();
                assert!((got - expected).abs() < 2e-3 * expected, "({x}, {y}): {got}, expected {expected}");
                inside += 1;
            } else if cos <= cos_outer {
                assert_eq!(got, 0.0, "({x}, {y}) is outside the cone");
                outside += 1;
            }
        }
    }
    assert!(inside > 20 && outside > 20, "{inside} inside, {outside} outside");
}

#[test]
fn scene_file_point_and_spot_lights_reach_the_description() {
    let dir = tempfile::tempdir().unwrap();
    let base = "[scene]\nname = \"lights\"\nframes = 1\n\n[environment]\ngenerator = \"ground\"\n\n\
                [[lights]]\nkind = \"directional\"\ndirection = [0.0, -1.0, 0.0]\n\n\
                [[lights]]\nkind = \"point\"\nposition = [0.0, 3.0, 0.0]\nintensity = 5.0\n\n\
                [[lights]]\nkind = \"spot\"\nposition = [1.0, 4.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\n";
    let file = SceneFile::parse(
        dir.path().join("lights.toml"),
        format!("{base}inner_cone_degrees = 10.0\nouter_cone_degrees = 30.0\n"),
    )
    .unwrap();
    let desc = SceneAssets::load(&file).unwrap().describe(0.0);
    assert_eq!(desc.lights.len(), 2, "{:?}", desc.lights);
    assert_eq!(
        desc.lights[0],
        Light::Point { position: Vec3::new(0.0, 3.0, 0.0), intensity: Vec3::splat(5.0) }
    );
    match desc.lights[1] {
        Light::Spot { cos_outer, cos_inner, direction, .. } => {
            assert!((cos_outer - 30f32.to_radians().cos()).abs() < 1e-6);
            assert!((cos_inner - 10f32.to_radians().cos()).abs() < 1e-6);
            assert_eq!(direction, Vec3::NEG_Y);
        }
        other => panic!("expected a spot light, got {other:?}"),
    }
    let bad = SceneFile::parse(
        dir.path().join("bad.toml"),
        format!("{base}inner_cone_degrees = 40.0\nouter_cone_degrees = 30.0\n"),
    )
    .unwrap_err();
    assert_eq!(bad.field(), Some("lights[2].inner_cone_degrees"), "{bad}");
    assert_eq!(bad.line(), Some(21), "{bad}");
}

#[test]
fn floor_under_an_emissive_ceiling_reflects_albedo_times_radiance() {
    // A Lambertian floor under a (practically) infinite ceiling of radiance L receives
    // E = pi * L, so it shows albedo * L. Emitter sampling and BSDF sampling meet by MIS.
    let mut desc = scene(top_down(0.9, 40.0), BLACK_SKY);
    desc.materials.push(Material::lambertian(Vec3::splat(0.5)));
    desc.materials.push(Material { emissive: Vec3::new(2.0, 1.0, 0.5), ..Material::lambertian(Vec3::ZERO) });
    desc.statics.push(StaticMesh { mesh: primitives::ground_plane(100.0, 0.0, 1), material: 0 });
    desc.statics.push(StaticMesh { mesh: primitives::ground_plane(100.0, 1.0, 1), material: 1 });
    let film = render(&desc, backend(), &PathTracer::default(), 16, 16, 16);
    let mean = film.pixels.iter().sum::<Vec3>() / film.pixels.len() as f32;
    let expected = Vec3::new(1.0, 0.5, 0.25);
    assert!((mean - expected).abs().max_element() < 0.01, "mean {mean}, expected {expected}");
}

#[test]
fn thin_lens_keeps_the_focus_plane_sharp_and_blurs_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |_| {});
    let size = 48;
    // Fraction of pixels that show a pure checker colour (red or blue within 2%).
    let pure = |camera: Camera| {
        let film = render(&quad_scene(&path, camera, WHITE_SKY), backend(), &DirectLighting, size, size, 32);
        let is_pure =
            |p: &Vec3| (*p - Vec3::X).abs().max_element() < 0.02 || (*p - Vec3::Z).abs().max_element() < 0.02;
        film.pixels.iter().filter(|p| is_pure(p)).count() as f32 / film.pixels.len() as f32
    };
    let pinhole = top_down(4.0, 24.0);
    let focused = Camera { aperture_radius: 0.3, ..pinhole };
    let near_focus = Camera { aperture_radius: 0.3, focus_distance: Some(1.0), ..pinhole };
    let (p0, p1, p2) = (pure(pinhole), pure(focused), pure(near_focus));
    assert!(p0 > 0.6, "pinhole: {p0}");
    assert!((p1 - p0).abs() < 0.1, "focused on the quad: {p1} pure pixels vs pinhole {p0}");
    assert!(p2 < 0.5 * p0, "focused in front of the quad: {p2} pure pixels vs pinhole {p0}");
}

#[test]
fn scene_file_camera_aperture_reaches_the_description() {
    let dir = tempfile::tempdir().unwrap();
    let base = "[scene]\nname = \"lens\"\nframes = 1\n\n[environment]\ngenerator = \"ground\"\n\n\
                [[cameras]]\nname = \"main\"\nposition = [0.0, 2.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    let file = SceneFile::parse(
        dir.path().join("lens.toml"),
        format!("{base}aperture_radius = 0.05\nfocus_distance = 4.0\n"),
    )
    .unwrap();
    let camera = SceneAssets::load(&file).unwrap().describe(0.0).camera;
    assert_eq!((camera.aperture_radius, camera.focus_distance), (0.05, Some(4.0)));
    let bad =
        SceneFile::parse(dir.path().join("bad.toml"), format!("{base}focus_distance = -1.0\n")).unwrap_err();
    assert_eq!(bad.field(), Some("cameras[0].focus_distance"), "{bad}");
}

#[test]
fn aov_passes_record_albedo_normal_and_depth() {
    use dormant::render::{Aov, AovIntegrator};
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |_| {});
    let camera = top_down(4.0, 24.0);
    let desc = quad_scene(&path, camera, BLACK_SKY);
    let size = 32;
    let albedo = render(&desc, backend(), &AovIntegrator(Aov::Albedo), size, size, 1);
    let normal = render(&desc, backend(), &AovIntegrator(Aov::Normal), size, size, 1);
    let depth = render(&desc, backend(), &AovIntegrator(Aov::Depth), size, size, 1);
    for y in 0..size {
        for x in 0..size {
            let i = (y * size + x) as usize;
            let p = plane_point(&camera, size, x, y);
            assert!((normal.pixels[i] - Vec3::Y).abs().max_element() < 1e-5, "{}", normal.pixels[i]);
            let expected = (p - camera.eye).length();
            assert!(
                (depth.pixels[i].x - expected).abs() < 1e-4 * expected,
                "{} vs {expected}",
                depth.pixels[i]
            );
            let (fu, fv) = (((p.x + 1.0) * 2.0).fract(), ((p.z + 1.0) * 2.0).fract());
            if (0.15..0.85).contains(&fu) && (0.15..0.85).contains(&fv) {
                let a = albedo.pixels[i];
                assert!(a == Vec3::X || a == Vec3::Z, "albedo {a}");
            }
        }
    }
    // The command line writes each pass next to the frame.
    let out = dir.path().join("out");
    succeeds(
        dormant()
            .args([
                "render",
                "--size",
                "16x16",
                "--spp",
                "1",
                "--quiet",
                "--exr",
                "--aov",
                "albedo,normal,depth",
            ])
            .arg("--out")
            .arg(&out),
    );
    for name in ["albedo", "normal", "depth"] {
        for ext in ["png", "exr"] {
            assert!(out.join(format!("frame_0000.{name}.{ext}")).is_file(), "{name}.{ext}");
        }
    }
}

#[test]
fn aov_passes_shaded_beside_the_image_equal_passes_traced_on_their_own() {
    use dormant::accel;
    use dormant::render::{render_with_aovs, Aov, AovIntegrator, RenderScene, RenderSettings};
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |_| {});
    // Wide enough that the corners see past the quad.
    let camera = top_down(4.0, 70.0);
    let desc = quad_scene(&path, camera, WHITE_SKY);
    let aovs = [Aov::Albedo, Aov::Spp, Aov::Normal, Aov::Depth, Aov::Baked];
    let mut a = accel::create(backend(), None).unwrap();
    let scene = RenderScene::build(&desc, a.as_mut()).unwrap();
    let settings = RenderSettings::new(24, 16, 5);
    let (_, _, passes) =
        render_with_aovs(&scene, a.query().unwrap(), &PathTracer::default(), &settings, &aovs).unwrap();
    assert_eq!(passes.iter().map(|(aov, _)| *aov).collect::<Vec<_>>(), aovs);
    for (aov, film) in passes.iter().filter(|(aov, _)| *aov != Aov::Spp) {
        let alone = render(&desc, backend(), &AovIntegrator(*aov), 24, 16, 5);
        let bits = |f: &dormant::render::Film| {
            f.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>()
        };
        assert_eq!(bits(film), bits(&alone), "{}", aov.name());
    }
    assert!(passes[1].1.pixels.iter().all(|&p| p == Vec3::splat(5.0)));
}

/// Photometric intensities (candela, lux) become radiometric ones over 683 lm/W.
#[test]
fn gltf_punctual_lights_and_sampler_wrap_modes_are_imported() {
    use dormant::scene::texture::Wrap;
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |doc| {
        // MIRRORED_REPEAT along s, CLAMP_TO_EDGE along t.
        doc["samplers"] = json!([{ "wrapS": 33648, "wrapT": 33071 }]);
        doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
            { "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 8.0 },
            { "type": "spot", "intensity": 2.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
            { "type": "directional", "intensity": 3.0 }
        ] } });
        // A parent moved up by 2 holds the lights; the spot is turned to shine along -Y
        // (a -90 degree turn about X takes the node's -Z to -Y).
        let s = std::f32::consts::FRAC_1_SQRT_2;
        doc["nodes"] = json!([
            { "mesh": 0 },
            { "translation": [0.0, 2.0, 0.0], "children": [2, 3, 4] },
            { "translation": [1.0, 0.0, 0.0], "extensions": { "KHR_lights_punctual": { "light": 0 } } },
            { "rotation": [-s, 0.0, 0.0, s], "extensions": { "KHR_lights_punctual": { "light": 1 } } },
            { "extensions": { "KHR_lights_punctual": { "light": 2 } } }
        ]);
        doc["scenes"] = json!([{ "nodes": [0, 1] }]);
    });
    let asset = load_gltf(&path).unwrap();
    assert_eq!(
        (asset.textures[0].wrap_s, asset.textures[0].wrap_t),
        (Wrap::MirroredRepeat, Wrap::ClampToEdge)
    );
    assert_eq!(asset.lights.len(), 3, "{:?}", asset.lights);
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    let mut kinds = 0;
    for light in &asset.lights {
        match *light {
            Light::Point { position, intensity } => {
                assert!(close(position, Vec3::new(1.0, 2.0, 0.0)), "{position}");
                assert!(close(intensity, Vec3::new(8.0, 4.0, 2.0) / 683.0), "{intensity}");
                kinds |= 1;
            }
            Light::Spot { position, direction, intensity, cos_inner, cos_outer } => {
                assert!(
                    close(position, Vec3::new(0.0, 2.0, 0.0)) && close(direction, Vec3::NEG_Y),
                    "{light:?}"
                );
                assert!(close(intensity, Vec3::splat(2.0 / 683.0)));
                assert!((cos_inner - 0.2f32.cos()).abs() < 1e-6 && (cos_outer - 0.5f32.cos()).abs() < 1e-6);
                kinds |= 2;
            }
            Light::Directional { direction, irradiance } => {
                assert!(
                    close(direction, Vec3::NEG_Z) && close(irradiance, Vec3::splat(3.0 / 683.0)),
                    "{light:?}"
                );
                kinds |= 4;
            }
        }
    }
    assert_eq!(kinds, 7);
}

#[test]
fn textured_primitive_without_uvs_warns_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |doc| {
        doc["meshes"][0]["primitives"][0]["attributes"] = json!({ "POSITION": 0, "NORMAL": 1 });
    });
    let stderr = exits_with(
        dormant()
            .args(["render", "--size", "8x8", "--spp", "1", "--count", "1", "--env"])
            .arg(&path)
            .arg("--object")
            .arg(&path)
            .arg("--out")
            .arg(dir.path().join("out")),
        0,
    );
    assert!(stderr.contains("meshes[0].primitives[0]") && stderr.contains("TEXCOORD_0"), "{stderr}");
}

#[test]
fn data_uri_images_decode_like_files() {
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let png = std::fs::read(dir.path().join("checker.png")).unwrap();
    let uri = format!("data:image/png;base64,{}", base64(&png));
    let from_file = load_gltf(&textured_quad(dir.path(), "checker.png", |_| {})).unwrap();
    let from_uri = load_gltf(&textured_quad(dir.path(), &uri, |_| {})).unwrap();
    assert_eq!(from_uri.textures[0].texels, from_file.textures[0].texels);
    assert_eq!((from_uri.textures[0].width, from_uri.textures[0].height), (16, 16));
}

#[test]
fn gltf_cameras_are_imported_and_frame_a_scene_file_without_cameras() {
    let dir = tempfile::tempdir().unwrap();
    write_checker(dir.path());
    let path = textured_quad(dir.path(), "checker.png", |doc| {
        doc["cameras"] = json!([
            { "type": "orthographic", "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } },
            { "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }
        ]);
        doc["nodes"] =
            json!([{ "mesh": 0 }, { "camera": 0 }, { "translation": [0.0, 3.0, 5.0], "camera": 1 }]);
        doc["scenes"] = json!([{ "nodes": [0, 1, 2] }]);
    });
    let asset = load_gltf(&path).unwrap();
    assert_eq!(asset.cameras.len(), 1, "the orthographic camera is skipped: {:?}", asset.cameras);
    let cam = &asset.cameras[0];
    assert_eq!((cam.position, cam.forward), (Vec3::new(0.0, 3.0, 5.0), Vec3::NEG_Z));
    assert!((cam.yfov_degrees - 0.5f32.to_degrees()).abs() < 1e-4);

    // A scene file with no [[cameras]] looks through the environment's first camera,
    // placed by the environment's scale and offset.
    let text = format!(
        "[scene]\nname = \"cam\"\nframes = 1\n\n[environment]\ngltf = \"{}\"\nscale = 2.0\noffset = [1.0, 0.0, 0.0]\n",
        path.display()
    );
    let file = SceneFile::parse(dir.path().join("cam.toml"), text).unwrap();
    let camera = SceneAssets::load(&file).unwrap().describe(0.0).camera;
    assert_eq!(camera.eye, Vec3::new(1.0, 6.0, 10.0));
    assert!((camera.target - Vec3::new(1.0, 6.0, 9.0)).length() < 1e-5);
    assert!((camera.vfov_deg - 0.5f32.to_degrees()).abs() < 1e-4);
}
