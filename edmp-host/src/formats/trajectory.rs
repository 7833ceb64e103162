//! `--timed`: the chosen path as a time-stamped trajectory, the `trajectory` field of
//! `edmp-plan/1` (docs/formats.md), shaped like ROS `trajectory_msgs/JointTrajectory`.
//!
//! The core times the path (`edmp_core::trajectory`): a cubic B-spline over the waypoints,
//! checked with the planner's checker (or the exact polyline when the spline touches
//! anything), within the arm's velocity, acceleration and jerk limits (its `Robot` table's)
//! times the user's scales, from rest to rest. Here it is sampled at the user's rate and written
//! out, under the arm's joint names.

use crate::Failure;
use edmp_core::collision::checker::CheckConfig;
use edmp_core::path::{HORIZON, Path};
use edmp_core::robot::Robot;
use edmp_core::scene::Scene;
use edmp_core::trajectory::{Limits, Shape, Timed, parameterize_checked};
use serde_json::{Value, json};

/// Highest sample rate, Hz: Franka's controller runs at 1 kHz.
pub const MAX_RATE: f64 = 1000.0;

/// The `--timed` flags of `edmp-host plan`.
#[derive(Debug, Clone, clap::Args)]
pub struct TimedArgs {
    /// Add `trajectory`: the path timed within the arm's limits, from rest to rest.
    #[arg(long)]
    pub timed: bool,
    /// Sample rate of the trajectory's points, Hz (at most 1000).
    #[arg(long, default_value_t = 100.0, requires = "timed")]
    pub rate: f64,
    /// Fraction of the arm's velocity limits, in (0, 1].
    #[arg(long, default_value_t = 1.0, requires = "timed")]
    pub velocity_scale: f32,
    /// Fraction of the arm's acceleration and jerk limits, in (0, 1].
    #[arg(long, default_value_t = 1.0, requires = "timed")]
    pub acceleration_scale: f32,
    /// Time-optimal under the velocity and acceleration limits alone, the acceleration jumps
    /// (for comparison with TOPP-RA; a controller wants the jerk-limited default).
    #[arg(long, requires = "timed")]
    pub no_jerk_limit: bool,
}

/// A validated request for a timed trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedRequest {
    /// Points per second.
    pub rate: f64,
    /// The scales (jerk limited).
    pub limits: Limits,
}

impl TimedRequest {
    /// The request for `rate` Hz and the two scales, or the bad value named by its flag.
    pub fn new(rate: f64, velocity_scale: f32, acceleration_scale: f32) -> Result<Self, Failure> {
        if !(rate.is_finite() && rate > 0.0 && rate <= MAX_RATE) {
            return Err(Failure::Input(format!("--rate: {rate} outside (0, {MAX_RATE}] Hz")));
        }
        let scale_ok = |s: f32| s > 0.0 && s <= 1.0;
        if !scale_ok(velocity_scale) {
            return Err(Failure::Input(format!(
                "--velocity-scale: {velocity_scale} outside (0, 1]"
            )));
        }
        if !scale_ok(acceleration_scale) {
            return Err(Failure::Input(format!(
                "--acceleration-scale: {acceleration_scale} outside (0, 1]"
            )));
        }
        Ok(Self {
            rate,
            limits: Limits {
                velocity_scale,
                acceleration_scale,
                jerk_limited: true,
            },
        })
    }
}

impl TimedArgs {
    /// The validated request, `None` without `--timed`.
    pub fn request(&self) -> Result<Option<TimedRequest>, Failure> {
        if !self.timed {
            return Ok(None);
        }
        let mut request = TimedRequest::new(self.rate, self.velocity_scale, self.acceleration_scale)?;
        request.limits.jerk_limited = !self.no_jerk_limit;
        Ok(Some(request))
    }
}

/// The `trajectory` document of `path`, a path of `robot` the planner's checker passed in
/// `scene`: timed within `robot`'s limits, its points under `robot`'s joint names.
pub fn trajectory_document<const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    path: &Path<J>,
    check: &CheckConfig,
    request: &TimedRequest,
) -> Result<Value, Failure> {
    let mut timed = Box::new(Timed::<{ edmp_core::trajectory::DEFAULT_GRID }, HORIZON, J>::new());
    let shape = parameterize_checked(robot, scene, path, &request.limits, check, &mut timed)
        .map_err(|e| Failure::Input(format!("time parameterization: {e}")))?;
    let duration = f64::from(timed.duration());
    // Every 1/rate seconds, and the last point exactly at the end.
    let n = (duration * request.rate).ceil() as usize;
    let points: Vec<Value> = (0..=n)
        .map(|k| {
            let time = if k == n {
                timed.duration()
            } else {
                (k as f64 / request.rate) as f32
            };
            let p = timed.sample(time);
            json!({
                "positions": p.positions.as_slice(),
                "velocities": p.velocities.as_slice(),
                "accelerations": p.accelerations.as_slice(),
                "time_from_start": p.time,
            })
        })
        .collect();
    Ok(json!({
        "joint_names": robot.joint_names.as_slice(),
        "points": points,
        "limits": {
            "velocity_scale": request.limits.velocity_scale,
            "acceleration_scale": request.limits.acceleration_scale,
            "jerk_limited": request.limits.jerk_limited,
        },
        "shape": match shape {
            Shape::Spline => "spline",
            Shape::Polyline => "polyline",
        },
        "tolerance": timed.tolerance(),
        "duration": timed.duration(),
        "rate_hz": request.rate,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_and_scales_are_validated_and_named() {
        assert!(TimedRequest::new(100.0, 1.0, 0.5).is_ok());
        for (rate, v, a, flag) in [
            (0.0, 1.0, 1.0, "--rate"),
            (f64::NAN, 1.0, 1.0, "--rate"),
            (2000.0, 1.0, 1.0, "--rate"),
            (100.0, 0.0, 1.0, "--velocity-scale"),
            (100.0, 1.5, 1.0, "--velocity-scale"),
            (100.0, 1.0, f32::NAN, "--acceleration-scale"),
        ] {
            match TimedRequest::new(rate, v, a) {
                Err(Failure::Input(message)) => assert!(message.starts_with(flag), "{message}"),
                other => panic!("{rate} {v} {a}: {other:?}"),
            }
        }
    }
}
