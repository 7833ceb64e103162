//! The robot's own points taken out of a cloud: a camera that sees the cell sees the arm too,
//! and those points would put every start in collision.

use crate::collision::convex::{Convex, Hull};
use crate::collision::gjk::distance_lower_bound;
use crate::error::Error;
use crate::robot::kinematics::forward_with;
use crate::robot::{MAX_BODIES, MAX_FRAMES, Robot};
use nalgebra::Vector3;

/// A point, as a convex set.
struct Point(Vector3<f32>);

impl Convex for Point {
    fn support(&self, _: &Vector3<f32>) -> Vector3<f32> {
        self.0
    }
}

/// Drops the points within `distance` of the arm's collision bodies (its base included) at
/// configuration `q` with the fingers at `finger` (the scene's opening; ignored by an arm
/// without fingers); the kept points move to the front. Returns how many were kept.
pub fn filter_robot<const J: usize>(
    robot: &'static Robot<f32, J>,
    points: &mut [[f32; 3]],
    q: &[f32; J],
    finger: f32,
    distance: f32,
) -> Result<usize, Error> {
    if !(distance.is_finite() && distance >= 0.0) {
        return Err(Error::BadParameter);
    }
    let k = forward_with(robot, q, robot.finger_opening(finger))?;
    let count = robot.bodies.len().min(MAX_BODIES);
    // Each body's bounding ball: centre and radius.
    let balls: [(Vector3<f32>, f32); MAX_BODIES] = core::array::from_fn(|b| match robot.bodies.get(b) {
        Some(body) => (
            k.boxes[b].translation,
            crate::float::sqrt(body.half_extents.norm_squared()),
        ),
        None => (Vector3::zeros(), 0.0),
    });
    let bodies = &balls[..count];
    let mut kept = 0;
    for i in 0..points.len() {
        let Some(&p) = points.get(i) else { break };
        let v = Vector3::from(p);
        let own = bodies.iter().enumerate().any(|(b, (c, r))| {
            if (v - c).norm_squared() > (r + distance) * (r + distance) {
                return false;
            }
            let hull = Hull::of_body(robot, b, &k.frames[robot.bodies[b].frame.min(MAX_FRAMES - 1)]);
            distance_lower_bound(&hull, &Point(v)) <= distance
        });
        if !own {
            if let Some(slot) = points.get_mut(kept) {
                *slot = p;
            }
            kept += 1;
        }
    }
    Ok(kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robots_own_points_are_dropped() {
        let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        let k = forward_with(&crate::robot::PANDA, &ready, 0.025).unwrap();
        let tcp = k.tcp().translation;
        // One point at the hand's origin (on the robot), one 1 m away.
        let hand = k.frames[crate::robot::HAND_FRAME].translation;
        let mut points = [[hand.x, hand.y, hand.z], [tcp.x + 1.0, tcp.y, tcp.z]];
        assert_eq!(
            filter_robot(&crate::robot::PANDA, &mut points, &ready, 0.025, 0.01).unwrap(),
            1
        );
        assert_eq!(points[0], [tcp.x + 1.0, tcp.y, tcp.z]);
        assert!(filter_robot(&crate::robot::PANDA, &mut points, &ready, 0.025, f32::NAN).is_err());
    }
}
