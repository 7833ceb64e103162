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
//! The tables are computed at compile time from the generated robot tables; square roots are
//! rounded up, so every entry bounds the true length from above.

use crate::robot::PANDA_TABLES as TABLES;
use crate::robot::{
    BODIES, BodySpec, FINGER_OPENING_MAX, FINGER_OPENING_MIN, FRAMES, FrameSpec, HAND_FRAME, HULL_POINTS, JOINTS,
};
use nalgebra::Vector3;

/// Per body and joint: how far any point of the body can be from the joint's axis (metres;
/// 0 where the joint does not move the body).
pub const BODY_REACH: [[f32; JOINTS]; BODIES] = body_reach();

/// Per joint: how far the hand frame's origin can be from the joint's axis (metres). A held
/// object's points are at most this plus their distance from the hand's origin.
pub const HAND_REACH: [f32; JOINTS] = frame_reach(HAND_FRAME, 0.0);

/// Upper bound on how far any point of a shape with the per-joint `reach` moves for joint
/// steps `step` (`|q'_j − q_j|`).
pub fn motion(reach: &[f32; JOINTS], step: &[f32; JOINTS]) -> f32 {
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
/// widest opening.
const fn offset_above(spec: &FrameSpec<f32>) -> f32 {
    let slide = match &spec.slide {
        Some(s) => {
            let w = if FINGER_OPENING_MAX.abs() > FINGER_OPENING_MIN.abs() {
                FINGER_OPENING_MAX.abs()
            } else {
                FINGER_OPENING_MIN.abs()
            };
            norm_above(s) * w
        }
        None => 0.0,
    };
    norm_above(&spec.translation) + slide
}

/// Per joint: the reach of a point `local` metres from frame `frame`'s origin.
const fn frame_reach(frame: usize, local: f32) -> [f32; JOINTS] {
    let mut reach = [0.0f32; JOINTS];
    let mut d = local;
    let mut f = if frame < FRAMES { frame } else { FRAMES - 1 };
    let mut steps = 0;
    while steps < FRAMES {
        let spec = &TABLES.frames[f];
        // Joint `j` turns frame `f` (and everything below it) about an axis through f's origin.
        if let Some(j) = spec.joint
            && j < JOINTS
        {
            reach[j] = d;
        }
        if f == 0 || spec.parent >= f {
            break;
        }
        d += offset_above(spec);
        f = spec.parent;
        steps += 1;
    }
    reach
}

/// The farthest hull point of `body` from its frame's origin.
const fn hull_radius(body: &BodySpec<f32>) -> f32 {
    let mut best = 0.0f32;
    let mut i = body.hull_start;
    while i < body.hull_start + body.hull_len && i < HULL_POINTS {
        let [x, y, z] = TABLES.hull_points[i].data.0[0];
        let r2 = x * x + y * y + z * z;
        if r2 > best {
            best = r2;
        }
        i += 1;
    }
    sqrt_above(best)
}

const fn body_reach() -> [[f32; JOINTS]; BODIES] {
    let mut table = [[0.0f32; JOINTS]; BODIES];
    let mut b = 0;
    while b < BODIES {
        let body = &TABLES.bodies[b];
        table[b] = frame_reach(body.frame, hull_radius(body));
        b += 1;
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::robot::PANDA;
    use crate::robot::kinematics::forward;

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
            for (body, reach) in BODY_REACH.iter().enumerate() {
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
            assert!(hand <= motion(&HAND_REACH, &step) + 1e-5);
        }
        // Not so loose that it is useless: the hand's points use a good share of it.
        assert!(worst > 0.3, "the bound is {worst} of the motion at best");
    }

    #[test]
    fn the_base_does_not_move_and_the_hand_reaches_farthest() {
        assert!(BODY_REACH[0].iter().all(|&r| r == 0.0));
        assert!(BODY_REACH[1][1..].iter().all(|&r| r == 0.0) && BODY_REACH[1][0] > 0.0);
        let hand = 8;
        assert!((0..JOINTS).all(|j| BODY_REACH[hand][j] > 0.0));
        assert!(
            BODY_REACH[hand][0] > 0.5 && BODY_REACH[hand][0] < 1.5,
            "{:?}",
            BODY_REACH[hand]
        );
    }
}
