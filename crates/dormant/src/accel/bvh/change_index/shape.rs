//! The exact side of the change index: whether a ray segment comes near a changed body's
//! geometry (a small mesh at the body's poses before and after the change), not only its box.
//!
//! "Near" is a distance, not a hit test: a tracer works in f32 and moves the ray into each
//! instance's object space, so the ray it intersects lies within some tolerance of the exact
//! one, and the hit it reports (and so the segment's end) is as uncertain. At a grazing angle
//! that uncertainty is small across the surface but large along the ray, which defeats any
//! margin in ray distance or barycentric coordinates. So the loose test asks whether the
//! segment passes within a tolerance of the triangle (a superset of every tracer's hits), and
//! the strict one whether it crosses the triangle so clearly that every ray within the
//! tolerance does too. The tolerance (1e-5 of the magnitudes involved, in f64) is far larger
//! than either tracer's rounding and far smaller than a body.

use glam::{Affine3A, DVec3, Vec3};

use super::super::flat::{build, STACK_SIZE};
use super::super::BuildParams;
use crate::geometry::{Aabb, Ray};

/// The geometry a change box bounds: mesh `mesh` of the index's meshes placed by each pose
/// there is (a body before and after the change; one for a body that appeared or left).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ChangeShape {
    pub mesh: u32,
    pub poses: [Option<Affine3A>; 2],
}

/// Meshes with at most this many triangles are tested exactly; larger ones by their box, so
/// that a query never walks thousands of triangles.
pub(crate) const EXACT_MESH_TRIANGLES: usize = 256;

/// The tolerance relative to the magnitudes a ray's computation involves (its origin, the
/// body's position and size): about 80 times f32's epsilon.
const RELATIVE_TOLERANCE: f64 = 1e-5;

/// Which way a test leans where the tracers' rounding could go either way.
#[derive(Clone, Copy, PartialEq)]
enum Margin {
    /// Within the tolerance: never misses what a tracer could hit.
    Loose,
    /// Through, by more than the tolerance: never hits what a tracer could miss.
    Strict,
}

/// A mesh ready for exact tests: a BVH over its triangles in object space (boxes in f64) and
/// its triangles in leaf order.
#[derive(Clone, Debug, Default)]
pub(super) struct ExactMesh {
    nodes: Vec<MeshNode>,
    triangles: Vec<Triangle>,
    /// The largest coordinate magnitude of the mesh.
    reach: f64,
    /// Every triangle lies on a face of the mesh's bounding box (a cuboid): a segment near a
    /// triangle is then near the box's surface, which one box test decides.
    on_its_box: bool,
    /// Moreover each face is two triangles split along a diagonal: whether a segment surely
    /// crosses a triangle is then decided on the box's faces too.
    halved_faces: bool,
}

/// A node of a mesh's BVH: its box, and its children (interior: the first, the second follows
/// it) or its triangles (leaf: `count` from `first`).
#[derive(Clone, Copy, Debug)]
struct MeshNode {
    min: DVec3,
    max: DVec3,
    first: u32,
    count: u32,
}

/// A triangle as the tests use it: its plane (unit normal and offset) and, per edge, the
/// unit normal in the plane pointing inwards and its offset. Degenerate triangles are kept
/// with a zero normal, which makes every test pass loosely and fail strictly.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    corners: [DVec3; 3],
    normal: DVec3,
    offset: f64,
    edge_normals: [DVec3; 3],
    edge_offsets: [f64; 3],
}

/// A shape ready for segment tests: its mesh, and per pose the world-to-object transform and
/// the scale of world distances in object space.
#[derive(Clone, Copy, Debug)]
pub(super) struct ShapeTest {
    mesh: u32,
    poses: [Option<ObjectPose>; 2],
}

#[derive(Clone, Copy, Debug)]
struct ObjectPose {
    to_object: Affine3A,
    /// The largest stretch `to_object` applies to a length.
    scale: f64,
    /// The largest coordinate magnitude of the body's position in the world.
    reach: f64,
}

