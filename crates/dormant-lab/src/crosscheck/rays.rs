use glam::{Vec2, Vec3};

use dormant::geometry::{offset_origin, Ray};
use dormant::render::PinholeCamera;
use dormant::rng::SplitMix64;
use dormant::scene::SceneDescription;

/// `rays` at random shutter times in `[0, 1)` (motion blur), drawn from `seed`.
pub fn with_random_times(rays: Vec<Ray>, seed: u64) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    rays.into_iter().map(|r| r.at_time(rng.unit())).collect()
}

/// One primary ray through each pixel centre of a `width x height` image.
pub fn camera_rays(desc: &SceneDescription, width: u32, height: u32) -> Vec<Ray> {
    PinholeCamera::pixel_centre_rays(&desc.camera, width, height)
}

/// Every valid world-space triangle of the scene (static meshes and bodies), sampled uniformly
/// by triangle.
struct SurfaceSampler {
    triangles: Vec<[Vec3; 3]>,
    rng: SplitMix64,
}

impl SurfaceSampler {
    fn new(desc: &SceneDescription, seed: u64) -> Option<Self> {
        // Statics first, then bodies in order.
        let mut triangles: Vec<[Vec3; 3]> = Vec::new();
        for s in &desc.statics {
            let m = &s.mesh;
            triangles
                .extend((0..m.triangle_count()).filter(|&i| m.triangle_is_valid(i)).map(|i| m.triangle(i)));
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
        (!triangles.is_empty()).then(|| Self { triangles, rng: SplitMix64::new(seed) })
    }

    /// A random point on a random triangle and the triangle's unit normal.
    fn point(&mut self) -> (Vec3, Vec3) {
        let [a, b, c] = self.triangles[self.rng.below(self.triangles.len())];
        let mut uv = Vec2::new(self.rng.unit(), self.rng.unit());
        if uv.x + uv.y > 1.0 {
            uv = Vec2::ONE - uv;
        }
        (a + uv.x * (b - a) + uv.y * (c - a), (b - a).cross(c - a).normalize_or_zero())
    }

    /// A uniformly random direction.
    fn direction(&mut self) -> Vec3 {
        let z = self.rng.signed();
        let phi = std::f32::consts::TAU * self.rng.unit();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The normal `n` turned to the side `dir` leaves by.
fn facing(n: Vec3, dir: Vec3) -> Vec3 {
    if n.dot(dir) >= 0.0 {
        n
    } else {
        -n
    }
}

/// `count` rays leaving random points on the scene's triangles (static meshes and bodies, in
/// world space) in uniformly random directions: the secondary rays a renderer traces.
pub fn surface_rays(desc: &SceneDescription, count: usize, seed: u64) -> Vec<Ray> {
    let Some(mut s) = SurfaceSampler::new(desc, seed) else { return Vec::new() };
    (0..count)
        .map(|_| {
            let (p, n) = s.point();
            let dir = s.direction();
            Ray::spawn(p, facing(n, dir), dir)
        })
        .collect()
}

/// `count` segments between two random surface points, ending short of the second as the
/// renderer's shadow rays end short of a light (`t_max = distance * (1 - 1e-4)`, unit
/// direction): occlusion queries with a finite interval.
pub fn shadow_rays(desc: &SceneDescription, count: usize, seed: u64) -> Vec<Ray> {
    let Some(mut s) = SurfaceSampler::new(desc, seed) else { return Vec::new() };
    let mut rays = Vec::with_capacity(count);
    while rays.len() < count {
        let ((p, n), (q, _)) = (s.point(), s.point());
        let Some(dir) = (q - p).try_normalize() else { continue };
        let origin = offset_origin(p, facing(n, dir));
        let distance = (q - origin).length();
        rays.push(Ray::segment(origin, dir, 0.0, distance * (1.0 - 1e-4)));
    }
    rays
}
