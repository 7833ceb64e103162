//! The exact checker along the curve itself, not only along the waypoints' polyline.

use super::spline::{Curve, Shape, deviation_bound, validate_waypoints};
use crate::collision::checker::{CheckConfig, MAX_STEPS_PER_SEGMENT, check_segment};
use crate::error::Error;
use crate::robot::Robot;
use crate::scene::Scene;

/// Fraction of the checker's step the curve's samples keep to, so that `f32` rounding of the
/// samples can never push a step past it.
const STEP_SAFETY: f32 = 0.99;

/// What [`check_curve`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveReport {
    /// No sampled state touches anything.
    pub free: bool,
    /// States checked (up to the first contact).
    pub states: u32,
    /// The curve's largest max-norm distance from the waypoints' polyline (rad): the stated
    /// tolerance of a trajectory that follows this curve ([`deviation_bound`]).
    pub tolerance: f32,
}

/// Checks the curve of `shape` through `waypoints` of `robot` with the exact checker, stopping at the
/// first contact. Each span is sampled uniformly in `u`, as many samples as keep every joint's
/// step ≤ `0.99 config.max_step` (from the span's derivative bound, so between the samples
/// nothing is skipped at the checker's resolution); the samples go to
/// [`check_segment`] two by two (two states a step apart: exactly those two states), so each
/// state is checked once. The ends (margins near the start and goal) are the first and last
/// waypoint. A span needing more than [`MAX_STEPS_PER_SEGMENT`] samples is
/// [`Error::SegmentTooLong`], as in the checker.
pub fn check_curve<const H: usize, const J: usize, const M: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<M>,
    waypoints: &[[f32; J]; H],
    shape: Shape,
    config: &CheckConfig,
) -> Result<CurveReport, Error> {
    validate_waypoints(waypoints)?;
    let (Some(first), Some(last)) = (waypoints.first(), waypoints.last()) else {
        return Err(Error::BadParameter);
    };
    if !(config.max_step > 0.0 && config.max_step.is_finite()) {
        return Err(Error::BadParameter);
    }
    let curve = Curve::new(waypoints, shape);
    let step = STEP_SAFETY * config.max_step;
    let mut report = CurveReport {
        free: true,
        states: 0,
        tolerance: deviation_bound(waypoints, shape),
    };
    let mut pending: Option<[f32; J]> = None;
    let mut visit = |q: [f32; J], report: &mut CurveReport| -> Result<bool, Error> {
        match pending.take() {
            None => {
                pending = Some(q);
                Ok(true)
            }
            Some(a) => {
                report.states += 2;
                check_segment(robot, scene, &a, &q, [first, last], config)
            }
        }
    };
    let spans = curve.spans();
    for i in 0..spans {
        let n = libm::ceilf(curve.speed_bound(i) / step).max(1.0);
        if n > MAX_STEPS_PER_SEGMENT as f32 {
            return Err(Error::SegmentTooLong);
        }
        let n = n as u32;
        let p = curve.span_points(i);
        let end = if i + 1 == spans { n + 1 } else { n };
        for k in 0..end {
            let q = super::spline::eval_span(&p, k as f32 / n as f32).q;
            if !visit(q, &mut report)? {
                report.free = false;
                return Ok(report);
            }
        }
    }
    if let Some(a) = pending {
        report.states += 1;
        report.free = check_segment(robot, scene, &a, &a, [first, last], config)?;
    }
    Ok(report)
}
