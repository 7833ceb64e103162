//! Convex shapes given by their support function: the only thing GJK needs.
//!
//! A support function maps a direction `d` to a point of the shape that is farthest along `d`.
//! Every shape here is exact: a robot body is the convex hull of its collision-mesh vertices
//! (what PyBullet uses too), obstacles are true cuboids, spheres and cylinders, and the balls
//! and triangles of clouds and meshes.

use crate::robot::kinematics::Pose;
use crate::robot::{HullGraph, Robot};
use crate::scene::{Obstacle, Shape};
use crate::surface::element::{Aabb, Element, Piece};
use core::cell::Cell;
use nalgebra::{Matrix3, Vector3};

/// A convex set known through its support function.
pub trait Convex {
    /// A point of the set maximising `⟨p, d⟩` (any point for `d = 0`).
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32>;

    /// World directions (columns) normal to the set's faces, if it has a few known ones. When
    /// a flat face meets another shape, the exact separating direction is that face's normal,
    /// which GJK on a large Minkowski difference reaches only to f32's precision.
    fn face_normals(&self) -> Option<Matrix3<f32>> {
        None
    }
}

/// The convex hull of points given in a frame placed at `pose`.
#[derive(Clone, Debug)]
pub struct Hull<'a> {
    /// Where the points' frame is.
    pub pose: &'a Pose<f32>,
    /// The points, in that frame.
    pub points: &'a [Vector3<f32>],
    /// The hull's edges, if known: the support climbs them instead of scanning every point.
    pub graph: Option<HullGraph<'a>>,
    /// Where the last climb ended: GJK asks for nearby directions in turn, so the next climb
    /// starts there and takes a step or two.
    pub last: Cell<Option<u16>>,
}

impl<'a> Hull<'a> {
    /// Robot body `body`'s hull, placed at `pose` (its link frame's pose).
    pub fn of_body<const J: usize>(robot: &'a Robot<f32, J>, body: usize, pose: &'a Pose<f32>) -> Self {
        Self {
            pose,
            points: robot.hull(body),
            graph: robot.hull_graph(body),
            last: Cell::new(None),
        }
    }

    /// The first of the points with the largest `⟨p, local⟩`, by a scan (the zero vector if
    /// there is none, or the direction is not finite).
    fn scan(&self, local: &Vector3<f32>) -> Vector3<f32> {
        let mut best = Vector3::zeros();
        let mut best_dot = f32::NEG_INFINITY;
        for p in self.points {
            let dot = p.dot(local);
            if dot > best_dot {
                best_dot = dot;
                best = *p;
            }
        }
        best
    }

    /// The point with the largest `⟨p, local⟩`, by climbing the hull's edges from where the
    /// last climb ended (the first: the seed farthest along `local`'s largest component) to a
    /// vertex whose every neighbour is lower.
    /// On a convex hull that vertex is the largest of all; `None` (scan instead) when a
    /// neighbour ties it (the scan's first-of-equals rule decides), the direction is not finite
    /// or the tables do not fit the points.
    fn climb(&self, graph: &HullGraph<'_>, local: &Vector3<f32>) -> Option<Vector3<f32>> {
        let [x, y, z] = [local.x, local.y, local.z];
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return None;
        }
        let start = match self.last.get() {
            Some(last) => last,
            None => {
                let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
                let seed = if ax >= ay && ax >= az {
                    usize::from(x < 0.0)
                } else if ay >= az {
                    2 + usize::from(y < 0.0)
                } else {
                    4 + usize::from(z < 0.0)
                };
                *graph.seeds.get(seed)?
            }
        };
        let mut at = usize::from(start);
        let mut at_dot = self.points.get(at)?.dot(local);
        // Every move is to a strictly larger value, so no vertex is visited twice.
        for _ in 0..self.points.len() {
            let (mut next, mut next_dot, mut tie) = (at, at_dot, false);
            for &n in graph.neighbours(at) {
                let dot = self.points.get(usize::from(n))?.dot(local);
                tie |= dot == at_dot;
                if dot > next_dot {
                    (next, next_dot) = (usize::from(n), dot);
                }
            }
            if next == at {
                if tie {
                    return None;
                }
                self.last.set(u16::try_from(at).ok());
                return self.points.get(at).copied();
            }
            (at, at_dot) = (next, next_dot);
        }
        None
    }
}

