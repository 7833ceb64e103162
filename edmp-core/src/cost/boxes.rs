//! Axis-aligned boxes and the world boxes of obstacles, as EDMP's costs use them.

use crate::scene::{Obstacle, Shape};
use nalgebra::Vector3;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vector3<f32>,
    /// Upper corner.
    pub max: Vector3<f32>,
}

impl Aabb {
    /// The smallest box holding both.
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    pub fn union(&self, other: &Self) -> Self {
        Self {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }

    /// Overlap length along each axis (zero where the boxes are apart).
    pub fn overlap(&self, other: &Self) -> Vector3<f32> {
        (self.max.inf(&other.max) - self.min.sup(&other.min)).map(|d| d.max(0.0))
    }

    /// Volume of the intersection.
    pub fn intersection_volume(&self, other: &Self) -> f32 {
        let o = self.overlap(other);
        o.x * o.y * o.z
    }
}

/// How a cylinder is boxed for the costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CylinderBox {
    /// The enclosing box, full extents (2r, 2r, h).
    #[default]
    Enclosing,
    /// The original EDMP code's (r, r, h), which under-covers the cylinder; kept only to
    /// reproduce the original for comparison.
    OriginalEdmp,
}

/// The frame in which each obstacle and robot box pair is boxed for the costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BoxFrame {
    /// The obstacle's own frame: its box is exact there, and the robot's box is boxed along
    /// the obstacle's axes. A thin board keeps its thickness whatever its yaw.
    #[default]
    Obstacle,
    /// The world axes, as the original EDMP code: every obstacle becomes its world AABB, so a
    /// 1.3 m shelf board yawed by 6° is costed as 15 cm thick.
    World,
}

/// Growth of obstacles for a guide at one diffusion step (metres, full extents).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Inflation {
    /// Added to every full extent (`c(t)`; `c/2` per side).
    pub clearance: f32,
    /// Every full extent is raised to at least this (`e(t)`).
    pub expansion: f32,
}

/// Full extents of the box EDMP puts around a primitive, before inflation.
pub fn box_dims(shape: &Shape, cylinder: CylinderBox) -> Vector3<f32> {
    match *shape {
        Shape::Cuboid { dims } => dims,
        Shape::Cylinder { radius, height } => match cylinder {
            CylinderBox::Enclosing => Vector3::new(2.0 * radius, 2.0 * radius, height),
            CylinderBox::OriginalEdmp => Vector3::new(radius, radius, height),
        },
        Shape::Sphere { radius } => Vector3::repeat(2.0 * radius),
    }
}

/// Full extents of an obstacle's box after inflation: `max(dims, e) + c`.
pub fn inflated_dims(obstacle: &Obstacle, inflation: &Inflation, cylinder: CylinderBox) -> Vector3<f32> {
    box_dims(&obstacle.shape, cylinder).map(|d| d.max(inflation.expansion) + inflation.clearance)
}

/// World AABB of an obstacle's box after inflation ([`inflated_dims`]), rotated, then boxed
/// (the 8-corner AABB, computed exactly as `|R| · dims_eff / 2`).
pub fn obstacle_aabb(obstacle: &Obstacle, inflation: &Inflation, cylinder: CylinderBox) -> Aabb {
    let dims = inflated_dims(obstacle, inflation, cylinder);
    let half = obstacle.rotation.abs() * dims * 0.5;
    Aabb {
        min: obstacle.center - half,
        max: obstacle.center + half,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_boxes_intersect_in_their_volume() {
        let a = Aabb {
            min: Vector3::new(0.0, 1.0, 2.0),
            max: Vector3::new(0.5, 1.25, 2.125),
        };
        assert_eq!(a.intersection_volume(&a), 0.5 * 0.25 * 0.125);
        let b = Aabb {
            min: a.max,
            max: a.max + Vector3::repeat(1.0),
        };
        assert_eq!(a.intersection_volume(&b), 0.0);
    }

    #[test]
    fn inflation_follows_edmp() {
        let o = Obstacle::cuboid([0.0; 3], [0.1, 0.5, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap();
        let b = obstacle_aabb(
            &o,
            &Inflation {
                clearance: 0.02,
                expansion: 0.4,
            },
            CylinderBox::Enclosing,
        );
        let full = b.max - b.min;
        assert!((full - Vector3::new(0.42, 0.52, 0.42)).norm() < 1e-6, "{full}");
        let c = Obstacle::cylinder([0.0; 3], 0.1, 0.3, [1.0, 0.0, 0.0, 0.0]).unwrap();
        let enclosing = obstacle_aabb(&c, &Inflation::default(), CylinderBox::Enclosing);
        let original = obstacle_aabb(&c, &Inflation::default(), CylinderBox::OriginalEdmp);
        assert!(((enclosing.max - enclosing.min).x - 0.2).abs() < 1e-7);
        assert!(((original.max - original.min).x - 0.1).abs() < 1e-7);
    }
}
