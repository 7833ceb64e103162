//! A planning problem as plain numbers, for the wire (postcard) into firmware.
//!
//! [`Scene`] holds validated obstacles (rotation matrices); the wire carries what a scene file
//! says instead: each primitive's parameters and quaternion, the finger opening, the start, a joint goal (a pose
//! goal is resolved on the host: the firmware runs no IK) and the seed. [`Problem::to_scene`]
//! rebuilds the scene through the same [`Primitive::to_obstacle`] the host uses, so both sides
//! plan on the same bits. Only with the `serde` feature.

use crate::robot::kinematics::Joints;
use crate::scene::{MAX_OBSTACLES, Primitive, Scene, SceneError};
use serde::{Deserialize, Serialize};

/// One planning problem: obstacles (at most `N`), the held object, the finger opening, the
/// ends and the seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Problem<const N: usize = MAX_OBSTACLES> {
    /// The obstacles, in the scene file's order (the checker reports contacts by index).
    pub obstacles: heapless::Vec<Primitive, N>,
    /// An object held in the hand (pose in the `panda_hand` frame), if any.
    pub held: Option<Primitive>,
    /// Opening of each finger, metres (the scene file's `gripper.finger`; 0.025 when absent),
    /// validated by [`Scene::set_gripper`].
    pub finger: f32,
    /// Start configuration.
    pub start: Joints<f32>,
    /// Goal configuration.
    pub goal: Joints<f32>,
    /// Seed of the planner's [`crate::rng::Rng`].
    pub seed: u64,
}

impl<const N: usize> Problem<N> {
    /// The scene, every primitive validated on the way in.
    pub fn to_scene(&self) -> Result<Scene<'static, N>, SceneError> {
        let mut scene = Scene::new();
        for primitive in &self.obstacles {
            scene.push(primitive.to_obstacle()?)?;
        }
        if let Some(held) = &self.held {
            scene.hold(held.to_obstacle()?);
        }
        scene.set_gripper(self.finger)?;
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Obstacle;

    const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];

    fn problem() -> Problem<4> {
        let mut obstacles = heapless::Vec::new();
        for p in [
            Primitive::Cuboid {
                center: [0.5, 0.0, -0.01],
                dims: [1.2, 1.6, 0.02],
                quaternion: ID,
            },
            Primitive::Cylinder {
                center: [0.45, 0.45, 0.1],
                radius: 0.05,
                height: 0.2,
                quaternion: ID,
            },
            Primitive::Sphere {
                center: [0.35, -0.45, 0.6],
                radius: 0.06,
            },
        ] {
            obstacles.push(p).unwrap();
        }
        Problem {
            obstacles,
            held: None,
            finger: 0.025,
            start: [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785],
            goal: [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785],
            seed: 7,
        }
    }

    #[test]
    fn builds_the_scene_through_the_constructors() {
        let p = problem();
        let scene = p.to_scene().unwrap();
        assert_eq!(scene.obstacles().len(), 3);
        assert_eq!(
            scene.obstacles()[1],
            Obstacle::cylinder([0.45, 0.45, 0.1], 0.05, 0.2, ID).unwrap()
        );
        assert!(scene.held().is_none());
        assert_eq!(scene.gripper(), 0.025);
    }

    #[test]
    fn bad_primitives_are_typed_errors() {
        let mut p = problem();
        p.held = Some(Primitive::Sphere {
            center: [0.0; 3],
            radius: -1.0,
        });
        assert_eq!(p.to_scene().unwrap_err(), SceneError::NonPositiveSize);
        p.held = None;
        p.obstacles[0] = Primitive::Cuboid {
            center: [0.0; 3],
            dims: [1.0; 3],
            quaternion: [0.5, 0.0, 0.0, 0.0],
        };
        assert_eq!(p.to_scene().unwrap_err(), SceneError::QuaternionNorm);
    }

    #[test]
    fn carries_the_finger_opening() {
        let mut p = problem();
        p.finger = 0.04;
        assert_eq!(p.to_scene().unwrap().gripper(), 0.04);
        for (bad, e) in [
            (0.041, SceneError::FingerOutOfRange),
            (-0.01, SceneError::FingerOutOfRange),
            (f32::NAN, SceneError::NonFinite),
        ] {
            p.finger = bad;
            assert_eq!(p.to_scene().unwrap_err(), e, "{bad}");
        }
    }

    #[test]
    fn carries_the_held_object() {
        let mut p = problem();
        p.held = Some(p.obstacles[2]);
        let scene = p.to_scene().unwrap();
        assert_eq!(scene.held(), Some(&scene.obstacles()[2]));
    }
}