/// A ray segment in a mesh's object space, in f64, and the tolerance of tests against it.
struct Segment {
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
    tolerance: f64,
}

impl Triangle {
    fn new(corners: [DVec3; 3]) -> Self {
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize_or_zero();
        let mut edge_normals = [DVec3::ZERO; 3];
        let mut edge_offsets = [0.0; 3];
        for i in 0..3 {
            let (a, b) = (corners[i], corners[(i + 1) % 3]);
            // Counter-clockwise about `normal`, so `normal x edge` points inwards.
            let m = normal.cross(b - a).normalize_or_zero();
            edge_normals[i] = m;
            edge_offsets[i] = m.dot(a);
        }
        Self { corners, normal, offset: normal.dot(corners[0]), edge_normals, edge_offsets }
    }
}

impl ExactMesh {
    /// The mesh of `triangles`; empty (never tested) when it has more than
    /// [`EXACT_MESH_TRIANGLES`].
    pub(super) fn new(triangles: &[[Vec3; 3]]) -> Self {
        if triangles.is_empty() || triangles.len() > EXACT_MESH_TRIANGLES {
            return Self::default();
        }
        let on_its_box = lies_on_its_box(triangles);
        let halved_faces = on_its_box && halves_each_face(triangles);
        let bounds: Vec<Aabb> = triangles.iter().map(|t| Aabb::from_points(*t)).collect();
        let (bvh, order) = build(&bounds, BuildParams::BALANCED);
        let nodes = bvh
            .nodes
            .iter()
            .map(|n| MeshNode {
                min: n.min.as_dvec3(),
                max: n.max.as_dvec3(),
                first: n.first,
                count: n.count,
            })
            .collect();
        let triangles: Vec<Triangle> =
            order.iter().map(|&i| Triangle::new(triangles[i as usize].map(|v| v.as_dvec3()))).collect();
        let root = &bvh.nodes[0];
        let reach = f64::from(root.min.abs().max(root.max.abs()).max_element());
        Self { nodes, triangles, reach, on_its_box, halved_faces }
    }

    /// Whether the segment meets the mesh (`margin` as for a triangle): the triangles of the
    /// leaves whose boxes, grown by the tolerance, it passes through.
    fn meets(&self, segment: &Segment, margin: Margin) -> bool {
        match (margin, self.nodes.first()) {
            (Margin::Loose, Some(root)) if self.on_its_box => {
                return segment.meets_box(root.min, root.max) && !segment.inside_box(root.min, root.max);
            }
            (Margin::Strict, Some(root)) if self.halved_faces => {
                return segment.crosses_box_surface(root.min, root.max);
            }
            _ => {}
        }
        let mut stack = [0u32; STACK_SIZE];
        let mut top = usize::from(!self.nodes.is_empty());
        while top > 0 {
            top -= 1;
            let n = &self.nodes[stack[top] as usize];
            if !segment.meets_box(n.min, n.max) {
                continue;
            }
            if n.count > 0 {
                let leaf = &self.triangles[n.first as usize..(n.first + n.count) as usize];
                if leaf.iter().any(|t| segment.meets(t, margin)) {
                    return true;
                }
                continue;
            }
            debug_assert!(top + 2 <= STACK_SIZE, "a mesh BVH deeper than the traversal stack");
            stack[top] = n.first;
            stack[top + 1] = n.first + 1;
            top += 2;
        }
        false
    }
}

