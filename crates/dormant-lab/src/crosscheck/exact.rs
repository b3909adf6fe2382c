//! The f64 re-intersection of a hit's triangle and the bound on the error of the backends' f32
//! tests (derived in docs/crosscheck.md): what a verdict compares answers against.

use glam::{DMat3, DVec3, Vec3};
use serde::Serialize;

use dormant::accel::HitTriangle;
use dormant::geometry::Ray;

/// Unit roundoff of f32, `2^-24`.
pub const UNIT_ROUNDOFF: f64 = f32::EPSILON as f64 / 2.0;

/// Constants of the position bound (docs/crosscheck.md, "The bound"), in units of
/// [`UNIT_ROUNDOFF`] times the magnitudes they multiply.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct BoundConstants {
    /// The instance transform: inverting the f32 matrix and moving the ray into object space.
    pub transform: f64,
    /// The triangle test itself: vertex minus origin, shear or cross products, plane equation.
    pub test: f64,
    /// The triangle's normal from f32 edges, which tilts the plane about a vertex.
    pub plane: f64,
}

/// The constants `dormant verify` uses.
pub const BOUND: BoundConstants = BoundConstants { transform: 16.0, test: 16.0, plane: 4.0 };

/// A ray against one triangle's plane in f64, with the bounds of an f32 answer.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Exact {
    /// Where the ray meets the triangle's plane, in units of the ray's direction.
    pub t: f64,
    /// Barycentric coordinates of that point (weights of the three vertices; negative outside).
    pub barycentric: [f64; 3],
    /// Signed distance in the plane from that point to the nearest edge line (positive
    /// inside), world units.
    pub edge_margin: f64,
    /// `|cos|` of the angle between the ray and the triangle's normal.
    pub cos: f64,
    /// How far an f32 test may effectively move the triangle and the ray's origin, world units.
    pub position_bound: f64,
    /// Bound on `|t_f32 - t|`.
    pub t_bound: f64,
    /// An f32 test may decide hit or miss otherwise when `|edge_margin| <= edge_bound`.
    pub edge_bound: f64,
    /// The triangle's world-space vertices as re-intersected.
    pub vertices: [[f64; 3]; 3],
}

impl Exact {
    /// The point lies inside the triangle by more than the bound (every f32 test hits it).
    pub fn surely_inside(&self) -> bool {
        self.edge_margin > self.edge_bound
    }

    /// The point lies outside the triangle by more than the bound (no f32 test hits it).
    pub fn surely_outside(&self) -> bool {
        self.edge_margin < -self.edge_bound
    }

    /// `t` lies inside `[t_min, t_max]` by more than the bound.
    pub fn surely_within(&self, ray: &Ray) -> bool {
        self.t > f64::from(ray.t_min) + self.t_bound && self.t < f64::from(ray.t_max) - self.t_bound
    }

    /// `t` lies outside `[t_min, t_max]` by more than the bound.
    pub fn surely_beyond(&self, ray: &Ray) -> bool {
        self.t < f64::from(ray.t_min) - self.t_bound || self.t > f64::from(ray.t_max) + self.t_bound
    }

    /// Every f32 test reports this triangle as hit within the ray's interval.
    pub fn surely_hit(&self, ray: &Ray) -> bool {
        self.surely_inside() && self.surely_within(ray)
    }

    /// `|t - t_f32| / t_bound`: 1 at the bound.
    pub fn t_error_over_bound(&self, t_f32: f32) -> f64 {
        (f64::from(t_f32) - self.t).abs() / self.t_bound
    }
}

fn dvec(v: Vec3) -> DVec3 {
    DVec3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

/// An upper bound on the spectral norm of `m`: `sqrt(|m^T m|_inf)`, exact for rotations and
/// uniform scales (`m^T m` is then a multiple of the identity).
fn norm_2(m: &DMat3) -> f64 {
    let g = m.transpose() * *m;
    let rows = g.transpose();
    [rows.x_axis, rows.y_axis, rows.z_axis].iter().map(|r| r.abs().element_sum()).fold(0.0, f64::max).sqrt()
}

/// Re-intersects `ray` with `tri` in f64: the f32 ray and the f32 vertices and transform the
/// accelerator was given, promoted exactly. `None` for a degenerate triangle or a ray parallel
/// to its plane, where no bound holds.
pub fn reintersect(ray: &Ray, tri: &HitTriangle) -> Option<Exact> {
    let (linear, translation) = match &tri.transform {
        Some(xf) => {
            let m = &xf.matrix3;
            let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| dvec(c.into()));
            (DMat3::from_cols(cols[0], cols[1], cols[2]), dvec(xf.translation.into()))
        }
        None => (DMat3::IDENTITY, DVec3::ZERO),
    };
    let object = tri.vertices.map(dvec);
    let world = object.map(|v| linear * v + translation);
    let (o, d) = (dvec(ray.origin), dvec(ray.dir));
    let n = (world[1] - world[0]).cross(world[2] - world[0]);
    let (nn, nd) = (n.length(), n.dot(d));
    if nn == 0.0 || nd == 0.0 || !nn.is_finite() || !nd.is_finite() {
        return None;
    }
    let t = n.dot(world[0] - o) / nd;
    let p = o + t * d;
    // Barycentrics from the sub-triangles' signed areas, each edge's distance from its height.
    let mut barycentric = [0.0; 3];
    let mut edge_margin = f64::INFINITY;
    let mut edges = [0.0f64; 3];
    for i in 0..3 {
        let (b, c) = (world[(i + 1) % 3], world[(i + 2) % 3]);
        barycentric[i] = (b - p).cross(c - p).dot(n) / (nn * nn);
        edges[i] = (c - b).length();
        edge_margin = edge_margin.min(barycentric[i] * nn / edges[i]);
    }
    let cos = nd.abs() / (nn * d.length());
    let position_bound = position_bound(o, &object, &linear, translation, tri.transform.is_some())?;
    let aspect =
        edges.iter().copied().fold(0.0, f64::max) / edges.iter().copied().fold(f64::INFINITY, f64::min);
    Some(Exact {
        t,
        barycentric,
        edge_margin,
        cos,
        position_bound,
        t_bound: position_bound / (d.length() * cos),
        edge_bound: position_bound * aspect / cos,
        vertices: world.map(|v| v.to_array()),
    })
}

/// `delta` of docs/crosscheck.md: the transform term (instances), the test term in object
/// space, and the plane term, mapped to world space by the linear part's norm.
fn position_bound(
    o: DVec3,
    object: &[DVec3; 3],
    linear: &DMat3,
    translation: DVec3,
    instance: bool,
) -> Option<f64> {
    let inverse = linear.inverse();
    if !inverse.is_finite() {
        return None;
    }
    let (norm, norm_inv) = (norm_2(linear), norm_2(&inverse));
    let o_obj = inverse * (o - translation);
    let transform_term = if instance {
        BOUND.transform * norm * norm_inv * (o.abs().max_element() + translation.abs().max_element())
    } else {
        0.0
    };
    let v_max = object.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
    let test_term = BOUND.test * norm * (o_obj.abs().max_element() + v_max);
    let (e1, e2) = (object[1] - object[0], object[2] - object[0]);
    let e_max = e1.length().max(e2.length()).max((object[2] - object[1]).length());
    let plane_term = BOUND.plane * norm * e_max * e1.length() * e2.length() / e1.cross(e2).length();
    Some(UNIT_ROUNDOFF * (transform_term + test_term + plane_term))
}