impl Convex for Hull<'_> {
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32> {
        let local = self.pose.rotation.tr_mul(d);
        let best = match &self.graph {
            Some(graph) => self.climb(graph, &local).unwrap_or_else(|| self.scan(&local)),
            None => self.scan(&local),
        };
        self.pose.transform_point(&best)
    }
}

/// A solid primitive placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solid {
    /// The geometry.
    pub shape: Shape,
    /// Orientation.
    pub rotation: Matrix3<f32>,
    /// Centre.
    pub center: Vector3<f32>,
}

impl Solid {
    /// An obstacle as it stands in the world.
    pub fn obstacle(o: &Obstacle) -> Self {
        Self {
            shape: o.shape,
            rotation: o.rotation,
            center: o.center,
        }
    }

    /// An object given in a frame (the held object in the hand), placed by that frame's pose.
    pub fn attached(o: &Obstacle, frame: &Pose<f32>) -> Self {
        Self {
            shape: o.shape,
            rotation: frame.rotation * o.rotation,
            center: frame.transform_point(&o.center),
        }
    }

    /// A box with half extents `half` at `pose` (a robot body's oriented box).
    pub fn cuboid(pose: &Pose<f32>, half: &Vector3<f32>) -> Self {
        Self {
            shape: Shape::Cuboid { dims: half * 2.0 },
            rotation: pose.rotation,
            center: pose.translation,
        }
    }

    /// An axis-aligned box (a subtree of a surface, proven clear at once).
    pub fn aabb(b: &Aabb) -> Self {
        Self {
            shape: Shape::Cuboid { dims: b.hi - b.lo },
            rotation: Matrix3::identity(),
            center: (b.lo + b.hi) * 0.5,
        }
    }

    /// Half extents of the box, in the solid's own frame, that holds it: a cuboid's own, a
    /// cylinder's bounding box, a sphere's cube.
    pub fn half_box(&self) -> Vector3<f32> {
        match self.shape {
            Shape::Cuboid { dims } => dims * 0.5,
            Shape::Cylinder { radius, height } => Vector3::new(radius, radius, 0.5 * height),
            Shape::Sphere { radius } => Vector3::new(radius, radius, radius),
        }
    }

    /// A lower bound on the distance between two solids: the separating-axis test of the
    /// boxes that hold them ([`Solid::half_box`]) along their six face normals, the largest
    /// gap between the boxes' projections. Negative when no face normal separates them. Cheaper
    /// than GJK by far, and tight for the thin panels of shelves and drawers, which a bounding
    /// ball holds loosely.
    pub fn face_gap(&self, other: &Solid) -> f32 {
        let (ha, hb) = (self.half_box(), other.half_box());
        // `other`'s axes and the centres' offset in this solid's frame.
        let c = self.rotation.tr_mul(&other.rotation);
        let d = self.rotation.tr_mul(&(other.center - self.center));
        let abs = c.abs();
        let across_a = abs * hb;
        let across_b = abs.tr_mul(&ha);
        let d_b = c.tr_mul(&d);
        let mut gap = f32::NEG_INFINITY;
        for i in 0..3 {
            gap = gap.max(d[i].abs() - ha[i] - across_a[i]);
            gap = gap.max(d_b[i].abs() - hb[i] - across_b[i]);
        }
        gap
    }

    /// Radius of a ball around `center` that holds the primitive.
    pub fn bounding_radius(&self) -> f32 {
        match self.shape {
            Shape::Cuboid { dims } => 0.5 * crate::float::sqrt(dims.norm_squared()),
            Shape::Cylinder { radius, height } => crate::float::sqrt(radius * radius + 0.25 * height * height),
            Shape::Sphere { radius } => radius,
        }
    }
}

fn sign(x: f32) -> f32 {
    if x < 0.0 { -1.0 } else { 1.0 }
}

impl Convex for Solid {
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32> {
        let local = self.rotation.tr_mul(d);
        let p = match self.shape {
            Shape::Cuboid { dims } => {
                Vector3::new(sign(local.x) * dims.x, sign(local.y) * dims.y, sign(local.z) * dims.z) * 0.5
            }
            Shape::Sphere { radius } => {
                let n = crate::float::sqrt(local.norm_squared());
                if n > 0.0 {
                    local * (radius / n)
                } else {
                    Vector3::new(radius, 0.0, 0.0)
                }
            }
            Shape::Cylinder { radius, height } => {
                let n = crate::float::sqrt(local.x * local.x + local.y * local.y);
                let (x, y) = if n > 0.0 {
                    (local.x * radius / n, local.y * radius / n)
                } else {
                    (radius, 0.0)
                };
                Vector3::new(x, y, sign(local.z) * 0.5 * height)
            }
        };
        self.rotation * p + self.center
    }