/// Whether `triangles` make up the surface of their bounding box: each lies in a face (its
/// three corners share the box's least or greatest coordinate on some axis) and together they
/// cover its area. Lying in the faces is what makes the box test conservative; the area, that
/// it is as tight as the triangles (a flat or open mesh keeps its triangle tests).
fn lies_on_its_box(triangles: &[[Vec3; 3]]) -> bool {
    let bounds = Aabb::from_points(triangles.iter().flatten().copied());
    let size = (bounds.max - bounds.min).as_dvec3();
    let on_faces = triangles.iter().all(|t| {
        (0..3).any(|axis| {
            let on = |side: f32| t.iter().all(|v| v[axis] == side);
            on(bounds.min[axis]) || on(bounds.max[axis])
        })
    });
    let area: f64 = triangles
        .iter()
        .map(|[a, b, c]| 0.5 * (*b - *a).as_dvec3().cross((*c - *a).as_dvec3()).length())
        .sum();
    let surface = 2.0 * (size.x * size.y + size.y * size.z + size.z * size.x);
    on_faces && size.min_element() > 0.0 && (area - surface).abs() <= 1e-4 * surface
}

/// Whether the 12 `triangles` (on the faces of their box, covering it: [`lies_on_its_box`])
/// are two per face, split along a diagonal: every corner is a corner of the box, and on each
/// face two triangles share two opposite corners. Only then does a crossing inside a face and
/// away from both its diagonals lie inside one triangle.
fn halves_each_face(triangles: &[[Vec3; 3]]) -> bool {
    let bounds = Aabb::from_points(triangles.iter().flatten().copied());
    // A box corner as three bits, one per axis: 0 at the least coordinate, 1 at the greatest.
    let corner = |v: Vec3| -> Option<u8> {
        (0..3).try_fold(0u8, |bits, axis| match v[axis] {
            c if c == bounds.min[axis] => Some(bits),
            c if c == bounds.max[axis] => Some(bits | 1 << axis),
            _ => None,
        })
    };
    let mut faces: [Vec<[u8; 3]>; 6] = Default::default();
    for t in triangles {
        let Some(c) = t.iter().map(|&v| corner(v)).collect::<Option<Vec<u8>>>() else { return false };
        let Some(face) = (0..3).find(|&a| c.iter().all(|&x| x & (1 << a) == c[0] & (1 << a))) else {
            return false;
        };
        faces[face * 2 + usize::from(c[0] & (1 << face) != 0)].push([c[0], c[1], c[2]]);
    }
    triangles.len() == 12
        && faces.iter().enumerate().all(|(f, tris)| {
            let [a, b] = tris.as_slice() else { return false };
            let shared: Vec<u8> = a.iter().copied().filter(|x| b.contains(x)).collect();
            let opposite = 0b111 & !(1u8 << (f / 2));
            shared.len() == 2 && shared[0] ^ shared[1] == opposite
        })
}

impl ShapeTest {
    /// `shape` ready for tests against `meshes`, or `None` (test by the box) when its mesh is
    /// missing or not tested exactly, or a pose does not invert.
    pub(super) fn new(shape: &ChangeShape, meshes: &[ExactMesh]) -> Option<Self> {
        if meshes.get(shape.mesh as usize)?.triangles.is_empty() {
            return None;
        }
        let prepare = |pose: Option<Affine3A>| -> Option<Option<ObjectPose>> {
            let Some(pose) = pose else { return Some(None) };
            let to_object = pose.inverse();
            if pose.matrix3.determinant() == 0.0 || !to_object.is_finite() {
                return None;
            }
            let m = to_object.matrix3;
            let scale = f64::from(m.x_axis.length() + m.y_axis.length() + m.z_axis.length());
            let reach = f64::from(pose.translation.abs().max_element());
            Some(Some(ObjectPose { to_object, scale, reach }))
        };
        Some(Self { mesh: shape.mesh, poses: [prepare(shape.poses[0])?, prepare(shape.poses[1])?] })
    }

