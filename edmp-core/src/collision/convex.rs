//! Convex shapes given by their support function: the only thing GJK needs.
//!
//! A support function maps a direction `d` to a point of the shape that is farthest along `d`.
//! Every shape here is exact: a robot body is the convex hull of its collision-mesh vertices
//! (what PyBullet uses too), obstacles are true cuboids, spheres and cylinders, and the balls
//! and triangles of clouds and meshes.

use crate::robot::kinematics::Pose;
use crate::scene::{Obstacle, Shape};
use crate::surface::element::{Aabb, Element, Piece};
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
#[derive(Clone, Copy, Debug)]
pub struct Hull<'a> {
    /// Where the points' frame is.
    pub pose: &'a Pose<f32>,
    /// The points, in that frame.
    pub points: &'a [Vector3<f32>],
}

impl Convex for Hull<'_> {
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32> {
        let local = self.pose.rotation.tr_mul(d);
        let mut best = Vector3::zeros();
        let mut best_dot = f32::NEG_INFINITY;
        for p in self.points {
            let dot = p.dot(&local);
            if dot > best_dot {
                best_dot = dot;
                best = *p;
            }
        }
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

impl Convex for Element {
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32> {
        match &self.piece {
            Piece::Ball { center, radius } => {
                let n = crate::float::sqrt(d.norm_squared());
                if n > 0.0 { center + d * (radius / n) } else { *center }
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

#[cfg(test)]
mod tests {
    use super::*;

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
