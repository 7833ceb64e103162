//! A cloud made small enough to hold, and the robot's own points taken out of it.
//!
//! [`reduce`] keeps every point while they fit; beyond the capacity it replaces the points of
//! each cell of a grid by one ball at the cell's centre, grown by the cell's half diagonal, so
//! the reduced balls still cover every input ball (conservative, never truncated).
//! [`filter_robot`] drops the points a camera saw on the arm itself.

use crate::collision::convex::{Convex, Hull};
use crate::collision::gjk::distance_lower_bound;
use crate::error::Error;
use crate::robot::kinematics::{Joints, forward_with};
use crate::robot::{BODIES, FRAMES, PANDA};
use crate::surface::element::SurfaceError;
use nalgebra::Vector3;

/// How a cloud was held: the points kept and the radius of their balls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reduced {
    /// Points now at the front of the buffer.
    pub points: usize,
    /// The ball radius that covers the input (the input's when nothing was reduced).
    pub radius: f32,
    /// The grid cell used (0 when nothing was reduced).
    pub cell: f32,
}

/// Grid cells tried before giving up: the cell doubles each time from the ball radius.
const ATTEMPTS: u32 = 24;

fn cell_key(p: &[f32; 3], cell: f32) -> [i64; 3] {
    p.map(|x| libm::floorf(x / cell) as i64)
}

/// Brings `points` down to at most `capacity` balls covering the input balls of `radius`;
/// the kept points are moved to the front. Refuses non-finite input.
pub fn reduce(points: &mut [[f32; 3]], radius: f32, capacity: usize) -> Result<Reduced, SurfaceError> {
    if !(radius.is_finite()) {
        return Err(SurfaceError::NonFinite);
    }
    if radius <= 0.0 {
        return Err(SurfaceError::NonPositiveRadius);
    }
    if points.iter().flatten().any(|x| !x.is_finite()) {
        return Err(SurfaceError::NonFinite);
    }
    if points.len() <= capacity {
        return Ok(Reduced {
            points: points.len(),
            radius,
            cell: 0.0,
        });
    }
    if capacity == 0 {
        return Err(SurfaceError::TooManyPieces);
    }
    let mut cell = radius;
    for _ in 0..ATTEMPTS {
        points.sort_unstable_by(|a, b| {
            cell_key(a, cell)
                .cmp(&cell_key(b, cell))
                .then(a.map(f32::to_bits).cmp(&b.map(f32::to_bits)))
        });
        let mut cells = 0usize;
        let mut last: Option<[i64; 3]> = None;
        for p in points.iter() {
            let k = cell_key(p, cell);
            if last != Some(k) {
                cells += 1;
                last = Some(k);
            }
        }
        if cells <= capacity {
            let mut kept = 0usize;
            let mut last: Option<[i64; 3]> = None;
            for i in 0..points.len() {
                let Some(&p) = points.get(i) else { break };
                let k = cell_key(&p, cell);
                if last != Some(k) {
                    last = Some(k);
                    if let Some(slot) = points.get_mut(kept) {
                        *slot = k.map(|c| (c as f32 + 0.5) * cell);
                    }
                    kept += 1;
                }
            }
            // The half diagonal, rounded up, and the centre's own rounding.
            let grow = cell * 0.866_026 * (1.0 + 1e-5) + cell * 1e-6;
            return Ok(Reduced {
                points: kept,
                radius: radius + grow,
                cell,
            });
        }
        cell *= 2.0;
    }
    Err(SurfaceError::TooManyPieces)
}

/// A point, as a convex set.
struct Point(Vector3<f32>);

impl Convex for Point {
    fn support(&self, _: &Vector3<f32>) -> Vector3<f32> {
        self.0
    }
}

/// Drops the points within `distance` of the robot's collision bodies (link0 included) at
/// configuration `q` with the fingers at `finger`; the kept points move to the front. Returns
/// how many were kept.
pub fn filter_robot(points: &mut [[f32; 3]], q: &Joints<f32>, finger: f32, distance: f32) -> Result<usize, Error> {
    if !(distance.is_finite() && distance >= 0.0) {
        return Err(Error::BadParameter);
    }
    let k = forward_with(q, finger)?;
    let bodies: [(Vector3<f32>, f32); BODIES] = core::array::from_fn(|b| {
        let body = &PANDA.bodies[b];
        (
            k.boxes[b].translation,
            crate::float::sqrt(body.half_extents.norm_squared()),
        )
    });
    let mut kept = 0;
    for i in 0..points.len() {
        let Some(&p) = points.get(i) else { break };
        let v = Vector3::from(p);
        let own = bodies.iter().enumerate().any(|(b, (c, r))| {
            if (v - c).norm_squared() > (r + distance) * (r + distance) {
                return false;
            }
            let hull = Hull {
                pose: &k.frames[PANDA.bodies[b].frame.min(FRAMES - 1)],
                points: PANDA.hull(b),
            };
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
    use std::vec::Vec;

    #[test]
    fn reduction_covers_every_input_ball() {
        let input: Vec<[f32; 3]> = (0..20_000)
            .map(|i| {
                let f = i as f32;
                [libm::sinf(f) * 0.4 + 0.5, libm::cosf(f * 0.7) * 0.4, (f * 0.001) % 0.6]
            })
            .collect();
        let mut points = input.clone();
        let r = reduce(&mut points, 0.0075, 2000).unwrap();
        assert!(r.points <= 2000 && r.cell > 0.0 && r.radius > 0.0075);
        let kept = &points[..r.points];
        for p in &input {
            let v = Vector3::from(*p);
            let covered = kept.iter().any(|c| (Vector3::from(*c) - v).norm() + 0.0075 <= r.radius);
            assert!(covered, "{p:?}");
        }
        let mut few = input[..100].to_vec();
        assert_eq!(reduce(&mut few, 0.0075, 100).unwrap().points, 100);
        assert_eq!(few, input[..100]);
        assert_eq!(reduce(&mut few, 0.0, 10), Err(SurfaceError::NonPositiveRadius));
    }

    #[test]
    fn the_robots_own_points_are_dropped() {
        let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        let k = forward_with(&ready, 0.025).unwrap();
        let tcp = k.tcp().translation;
        // One point at the hand's origin (on the robot), one 1 m away.
        let hand = k.frames[crate::robot::HAND_FRAME].translation;
        let mut points = [[hand.x, hand.y, hand.z], [tcp.x + 1.0, tcp.y, tcp.z]];
        assert_eq!(filter_robot(&mut points, &ready, 0.025, 0.01).unwrap(), 1);
        assert_eq!(points[0], [tcp.x + 1.0, tcp.y, tcp.z]);
        assert!(filter_robot(&mut points, &ready, 0.025, f32::NAN).is_err());
    }
}
