//! The planning scene: obstacles (cuboids, cylinders, spheres) in a fixed-capacity list, an
//! optional object held in the hand, and the gripper's opening (`gripper.finger`, both fingers
//! at it for the whole plan: the costs, the checker and IK's check all read it). Everything is validated on the way in, so the costs and
//! the checker never see a NaN, a zero size or a non-rotation.

use crate::robot::{FINGER_OPENING_DEFAULT, FINGER_OPENING_MAX, FINGER_OPENING_MIN};
use crate::surface::Surface;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Default obstacle capacity of a [`Scene`].
pub const MAX_OBSTACLES: usize = 64;

/// How far a quaternion's norm may be from 1 (docs/formats.md); within it, it is normalised.
pub const QUATERNION_NORM_TOLERANCE: f32 = 1e-3;

/// The geometry of a primitive, in its own frame (centred at the origin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A box with full extents `dims` along its x, y, z.
    Cuboid {
        /// Full extents.
        dims: Vector3<f32>,
    },
    /// A cylinder along its local z.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Full length along z.
        height: f32,
    },
    /// A ball.
    Sphere {
        /// Radius.
        radius: f32,
    },
}

/// A primitive placed in a frame: the world for obstacles, the hand for a held object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obstacle {
    /// The geometry.
    pub shape: Shape,
    /// Centre.
    pub center: Vector3<f32>,
    /// Orientation (columns are the primitive's axes).
    pub rotation: Matrix3<f32>,
}

/// An obstacle as its parameters, as a scene file, a generator or the wire to firmware gives
/// them (quaternions `[w, x, y, z]`, as in `edmp-scene/1`); [`Primitive::to_obstacle`]
/// validates it into an [`Obstacle`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Primitive {
    /// A box with full extents `dims`.
    Cuboid {
        /// Centre.
        center: [f32; 3],
        /// Full extents along the box's x, y, z.
        dims: [f32; 3],
        /// Orientation.
        quaternion: [f32; 4],
    },
    /// A cylinder along its local z.
    Cylinder {
        /// Centre.
        center: [f32; 3],
        /// Radius.
        radius: f32,
        /// Full length along z.
        height: f32,
        /// Orientation.
        quaternion: [f32; 4],
    },
    /// A ball.
    Sphere {
        /// Centre.
        center: [f32; 3],
        /// Radius.
        radius: f32,
    },
}

impl Primitive {
    /// The validated obstacle ([`Obstacle::cuboid`], [`Obstacle::cylinder`], [`Obstacle::sphere`]).
    pub fn to_obstacle(&self) -> Result<Obstacle, SceneError> {
        match *self {
            Self::Cuboid {
                center,
                dims,
                quaternion,
            } => Obstacle::cuboid(center, dims, quaternion),
            Self::Cylinder {
                center,
                radius,
                height,
                quaternion,
            } => Obstacle::cylinder(center, radius, height, quaternion),
            Self::Sphere { center, radius } => Obstacle::sphere(center, radius),
        }
    }
}

/// Why an obstacle or a scene was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SceneError {
    /// A centre, size or quaternion component is NaN or infinite.
    NonFinite,
    /// The quaternion's norm is not within [`QUATERNION_NORM_TOLERANCE`] of 1.
    QuaternionNorm,
    /// A size (extent, radius, height) is zero or negative.
    NonPositiveSize,
    /// The scene already holds its capacity of obstacles.
    TooManyObstacles,
    /// The finger opening is outside the URDF's finger limits, 0 to 0.04 m
    /// (`robot::FINGER_OPENING_MIN`, `robot::FINGER_OPENING_MAX`).
    FingerOutOfRange,
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "value is not a finite number",
            Self::QuaternionNorm => "quaternion norm is not within 1e-3 of 1",
            Self::NonPositiveSize => "size must be positive",
            Self::TooManyObstacles => "too many obstacles for the scene's capacity",
            Self::FingerOutOfRange => "finger opening outside [0, 0.04] m",
        })
    }
}

impl core::error::Error for SceneError {}

fn finite(values: &[f32]) -> Result<(), SceneError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::NonFinite)
    }
}

fn positive(values: &[f32]) -> Result<(), SceneError> {
    finite(values)?;
    if values.iter().all(|&v| v > 0.0) {
        Ok(())
    } else {
        Err(SceneError::NonPositiveSize)
    }
}

/// A quaternion `[w, x, y, z]` whose norm is within tolerance of 1, as a rotation matrix.
pub fn rotation_from_wxyz(q: [f32; 4]) -> Result<Matrix3<f32>, SceneError> {
    finite(&q)?;
    let norm = crate::float::sqrt(q.iter().map(|v| v * v).sum::<f32>());
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(SceneError::QuaternionNorm);
    }
    let unit = UnitQuaternion::new_unchecked(Quaternion::new(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm));
    Ok(unit.to_rotation_matrix().into_inner())
}