    /// Whether the change can change what the segment of `ray` finds: it comes near the mesh
    /// at one of the poses. An occlusion ray that surely passes through the mesh at both poses
    /// is blocked before and after, so for it such a change does not count.
    pub(super) fn changes_for(&self, meshes: &[ExactMesh], ray: &Ray, occlusion: bool) -> bool {
        let mesh = &meshes[self.mesh as usize];
        let segments = self.poses.map(|p| p.map(|p| Segment::in_object_space(ray, &p, mesh.reach)));
        let meets = |s: &Option<Segment>, margin| s.as_ref().is_some_and(|s| mesh.meets(s, margin));
        if !occlusion {
            return meets(&segments[0], Margin::Loose) || meets(&segments[1], Margin::Loose);
        }
        let near = [meets(&segments[0], Margin::Loose), meets(&segments[1], Margin::Loose)];
        if !(near[0] || near[1]) {
            return false;
        }
        !(near == [true, true] && segments.iter().all(|s| meets(s, Margin::Strict)))
    }

    /// Whether the segment of `ray` surely crosses the mesh at both poses (every ray within
    /// the tolerance does): an occlusion ray it blocks before the change it blocks after.
    pub(super) fn blocks_at_both(&self, meshes: &[ExactMesh], ray: &Ray) -> bool {
        let mesh = &meshes[self.mesh as usize];
        self.poses.iter().all(|p| {
            p.is_some_and(|p| mesh.meets(&Segment::in_object_space(ray, &p, mesh.reach), Margin::Strict))
        })
    }
}

impl Segment {
    /// The segment of `ray` in the object space of `pose`, whose mesh's coordinates reach
    /// `mesh_reach`; the ray parameter is kept (the direction is not normalised).
    fn in_object_space(ray: &Ray, pose: &ObjectPose, mesh_reach: f64) -> Self {
        // What a tracer's rounding scales with: the ray's origin and the distance it travels to
        // the body (at most the origin's and the body's magnitudes), and the body's size.
        let magnitude = f64::from(ray.origin.abs().max_element()) + pose.reach + mesh_reach;
        Segment {
            origin: pose.to_object.transform_point3(ray.origin).as_dvec3(),
            dir: pose.to_object.transform_vector3(ray.dir).as_dvec3(),
            t_min: f64::from(ray.t_min),
            t_max: f64::from(ray.t_max),
            tolerance: RELATIVE_TOLERANCE * (1.0 + magnitude) * pose.scale,
        }
    }

    /// Whether the segment passes through the box grown by the tolerance (slab test).
    /// Not-a-number anywhere counts as meeting it.
    fn meets_box(&self, min: DVec3, max: DVec3) -> bool {
        let (min, max) = (min - self.tolerance, max + self.tolerance);
        let (mut t0, mut t1) = (self.t_min, self.t_max);
        for axis in 0..3 {
            let (o, d) = (self.origin[axis], self.dir[axis]);
            if d == 0.0 {
                if o < min[axis] || o > max[axis] {
                    return false;
                }
                continue;
            }
            let (a, b) = ((min[axis] - o) / d, (max[axis] - o) / d);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
            if t0 > t1 {
                return false;
            }
        }
        true
    }

    /// Whether the whole segment lies inside the box shrunk by the tolerance, so farther than
    /// that from its surface (both ends inside: the box is convex).
    fn inside_box(&self, min: DVec3, max: DVec3) -> bool {
        let (min, max) = (min + self.tolerance, max - self.tolerance);
        let inside = |p: DVec3| p.cmpgt(min).all() && p.cmplt(max).all();
        self.t_max.is_finite()
            && inside(self.origin + self.t_min * self.dir)
            && inside(self.origin + self.t_max * self.dir)
    }

    /// Whether the segment meets triangle `t`: loosely, whether it passes within the
    /// tolerance of it; strictly, whether it crosses it with every ray within the tolerance
    /// crossing it too.
    fn meets(&self, t: &Triangle, margin: Margin) -> bool {
        match margin {
            Margin::Loose => self.passes_near(t),
            Margin::Strict => self.crosses(t),
        }
    }

