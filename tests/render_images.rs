//! Renderer tests: analytic scenes (white furnace, a directly lit plane), deterministic output
//! across thread counts, equal images from both backends, and from camera-ray packets and
//! single rays.

use crate::common;

use common::cli::{dormant, succeeds};
use common::render::{backend, empty_scene, render, BLACK_SKY, NO_SUN, WHITE_SKY};
use dormant::accel::{self, Backend, Hit, SceneQuery};
use dormant::geometry::{primitives, Ray};
use dormant::render::{
    render_frame, AmbientOcclusion, DirectLighting, Integrator, PathTracer, RenderScene, RenderSettings,
};
use dormant::scene::{Body, Camera, Material, Prototype, StaticMesh, Sun};
use glam::{Affine3A, Vec3};

#[test]
fn white_furnace_sphere_reflects_its_albedo_of_the_sky() {
    // A Lambertian sphere of albedo 0.8 under a uniform sky of radiance 1: it is convex, so
    // every reflected ray escapes and the sphere's radiance is exactly 0.8.
    let camera = Camera::pinhole(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0);
    let mut desc = empty_scene(camera, NO_SUN, WHITE_SKY);
    desc.materials.push(Material::lambertian(Vec3::splat(0.8)));
    desc.prototypes.push(Prototype {
        name: "sphere".into(),
        mesh: primitives::uv_sphere(1.0, 64, 32),
        material: 0,
    });
    desc.bodies.push(Body { prototype: 0, transform: Affine3A::IDENTITY });
    let film = render(
        &desc,
        backend(),
        &PathTracer { clamp_indirect: f32::INFINITY, ..PathTracer::default() },
        32,
        32,
        64,
    );
    // The central 8x8 pixels all see the sphere.
    let mut sum = Vec3::ZERO;
    for y in 12..20 {
        for x in 12..20 {
            sum += film.pixels[y * 32 + x];
        }
    }
    let mean = sum / 64.0;
    assert!((mean - Vec3::splat(0.8)).abs().max_element() < 0.01, "furnace radiance {mean}, expected 0.8");
    // Pixels that miss the sphere see the sky.
    assert!((film.pixels[0] - Vec3::ONE).abs().max_element() < 1e-6);
}

#[test]
fn directly_lit_plane_matches_the_closed_form() {
    // L = albedo / pi * E * cos(theta) for a Lambertian plane under a sun of irradiance E.
    let elevation = 60f32.to_radians();
    let sun = Sun {
        direction: Vec3::new(0.0, elevation.sin(), elevation.cos()),
        irradiance: Vec3::splat(2.0),
        angular_radius_deg: 0.25,
    };
    let camera = Camera::pinhole(Vec3::new(0.0, 5.0, 0.0), Vec3::ZERO, Vec3::Z, 30.0);
    let mut desc = empty_scene(camera, sun, BLACK_SKY);
    desc.materials.push(Material::lambertian(Vec3::splat(0.5)));
    desc.statics.push(StaticMesh { mesh: primitives::ground_plane(100.0, 0.0, 1), material: 0 });
    let film = render(&desc, backend(), &PathTracer::default(), 16, 16, 16);
    let expected = 0.5 / std::f32::consts::PI * 2.0 * elevation.sin();
    for p in &film.pixels {
        assert!((p.x - expected).abs() < 0.01 * expected, "pixel {p}, expected {expected}");
    }
}

#[cfg(feature = "embree")]
#[test]
fn embree_and_bvh_images_agree_within_float_noise() {
    let desc = dormant::scene::default_scene();
    let pt = PathTracer::default();
    let a = render(&desc, Backend::Embree, &pt, 64, 64, 8);
    let b = render(&desc, Backend::Bvh, &pt, 64, 64, 8);
    let n = a.pixels.len() as f32;
    let mse: f32 =
        a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x - *y).length_squared() / 3.0).sum::<f32>() / n;
    assert!(mse.sqrt() < 1e-3, "RMSE {} between Embree and BVH images", mse.sqrt());
}

#[test]
fn png_is_byte_identical_with_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mut pngs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(threads);
        succeeds(
            dormant()
                .args(["--threads", threads, "render", "--size", "64x40", "--spp", "4", "--quiet", "--out"])
                .arg(&out),
        );
        pngs.push(std::fs::read(out.join("frame_0000.png")).unwrap());
    }
    assert!(pngs[0] == pngs[1], "images differ between 1 and 2 threads");
}

/// Forwards the single-ray queries only, so the renderer's camera-ray packets fall back to
/// the per-ray loop.
struct SingleRays<'a>(&'a dyn SceneQuery);

impl SceneQuery for SingleRays<'_> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }

    fn intersect_p(&self, ray: &Ray) -> bool {
        self.0.intersect_p(ray)
    }
}

#[test]
fn camera_ray_packets_give_the_same_image_as_single_rays() {
    let desc = dormant::scene::default_scene();
    let integrators: [&dyn Integrator; 3] =
        [&PathTracer::default(), &DirectLighting, &AmbientOcclusion { radius: 1.0 }];
    for backend in Backend::compiled() {
        let mut a = accel::create(backend, Some(2)).unwrap();
        let scene = RenderScene::build(&desc, a.as_mut()).unwrap();
        let q = a.query().unwrap();
        // Odd sizes leave partial 16x16 tiles and partial packets at the borders.
        for (integrator, spp) in integrators.into_iter().zip([3, 1, 2]) {
            let settings = RenderSettings { seed: 1, ..RenderSettings::new(37, 23, spp) };
            let (packets, p_stats) = render_frame(&scene, q, integrator, &settings).unwrap();
            let (single, s_stats) = render_frame(&scene, &SingleRays(q), integrator, &settings).unwrap();
            assert!(packets.pixels == single.pixels, "{backend}: packets changed the image");
            assert_eq!(p_stats.rays, s_stats.rays);
        }
    }
}