impl Obstacle {
    /// A unit ball at the origin: fills fixed arrays before they are written
    /// (e.g. the output of [`crate::cost::cover::covers`]).
    pub const PLACEHOLDER: Self = Self {
        shape: Shape::Sphere { radius: 1.0 },
        center: Vector3::new(0.0, 0.0, 0.0),
        rotation: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    };

    /// A cuboid with full extents `dims`, rotated by the quaternion `[w, x, y, z]`.
    pub fn cuboid(center: [f32; 3], dims: [f32; 3], quaternion: [f32; 4]) -> Result<Self, SceneError> {
        finite(&center)?;
        positive(&dims)?;
        let rotation = rotation_from_wxyz(quaternion)?;
        Ok(Self {
            shape: Shape::Cuboid { dims: dims.into() },
            center: center.into(),
            rotation,
        })
    }

    /// A cylinder along its local z, rotated by the quaternion `[w, x, y, z]`.
    pub fn cylinder(center: [f32; 3], radius: f32, height: f32, quaternion: [f32; 4]) -> Result<Self, SceneError> {
        finite(&center)?;
        positive(&[radius, height])?;
        let rotation = rotation_from_wxyz(quaternion)?;
        Ok(Self {
            shape: Shape::Cylinder { radius, height },
            center: center.into(),
            rotation,
        })
    }

    /// A sphere.
    pub fn sphere(center: [f32; 3], radius: f32) -> Result<Self, SceneError> {
        finite(&center)?;
        positive(&[radius])?;
        Ok(Self {
            shape: Shape::Sphere { radius },
            center: center.into(),
            rotation: Matrix3::identity(),
        })
    }
}

/// Obstacles (at most `N`), the pieces of clouds and meshes ([`Surface`], borrowed from the
/// caller's buffers, with a few boxes around them for the guides among the `N`), an optional
/// object held in the hand (pose in the `panda_hand` frame) and the opening of each finger
/// (default `robot::FINGER_OPENING_DEFAULT`, 0.025 m).
#[derive(Clone, Debug)]
pub struct Scene<'a, const N: usize = MAX_OBSTACLES> {
    /// The primitives first (`primitives` of them), then the surface's boxes for the guides.
    obstacles: heapless::Vec<Obstacle, N>,
    primitives: usize,
    surface: Surface<'a>,
    held: Option<Obstacle>,
    finger: f32,
}

impl<const N: usize> Default for Scene<'_, N> {
    fn default() -> Self {
        Self::new()
    }
}

/// A finger opening, validated: finite and within the URDF's finger limits.
pub fn finger_opening(finger: f32) -> Result<f32, SceneError> {
    finite(&[finger])?;
    if (FINGER_OPENING_MIN..=FINGER_OPENING_MAX).contains(&finger) {
        Ok(finger)
    } else {
        Err(SceneError::FingerOutOfRange)
    }
}

impl<'a, const N: usize> Scene<'a, N> {
    /// An empty scene, the fingers at the default opening.
    pub const fn new() -> Self {
        Self {
            obstacles: heapless::Vec::new(),
            primitives: 0,
            surface: Surface::EMPTY,
            held: None,
            finger: FINGER_OPENING_DEFAULT,
        }
    }

    /// This scene with each finger opened to `finger` metres (the scene file's
    /// `gripper.finger`): NaN or infinity is [`SceneError::NonFinite`], outside 0..=0.04 m
    /// [`SceneError::FingerOutOfRange`].
    pub fn with_gripper(mut self, finger: f32) -> Result<Self, SceneError> {
        self.set_gripper(finger)?;
        Ok(self)
    }

    /// Sets the opening of each finger (see [`Self::with_gripper`]); on error the scene keeps
    /// its opening.
    pub fn set_gripper(&mut self, finger: f32) -> Result<(), SceneError> {
        self.finger = finger_opening(finger)?;
        Ok(())
    }

    /// The opening of each finger, metres (validated: within 0..=0.04).
    pub fn gripper(&self) -> f32 {
        self.finger
    }

    /// Adds an obstacle (already validated by its constructor), before any surface boxes.
    pub fn push(&mut self, obstacle: Obstacle) -> Result<(), SceneError> {
        self.obstacles
            .push(obstacle)
            .map_err(|_| SceneError::TooManyObstacles)?;
        // Moved down past the surface's boxes, one swap at a time (no panicking insert).
        let mut i = self.obstacles.len().saturating_sub(1);
        while i > self.primitives {
            if let Some([a, b]) = self.obstacles.get_mut(i - 1..i + 1) {
                core::mem::swap(a, b);
            }
            i -= 1;
        }
        self.primitives += 1;
        Ok(())
    }