    /// Whether the segment passes within the tolerance of `t`: some part of it lies within
    /// the tolerance of the triangle's plane, and that part, seen in the plane, is not
    /// separated from the triangle by more than the tolerance (the separating axes of a
    /// segment and a triangle in a plane: the triangle's edge normals and the segment's).
    /// Conservative: distances across and along the plane are bounded apart.
    /// A bounding-sphere test first did not pay: docs/lab/reuse.md#2026-12-05-the-demolition-over-120-frames-bench-reuse
    fn passes_near(&self, t: &Triangle) -> bool {
        let eps = self.tolerance;
        let (a, b) = (t.normal.dot(self.origin) - t.offset, t.normal.dot(self.dir));
        let (lo, hi) = if b == 0.0 {
            if a.abs() > eps {
                return false;
            }
            (self.t_min, self.t_max)
        } else {
            let (x, y) = ((-eps - a) / b, (eps - a) / b);
            (x.min(y).max(self.t_min), x.max(y).min(self.t_max))
        };
        if lo > hi {
            return false;
        }
        if !hi.is_finite() || !lo.is_finite() {
            return true;
        }
        // Along the plane a tracer's crossing is uncertain by the tolerance over the sine of the
        // ray's angle to it: f32 barycentrics of a ray at 0.005 degrees err by 1e-3.
        let sine = b.abs() / self.dir.length();
        let wide = if sine > 0.0 { eps.max(eps / sine) } else { eps };
        let (q0, q1) = (self.origin + lo * self.dir, self.origin + hi * self.dir);
        for (m, &offset) in t.edge_normals.iter().zip(&t.edge_offsets) {
            if m.dot(q0) - offset < -wide && m.dot(q1) - offset < -wide {
                return false;
            }
        }
        let across = t.normal.cross(q1 - q0).normalize_or_zero();
        let sides = t.corners.map(|c| across.dot(c - q0));
        !(sides.iter().all(|&s| s > wide) || sides.iter().all(|&s| s < -wide))
    }

    /// Whether the segment surely crosses a triangle of the box `min..max` whose faces are each
    /// two triangles split along a diagonal: as [`Self::crosses`] asks of a triangle, it
    /// crosses a face's plane from one side to the other by more than the tolerance, at a
    /// point farther than the widest crossing from the face's edges and from both its
    /// diagonals (either may be the one its triangles share), so inside one triangle.
    fn crosses_box_surface(&self, min: DVec3, max: DVec3) -> bool {
        let eps = self.tolerance;
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let (du, dv) = (max[u] - min[u], max[v] - min[v]);
            let diagonal = (du * du + dv * dv).sqrt();
            for plane in [min[axis], max[axis]] {
                let (a, b) = (self.origin[axis] - plane, self.dir[axis]);
                let start = a + b * self.t_min;
                let end = if self.t_max.is_finite() { a + b * self.t_max } else { b * f64::INFINITY };
                if !((start < -eps && end > eps) || (start > eps && end < -eps)) {
                    continue;
                }
                let p = self.origin - (a / b) * self.dir;
                let inside = eps * self.dir.length() / b.abs();
                let (pu, pv) = (p[u] - min[u], p[v] - min[v]);
                let in_face = pu > inside && du - pu > inside && pv > inside && dv - pv > inside;
                let off_diagonals = (pu * dv - pv * du).abs() > inside * diagonal
                    && (pu * dv + (pv - dv) * du).abs() > inside * diagonal;
                if in_face && off_diagonals {
                    return true;
                }
            }
        }
        false
    }

    /// Whether the segment surely crosses `t`: its ends lie on either side of the plane by
    /// more than the tolerance, and it crosses the plane inside the triangle by more than the
    /// widest any ray within the tolerance could cross it (the tolerance over the sine of
    /// the angle between ray and plane).
    fn crosses(&self, t: &Triangle) -> bool {
        let eps = self.tolerance;
        let (a, b) = (t.normal.dot(self.origin) - t.offset, t.normal.dot(self.dir));
        let (start, end) =
            (a + b * self.t_min, if self.t_max.is_finite() { a + b * self.t_max } else { b * f64::INFINITY });
        if !((start < -eps && end > eps) || (start > eps && end < -eps)) {
            return false;
        }
        let crossing = self.origin - (a / b) * self.dir;
        let inside = eps * self.dir.length() / b.abs();
        t.edge_normals.iter().zip(&t.edge_offsets).all(|(m, &offset)| m.dot(crossing) - offset > inside)
    }
}