    fn face_normals(&self) -> Option<Matrix3<f32>> {
        match self.shape {
            // A cylinder's caps are normal to its z; its other columns are merely valid axes.
            Shape::Cuboid { .. } | Shape::Cylinder { .. } => Some(self.rotation),
            Shape::Sphere { .. } => None,
        }
    }
}

impl Element {
    /// [`Convex::support`] along `d` with `norm` = `|d|` (what a ball needs) found by the
    /// caller: one that asks many pieces along the same `d` finds it once.
    #[inline]
    pub(crate) fn support_with_norm(&self, d: &Vector3<f32>, norm: f32) -> Vector3<f32> {
        match &self.piece {
            Piece::Ball { center, radius } => {
                if norm > 0.0 {
                    center + d * (radius / norm)
                } else {
                    *center
                }
            }
            Piece::Triangle { corners } => {
                let mut best = corners[0];
                let mut best_dot = best.dot(d);
                for c in &corners[1..] {
                    let dot = c.dot(d);
                    if dot > best_dot {
                        best_dot = dot;
                        best = *c;
                    }
                }
                best
            }
        }
    }
}

impl Convex for Element {
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32> {
        // Only a ball needs `|d|`.
        let norm = match self.piece {
            Piece::Ball { .. } => crate::float::sqrt(d.norm_squared()),
            Piece::Triangle { .. } => 0.0,
        };
        self.support_with_norm(d, norm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::gjk::closest;
    use crate::rng::Rng;

    /// A random solid within a metre of the origin: a box, a cylinder or a sphere, turned
    /// anyhow, some of them thin panels.
    fn random_solid(rng: &mut Rng) -> Solid {
        let center = [0; 3].map(|_| rng.uniform_f32(-0.6, 0.6));
        let q = [0; 4].map(|_| rng.uniform_f32(-1.0, 1.0));
        let n = crate::float::sqrt(q.iter().map(|x| x * x).sum::<f32>()).max(1e-3);
        let q = q.map(|x| x / n);
        let size = |rng: &mut Rng| rng.uniform_f32(0.005, 0.5);
        let o = match rng.below(3) {
            0 => Obstacle::cuboid(center, [size(rng), size(rng), size(rng)], q),
            1 => Obstacle::cylinder(center, size(rng), size(rng), q),
            _ => Obstacle::sphere(center, size(rng)),
        };
        Solid::obstacle(&o.unwrap())
    }

    #[test]
    fn face_gap_never_exceeds_the_distance() {
        let mut rng = Rng::new(7);
        let (mut apart, mut proven) = (0, 0);
        for _ in 0..20_000 {
            let (a, b) = (random_solid(&mut rng), random_solid(&mut rng));
            let gap = a.face_gap(&b);
            // GJK's vector bounds the distance from above; `None`: they overlap.
            let upper = closest(&a, &b, &(a.center - b.center)).map_or(0.0, |v| crate::float::sqrt(v.norm_squared()));
            assert!(gap <= upper + 1e-5, "{a:?} {b:?}: {gap} > {upper}");
            apart += u32::from(upper > 0.01);
            proven += u32::from(gap > 0.01);
        }
        // Not a bound that proves nothing: most pairs apart by a centimetre are proven so.
        assert!(proven * 2 > apart, "{proven} of {apart}");
    }

    #[test]
    fn face_gap_of_boxes_side_by_side_is_their_distance() {
        let id = [1.0, 0.0, 0.0, 0.0];
        let a = Solid::obstacle(&Obstacle::cuboid([0.0, 0.0, 0.0], [0.2, 0.4, 0.6], id).unwrap());
        let b = Solid::obstacle(&Obstacle::cuboid([0.5, 0.1, -0.2], [0.4, 0.02, 0.02], id).unwrap());
        assert!((a.face_gap(&b) - 0.2).abs() < 1e-6, "{}", a.face_gap(&b));
        // A thin panel turned 45° about z, 5 cm beyond the box's corner along the diagonal: its
        // face normal proves the gap a bounding ball cannot.
        let h = core::f32::consts::FRAC_1_SQRT_2;
        let q = [
            libm::cosf(core::f32::consts::FRAC_PI_8),
            0.0,
            0.0,
            libm::sinf(core::f32::consts::FRAC_PI_8),
        ];
        let corner = (0.1 + 0.2) * h + 0.05 + 0.005;
        let p = Solid::obstacle(&Obstacle::cuboid([corner * h, corner * h, 0.0], [0.01, 1.0, 1.0], q).unwrap());
        let a = Solid::obstacle(&Obstacle::cuboid([0.0; 3], [0.2, 0.4, 0.6], id).unwrap());
        assert!((a.face_gap(&p) - 0.05).abs() < 1e-5, "{}", a.face_gap(&p));
        assert!(a.face_gap(&a) < 0.0);
    }

    /// Every body of `robot`: climbing its hull's edges (each climb from where the last ended,
    /// as in GJK) gives the scan's point, bit for bit, for the zero direction, the axes and
    /// 3,000 random directions, a fifth of them rounded to a coarse grid, where vertices tie.
    fn climbs_end_where_scans_do<const J: usize>(robot: &Robot<f32, J>) {
        let pose = Pose::identity();
        let mut rng = Rng::new(7);
        let (mut climbs, mut scans) = (0, 0);
        for b in 0..robot.bodies.len() {
            let hull = Hull::of_body(robot, b, &pose);
            assert!(hull.graph.is_some(), "{} body {b} has no hull graph", robot.name);
            let scan = Hull {
                graph: None,
                ..hull.clone()
            };
            let mut directions = std::vec![Vector3::zeros()];
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    directions.push(Vector3::ith(axis, sign));
                }
            }
            for _ in 0..3000 {
                let d = Vector3::new(rng.normal_f32(), rng.normal_f32(), rng.normal_f32());
                // Every fifth direction rounded to a coarse grid: ties between hull vertices.
                directions.push(if directions.len() % 5 == 0 {
                    d.map(|x| (x * 2.0).round())
                } else {
                    d
                });
            }
            for d in &directions {
                let (got, want) = (hull.support(d), scan.support(d));
                assert_eq!(got, want, "{} body {b}, direction {d:?}", robot.name);
                if hull.climb(hull.graph.as_ref().unwrap(), d).is_some() {
                    climbs += 1;
                } else {
                    scans += 1;
                }
            }
        }
        // Most queries climb; some tie and scan.
        assert!(climbs > 10 * scans && scans > 0, "{climbs} climbs, {scans} scans");
    }