    /// This scene with `surface`'s pieces as obstacles: the checker takes them exactly, the
    /// guides take `boxes` around them ([`crate::cost::cover::covers`]), as many as the scene's capacity
    /// leaves room for. Any earlier surface and its boxes are replaced.
    pub fn with_surface<'b>(self, surface: Surface<'b>, boxes: &[Obstacle]) -> Scene<'b, N> {
        let mut obstacles = self.obstacles;
        obstacles.truncate(self.primitives);
        for b in boxes {
            if obstacles.push(*b).is_err() {
                break;
            }
        }
        Scene {
            obstacles,
            primitives: self.primitives,
            surface,
            held: self.held,
            finger: self.finger,
        }
    }

    /// Attaches `object` to the hand (its pose is in the `panda_hand` frame), replacing any other.
    pub fn hold(&mut self, object: Obstacle) {
        self.held = Some(object);
    }

    /// The primitive obstacles: what the checker tests besides the surface.
    pub fn obstacles(&self) -> &[Obstacle] {
        self.obstacles.get(..self.primitives).unwrap_or(&[])
    }

    /// What the guides' costs see: the primitives and the boxes around the surface.
    pub fn guide_obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The pieces of the scene's clouds and meshes.
    pub fn surface(&self) -> &Surface<'a> {
        &self.surface
    }

    /// The held object, if any.
    pub fn held(&self) -> Option<&Obstacle> {
        self.held.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];

    #[test]
    fn validates_each_field() {
        assert!(Obstacle::cuboid([0.5, 0.0, 0.2], [0.4, 0.8, 0.02], ID).is_ok());
        assert_eq!(
            Obstacle::cuboid([f32::NAN, 0.0, 0.0], [1.0; 3], ID),
            Err(SceneError::NonFinite)
        );
        assert_eq!(
            Obstacle::cuboid([0.0; 3], [1.0, 0.0, 1.0], ID),
            Err(SceneError::NonPositiveSize)
        );
        assert_eq!(
            Obstacle::cuboid([0.0; 3], [1.0; 3], [0.7, 0.0, 0.0, 0.0]),
            Err(SceneError::QuaternionNorm)
        );
        assert_eq!(
            Obstacle::cylinder([0.0; 3], -0.1, 0.2, ID),
            Err(SceneError::NonPositiveSize)
        );
        assert_eq!(Obstacle::sphere([0.0; 3], f32::INFINITY), Err(SceneError::NonFinite));
    }

    #[test]
    fn near_unit_quaternions_are_normalised() {
        let o = Obstacle::cuboid([0.0; 3], [1.0; 3], [1.0005, 0.0, 0.0, 0.0]).unwrap();
        assert!((o.rotation - Matrix3::identity()).norm() < 1e-6);
        // 90° about z: x goes to y.
        let h = core::f32::consts::FRAC_1_SQRT_2;
        let o = Obstacle::cuboid([0.0; 3], [1.0; 3], [h, 0.0, 0.0, h]).unwrap();
        let x = o.rotation * Vector3::x();
        assert!((x - Vector3::y()).norm() < 1e-6);
    }

    #[test]
    fn the_gripper_opening_is_validated() {
        let s = Scene::<2>::new();
        assert_eq!(s.gripper(), 0.025);
        assert_eq!(Scene::<2>::default().gripper(), 0.025);
        assert_eq!(s.clone().with_gripper(0.04).map(|s| s.gripper()), Ok(0.04));
        assert_eq!(s.clone().with_gripper(0.0).map(|s| s.gripper()), Ok(0.0));
        assert_eq!(s.clone().with_gripper(f32::NAN).unwrap_err(), SceneError::NonFinite);
        assert_eq!(
            s.clone().with_gripper(f32::INFINITY).unwrap_err(),
            SceneError::NonFinite
        );
        assert_eq!(
            s.clone().with_gripper(-0.001).unwrap_err(),
            SceneError::FingerOutOfRange
        );
        assert_eq!(
            s.clone().with_gripper(0.0401).unwrap_err(),
            SceneError::FingerOutOfRange
        );
        let mut t = s.with_gripper(0.01).unwrap();
        assert_eq!(t.set_gripper(0.05), Err(SceneError::FingerOutOfRange));
        assert_eq!(t.gripper(), 0.01);
    }

    #[test]
    fn capacity_is_a_typed_error() {
        let mut s = Scene::<2>::new();
        let o = Obstacle::sphere([0.0; 3], 0.1).unwrap();
        assert!(s.push(o).is_ok() && s.push(o).is_ok());
        assert_eq!(s.push(o), Err(SceneError::TooManyObstacles));
        assert_eq!(s.obstacles().len(), 2);
    }
}