#[cfg(test)]
mod tests {
    use glam::{Mat3A, Vec3A};

    use super::*;
    use crate::geometry::primitives;

    fn cube_mesh(half: f32) -> Vec<ExactMesh> {
        let m = primitives::cuboid(Vec3::splat(half));
        vec![ExactMesh::new(&(0..m.triangle_count()).map(|i| m.triangle(i)).collect::<Vec<_>>())]
    }

    #[test]
    fn a_grazing_ray_that_ends_on_a_face_meets_it() {
        // From the demolition: a bounce ray at half a degree to a boulder's face, whose hit
        // Embree placed 5.5e-4 short of where the exact ray crosses the face (4.6e-6 off the
        // face across it). A margin in ray distance missed it.
        let meshes = cube_mesh(0.3);
        let pose = Affine3A {
            matrix3: Mat3A::from_cols(
                Vec3A::new(0.99843395, -0.053423658, 0.016601512),
                Vec3A::new(0.037053972, 0.40918946, -0.9116969),
                Vec3A::new(0.04191301, 0.91088426, 0.41052818),
            ),
            translation: Vec3A::new(54.996326, 0.46333042, 40.85696),
        };
        let shape = ShapeTest::new(&ChangeShape { mesh: 0, poses: [Some(pose), None] }, &meshes).unwrap();
        let (origin, dir) =
            (Vec3::new(54.682343, 0.005468234, 39.392784), Vec3::new(0.003954869, 0.22259788, 0.9749023));
        assert!(shape.changes_for(&meshes, &Ray::segment(origin, dir, 0.0, 1.6184489), false));
        // The same ray stopped a centimetre short of the face does not.
        assert!(!shape.changes_for(&meshes, &Ray::segment(origin, dir, 0.0, 1.0), false));
    }