    #[test]
    #[cfg(feature = "panda")]
    fn panda_hull_climbs_end_where_scans_do() {
        climbs_end_where_scans_do(&crate::robot::arms::panda::ROBOT);
    }

    #[test]
    #[cfg(feature = "iiwa7")]
    fn iiwa7_hull_climbs_end_where_scans_do() {
        climbs_end_where_scans_do(&crate::robot::arms::iiwa7::ROBOT);
    }

    #[test]
    #[cfg(feature = "xarm6")]
    fn xarm6_hull_climbs_end_where_scans_do() {
        climbs_end_where_scans_do(&crate::robot::arms::xarm6::ROBOT);
    }

    #[test]
    fn primitive_supports_are_extreme_points() {
        let id = [1.0, 0.0, 0.0, 0.0];
        let b = Solid::obstacle(&Obstacle::cuboid([1.0, 0.0, 0.0], [0.2, 0.4, 0.6], id).unwrap());
        assert_eq!(b.support(&Vector3::new(1.0, -1.0, 0.5)), Vector3::new(1.1, -0.2, 0.3));
        let s = Solid::obstacle(&Obstacle::sphere([0.0, 1.0, 0.0], 0.5).unwrap());
        assert!((s.support(&Vector3::new(0.0, 0.0, -3.0)) - Vector3::new(0.0, 1.0, -0.5)).norm() < 1e-7);
        let c = Solid::obstacle(&Obstacle::cylinder([0.0; 3], 0.1, 0.4, id).unwrap());
        assert!((c.support(&Vector3::new(3.0, 4.0, 1.0)) - Vector3::new(0.06, 0.08, 0.2)).norm() < 1e-6);
        let t = Element::triangle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], 0)
            .unwrap()
            .unwrap();
        assert_eq!(t.support(&Vector3::new(1.0, 0.1, 0.0)), Vector3::new(1.0, 0.0, 0.0));
        let ball = Element::ball([1.0, 0.0, 0.0], 0.5, 0).unwrap();
        assert!((ball.support(&Vector3::new(0.0, 0.0, 2.0)) - Vector3::new(1.0, 0.0, 0.5)).norm() < 1e-7);
    }
}
