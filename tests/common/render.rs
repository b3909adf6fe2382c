//! Rendering a scene description in process, without the command line.

use dormant::accel::{self, Backend};
use dormant::render::{render_frame, Film, Integrator, RenderScene, RenderSettings};
use dormant::scene::{Camera, SceneDescription, Sky, Sun};
use glam::Vec3;

/// A sun that gives no light.
pub const NO_SUN: Sun = Sun { direction: Vec3::Y, irradiance: Vec3::ZERO, angular_radius_deg: 0.5 };
/// A uniform sky of radiance 1.
pub const WHITE_SKY: Sky = Sky { zenith: Vec3::ONE, horizon: Vec3::ONE, ground: Vec3::ONE };
/// A sky that gives no light.
pub const BLACK_SKY: Sky = Sky { zenith: Vec3::ZERO, horizon: Vec3::ZERO, ground: Vec3::ZERO };

/// The first compiled backend (Embree when it is compiled in).
pub fn backend() -> Backend {
    Backend::compiled()[0]
}

/// A scene with nothing in it yet, seen by `camera` under `sun` and `sky`.
pub fn empty_scene(camera: Camera, sun: Sun, sky: Sky) -> SceneDescription {
    SceneDescription {
        name: "test".into(),
        materials: Vec::new(),
        textures: Vec::new(),
        statics: Vec::new(),
        prototypes: Vec::new(),
        bodies: Vec::new(),
        camera,
        sun,
        sky,
        lights: Vec::new(),
    }
}

/// `desc` rendered on `backend` with `integrator` at `width` x `height`, `spp` samples a pixel
/// (uniform, seed 0).
pub fn render(
    desc: &SceneDescription,
    backend: Backend,
    integrator: &dyn Integrator,
    width: u32,
    height: u32,
    spp: u32,
) -> Film {
    let mut a = accel::create(backend, None).unwrap();
    let scene = RenderScene::build(desc, a.as_mut()).unwrap();
    let settings = RenderSettings::new(width, height, spp);
    render_frame(&scene, a.query().unwrap(), integrator, &settings).unwrap().0
}
