use glam::Vec3;

/// A ray `origin + t * dir` restricted to `t_min <= t <= t_max`. `dir` need not be normalised;
/// `t` is measured in units of `dir`. `time` is when in the camera's shutter the ray travels,
/// from 0 (open) to 1 (close): moving instances are where they are at that time (motion blur);
/// without blur nothing depends on it. Rays leaving a surface keep the time of the ray that
/// hit it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_min: f32,
    pub t_max: f32,
    pub time: f32,
}

impl Ray {
    /// The time of rays that name none: the middle of the shutter, where a centred shutter puts
    /// the frame's own instant.
    pub const FRAME_TIME: f32 = 0.5;

    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir, t_min: 0.0, t_max: f32::INFINITY, time: Self::FRAME_TIME }
    }

    pub fn segment(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self { origin, dir, t_min, t_max, time: Self::FRAME_TIME }
    }

    /// The same ray at shutter time `time`.
    pub fn at_time(self, time: f32) -> Self {
        Self { time, ..self }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }

    /// A ray leaving surface point `p` along `dir`, its origin pushed off the surface along
    /// `n` (the unit normal on the side `dir` leaves by) so it does not hit the surface it
    /// starts on. The push scales with the magnitude of `p`, as float spacing does.
    pub fn spawn(p: Vec3, n: Vec3, dir: Vec3) -> Self {
        Self::new(offset_origin(p, n), dir)
    }
}

/// `p` pushed off its surface along the unit normal `n` (see [`Ray::spawn`]).
pub fn offset_origin(p: Vec3, n: Vec3) -> Vec3 {
    p + n * (1e-4 * p.abs().max_element().max(1.0))
}
