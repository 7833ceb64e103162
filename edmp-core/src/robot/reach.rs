//! How far a joint step can move any point of a robot body, whatever the configuration: the
//! bound that lets the exact checker carry a certified clearance from one state to the next
//! instead of proving it again ([`crate::collision::checker`]).
//!
//! A point of a body turns about joint `j`'s axis at a distance of at most the lengths of the
//! frame offsets from joint `j`'s frame down to the body's frame plus the body's farthest hull
//! point from its own origin (rotations keep lengths). Along the straight joint-space line from
//! `q` to `q'` the point therefore moves at most `Σ_j |q'_j − q_j| · reach_j`: a body certified
//! `g` clear of a fixed obstacle at `q` is still more than `g − that` clear at `q'`.
//!
//! The tables are computed at compile time from each arm's generated tables
//! ([`crate::robot::arms`] stores them as [`Robot::body_reach`] and [`Robot::hand_reach`]);
//! square roots are rounded up, so every entry bounds the true length from above.

use crate::robot::{BodySpec, FrameSpec, Robot};
use nalgebra::Vector3;

/// Upper bound on how far any point of a shape with the per-joint `reach` moves for joint
/// steps `step` (`|q'_j − q_j|`).
pub fn motion<const J: usize>(reach: &[f32; J], step: &[f32; J]) -> f32 {
    let mut m = 0.0f32;
    for (r, d) in reach.iter().zip(step) {
        m += r * d;
    }
    m
}

/// `√x` rounded up (x ≥ 0), at compile time: Newton's iteration from above, then a relative
/// margin far above f32's rounding.
const fn sqrt_above(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    let mut y = if x > 1.0 { x } else { 1.0 };
    let mut i = 0;
    while i < 64 {
        y = 0.5 * (y + x / y);
        i += 1;
    }
    y * 1.000_01 + 1e-9
}

const fn norm_above(v: &Vector3<f32>) -> f32 {
    let [x, y, z] = v.data.0[0];
    sqrt_above(x * x + y * y + z * z)
}

/// The most a frame's origin can sit from its parent's: its offset, and a finger's slide at the
/// widest opening of the arm's gripper.
const fn offset_above<const J: usize>(robot: &Robot<f32, J>, spec: &FrameSpec<f32>) -> f32 {
    let slide = match (&spec.slide, &robot.gripper) {
        (Some(s), Some(g)) => {
            let w = if g.upper.abs() > g.lower.abs() {
                g.upper.abs()
            } else {
                g.lower.abs()
            };
            norm_above(s) * w
        }
        _ => 0.0,
    };
    norm_above(&spec.translation) + slide
}

/// Per joint: the reach of a point `local` metres from frame `frame`'s origin (metres; 0 where
/// the joint does not move the frame).
pub const fn frame_reach<const J: usize>(robot: &Robot<f32, J>, frame: usize, local: f32) -> [f32; J] {
    let mut reach = [0.0f32; J];
    let frames = robot.frames.len();
    if frames == 0 {
        return reach;
    }
    let mut d = local;
    let mut f = if frame < frames { frame } else { frames - 1 };
    let mut steps = 0;
    while steps < frames {
        let spec = &robot.frames[f];
        // Joint `j` turns frame `f` (and everything below it) about an axis through f's origin.
        if let Some(j) = spec.joint
            && j < J
        {
            reach[j] = d;
        }
        if f == 0 || spec.parent >= f {
            break;
        }
        d += offset_above(robot, spec);
        f = spec.parent;
        steps += 1;
    }
    reach
}

/// The farthest hull point of `body` from its frame's origin.
const fn hull_radius<const J: usize>(robot: &Robot<f32, J>, body: &BodySpec<f32>) -> f32 {
    let mut best = 0.0f32;
    let mut i = body.hull_start;
    while i < body.hull_start + body.hull_len && i < robot.hull_points.len() {
        let [x, y, z] = robot.hull_points[i].data.0[0];
        let r2 = x * x + y * y + z * z;
        if r2 > best {
            best = r2;
        }
        i += 1;
    }
    sqrt_above(best)
}

/// Per body (the first `B` of the arm's) and joint: how far any point of the body can be from
/// the joint's axis (metres; 0 where the joint does not move the body).
pub const fn body_reach<const J: usize, const B: usize>(robot: &Robot<f32, J>) -> [[f32; J]; B] {
    let mut table = [[0.0f32; J]; B];
    let mut b = 0;
    while b < B && b < robot.bodies.len() {
        let body = &robot.bodies[b];
        table[b] = frame_reach(robot, body.frame, hull_radius(robot, body));
        b += 1;
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::robot::kinematics::forward;
    use crate::robot::{HAND_FRAME, JOINTS, PANDA};

    #[test]
    fn no_hull_point_moves_farther_than_the_bound() {
        let mut rng = Rng::new(7);
        let mut worst = 0.0f32;
        for _ in 0..400 {
            let q: [f32; JOINTS] = core::array::from_fn(|j| rng.uniform_f32(PANDA.soft_lower[j], PANDA.soft_upper[j]));
            let scale = rng.uniform_f32(0.0, 0.3);
            let q2: [f32; JOINTS] = core::array::from_fn(|j| q[j] + scale * rng.uniform_f32(-1.0, 1.0));
            let (a, b) = (
                forward(&crate::robot::PANDA, &q).unwrap(),
                forward(&crate::robot::PANDA, &q2).unwrap(),
            );
            for (body, reach) in PANDA.body_reach.iter().enumerate() {
                let frame = PANDA.bodies[body].frame;
                let step: [f32; JOINTS] = core::array::from_fn(|j| (q2[j] - q[j]).abs());
                let bound = motion(reach, &step);
                for p in PANDA.hull(body) {
                    let moved = (a.frames[frame].transform_point(p) - b.frames[frame].transform_point(p)).norm();
                    assert!(moved <= bound + 1e-5, "body {body}: moved {moved} > bound {bound}");
                    if bound > 1e-3 {
                        worst = worst.max(moved / bound);
                    }
                }
            }
            let hand = (a.frames[HAND_FRAME].translation - b.frames[HAND_FRAME].translation).norm();
            let step: [f32; JOINTS] = core::array::from_fn(|j| (q2[j] - q[j]).abs());
            assert!(hand <= motion(&PANDA.hand_reach, &step) + 1e-5);
        }
        // Not so loose that it is useless: the hand's points use a good share of it.
        assert!(worst > 0.3, "the bound is {worst} of the motion at best");
    }

    #[test]
    fn the_base_does_not_move_and_the_hand_reaches_farthest() {
        let reach = PANDA.body_reach;
        assert_eq!(reach.len(), PANDA.bodies.len());
        assert!(reach[0].iter().all(|&r| r == 0.0));
        assert!(reach[1][1..].iter().all(|&r| r == 0.0) && reach[1][0] > 0.0);
        let hand = 8;
        assert!((0..JOINTS).all(|j| reach[hand][j] > 0.0));
        assert!(reach[hand][0] > 0.5 && reach[hand][0] < 1.5, "{:?}", reach[hand]);
    }
}
