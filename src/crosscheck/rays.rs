use glam::{Vec2, Vec3};

use crate::geometry::Ray;
use crate::render::PinholeCamera;
use crate::rng::SplitMix64;
use crate::scene::SceneDescription;

/// `rays` at random shutter times in `[0, 1)` (motion blur), drawn from `seed`.
pub fn with_random_times(rays: Vec<Ray>, seed: u64) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    rays.into_iter().map(|r| r.at_time(rng.unit())).collect()
}

/// One primary ray through each pixel centre of a `width x height` image.
pub fn camera_rays(desc: &SceneDescription, width: u32, height: u32) -> Vec<Ray> {
    PinholeCamera::pixel_centre_rays(&desc.camera, width, height)
}

/// `count` rays leaving random points on the scene's triangles (static meshes and bodies, in
/// world space) in uniformly random directions: the secondary rays a renderer traces.
pub fn surface_rays(desc: &SceneDescription, count: usize, seed: u64) -> Vec<Ray> {
    // Every valid world-space triangle, statics first, then bodies in order.
    let mut triangles: Vec<[Vec3; 3]> = Vec::new();
    for s in &desc.statics {
        let m = &s.mesh;
        triangles.extend((0..m.triangle_count()).filter(|&i| m.triangle_is_valid(i)).map(|i| m.triangle(i)));
    }
    for b in &desc.bodies {
        let Some(p) = desc.prototypes.get(b.prototype as usize) else { continue };
        let m = &p.mesh;
        triangles.extend(
            (0..m.triangle_count())
                .filter(|&i| m.triangle_is_valid(i))
                .map(|i| m.triangle(i).map(|v| b.transform.transform_point3(v))),
        );
    }
    if triangles.is_empty() {
        return Vec::new();
    }
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let [a, b, c] = triangles[rng.below(triangles.len())];
            let mut uv = Vec2::new(rng.unit(), rng.unit());
            if uv.x + uv.y > 1.0 {
                uv = Vec2::ONE - uv;
            }
            let p = a + uv.x * (b - a) + uv.y * (c - a);
            let n = (b - a).cross(c - a).normalize_or_zero();
            // Uniform direction on the sphere.
            let z = rng.signed();
            let phi = std::f32::consts::TAU * rng.unit();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let dir = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            // Leave the surface on the side the ray heads to.
            let side = if n.dot(dir) >= 0.0 { n } else { -n };
            Ray::spawn(p, side, dir)
        })
        .collect()
}