    #[test]
    fn an_occlusion_ray_through_the_body_at_both_poses_is_not_a_change() {
        let meshes = cube_mesh(0.5);
        let (here, there) = (Affine3A::IDENTITY, Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0)));
        let shape =
            ShapeTest::new(&ChangeShape { mesh: 0, poses: [Some(here), Some(there)] }, &meshes).unwrap();
        // Not through a face's diagonal, where no single triangle is surely crossed.
        let through = Ray::segment(Vec3::new(0.1, 0.3, -5.0), Vec3::Z, 0.0, 10.0);
        assert!(shape.changes_for(&meshes, &through, false));
        assert!(!shape.changes_for(&meshes, &through, true));
        // Through the edge the body leaves: blocked before, not after.
        let edge = Ray::segment(Vec3::new(-0.45, 0.3, -5.0), Vec3::Z, 0.0, 10.0);
        assert!(shape.changes_for(&meshes, &edge, true));
    }

    /// 20,000 segments (xorshift from `seed`) around a unit cube at the origin: origins within
    /// 1.5 or 0.45 of it by turns, one in seven infinite, the others up to `length` long
    /// (in ray parameter), tolerance 1e-3.
    fn random_segments(seed: u64, length: f64) -> impl Iterator<Item = Segment> {
        let mut state = seed;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        (0..20_000).map(move |i| {
            let origin = DVec3::new(next(), next(), next()) * if i % 2 == 0 { 3.0 } else { 0.9 };
            let dir = DVec3::new(next(), next(), next());
            let t_max = if i % 7 == 0 { f64::INFINITY } else { length * next().abs() };
            Segment { origin, dir, t_min: 0.0, t_max, tolerance: 1e-3 }
        })
    }

    #[test]
    fn a_cuboid_is_tested_by_its_box_and_never_misses_what_its_triangles_meet() {
        let by_box = &cube_mesh(0.5)[0];
        assert!(by_box.on_its_box);
        let by_triangles = ExactMesh { on_its_box: false, halved_faces: false, ..by_box.clone() };
        let (mut near, mut only_box) = (0, 0);
        for segment in random_segments(0x2545_f491_4f6c_dd1d, 2.0) {
            let Segment { origin, dir, t_max, .. } = segment;
            let exact = by_triangles.meets(&segment, Margin::Loose);
            let boxed = by_box.meets(&segment, Margin::Loose);
            assert!(boxed || !exact, "the box test missed a segment near a face: {origin} {dir} {t_max}");
            near += usize::from(exact);
            only_box += usize::from(boxed && !exact);
        }
        // Both kinds of segment occur, and the box is about as tight as the triangles.
        assert!(near > 1_000, "{near}");
        assert!(only_box * 50 < near, "{only_box} of {near}");
        // A mesh with a triangle off its box's faces is tested by its triangles.
        let tris = [[Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.5, 1.0)]];
        assert!(!ExactMesh::new(&tris).on_its_box);
    }

    #[test]
    fn a_cuboid_surely_crossed_by_its_box_is_surely_crossed_by_a_triangle() {
        let by_box = &cube_mesh(0.5)[0];
        assert!(by_box.halved_faces);
        let by_triangles = ExactMesh { on_its_box: false, halved_faces: false, ..by_box.clone() };
        let (mut crossed, mut only_triangles) = (0, 0);
        for segment in random_segments(0x9e37_79b9_7f4a_7c15, 4.0) {
            let Segment { origin, dir, t_max, .. } = segment;
            let exact = by_triangles.meets(&segment, Margin::Strict);
            let boxed = by_box.meets(&segment, Margin::Strict);
            assert!(exact || !boxed, "the box said a segment surely crosses: {origin} {dir} {t_max}");
            crossed += usize::from(exact);
            only_triangles += usize::from(exact && !boxed);
        }
        // Both kinds occur, and the box misses only crossings near a face's other diagonal.
        assert!(crossed > 1_000, "{crossed}");
        assert!(only_triangles * 20 < crossed, "{only_triangles} of {crossed}");
        // With one triangle given twice (a face left half bare), it is not.
        let cube = primitives::cuboid(Vec3::splat(0.5));
        let mut tris: Vec<[Vec3; 3]> = (0..cube.triangle_count()).map(|i| cube.triangle(i)).collect();
        assert!(halves_each_face(&tris));
        tris[0] = tris[1];
        assert!(!halves_each_face(&tris));
    }

    #[test]
    fn a_ray_nearly_parallel_to_a_face_that_a_tracer_hits_meets_it() {
        // Found by the property test: at 0.005 degrees to the triangle the exact ray crosses
        // its plane 6.7e-4 outside an edge, and Embree's f32 barycentrics put the hit inside.
        let tri = [
            Vec3::new(1.2949696, -0.63098377, 1.4653318),
            Vec3::new(2.1710954, -0.65735596, 1.3331103),
            Vec3::new(1.0866274, 0.25746173, 1.8705345),
        ];
        let meshes = vec![ExactMesh::new(&[tri])];
        let pose = Affine3A {
            matrix3: Mat3A::from_cols(
                Vec3A::new(0.25712347, 0.5350714, -0.8047275),
                Vec3A::new(-0.8578408, 0.50980383, 0.06487957),
                Vec3A::new(0.4449684, 0.67364585, 0.5900885),
            ),
            translation: Vec3A::new(-1.8872253, 0.0, 2.624142),
        };
        let shape = ShapeTest::new(&ChangeShape { mesh: 0, poses: [Some(pose), None] }, &meshes).unwrap();
        let (origin, dir) =
            (Vec3::new(2.4152884, 0.47913298, -1.7501073), Vec3::new(-0.584266, 0.28131944, 0.76124406));
        assert!(shape.changes_for(&meshes, &Ray::segment(origin, dir, 0.0, 4.4345827), false));
    }
}
