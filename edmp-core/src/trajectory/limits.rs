//! Franka's joint limits and the user's scales on them.

use crate::error::Error;
use crate::robot::kinematics::Joints;

/// Largest joint velocity (rad/s), Franka's datasheet: joints 1-4, then 5-7.
pub const VELOCITY: Joints<f32> = [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61];
/// Largest joint acceleration (rad/s²), Franka's datasheet.
pub const ACCELERATION: Joints<f32> = [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0];
/// Largest joint jerk (rad/s³), Franka's datasheet.
pub const JERK: Joints<f32> = [7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0];

/// What the user asks of the timing: fractions of Franka's limits, and whether jerk counts.
///
/// The velocity limits are multiplied by `velocity_scale`; the acceleration *and* the jerk
/// limits by `acceleration_scale` (slower starts and stops also mean gentler ones). Both scales
/// must lie in (0, 1]; anything else, NaN included, is [`Error::BadScale`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Fraction of Franka's velocity limits, in (0, 1].
    pub velocity_scale: f32,
    /// Fraction of Franka's acceleration and jerk limits, in (0, 1].
    pub acceleration_scale: f32,
    /// Bound the jerk too (off: the time-optimal velocity and acceleration profile alone, whose
    /// acceleration jumps; for comparison with TOPP-RA).
    pub jerk_limited: bool,
}

impl Limits {
    /// Franka's full limits, jerk included.
    pub const DEFAULT: Self = Self {
        velocity_scale: 1.0,
        acceleration_scale: 1.0,
        jerk_limited: true,
    };

    /// The per-joint limits these scales give, or [`Error::BadScale`].
    pub fn joint_limits(&self) -> Result<JointLimits, Error> {
        let ok = |s: f32| s > 0.0 && s <= 1.0;
        if !ok(self.velocity_scale) || !ok(self.acceleration_scale) {
            return Err(Error::BadScale);
        }
        let (v, a) = (self.velocity_scale, self.acceleration_scale);
        Ok(JointLimits {
            velocity: VELOCITY.map(|x| x * v),
            acceleration: ACCELERATION.map(|x| x * a),
            jerk: JERK.map(|x| x * a),
        })
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Per-joint limits after scaling (all positive and finite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits {
    /// rad/s.
    pub velocity: Joints<f32>,
    /// rad/s².
    pub acceleration: Joints<f32>,
    /// rad/s³.
    pub jerk: Joints<f32>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_outside_the_unit_interval_are_refused() {
        for bad in [0.0, -0.5, 1.0001, f32::NAN, f32::INFINITY, f32::MIN_POSITIVE * 0.0] {
            let l = Limits {
                velocity_scale: bad,
                ..Limits::DEFAULT
            };
            assert_eq!(l.joint_limits(), Err(Error::BadScale), "velocity_scale {bad}");
            let l = Limits {
                acceleration_scale: bad,
                ..Limits::DEFAULT
            };
            assert_eq!(l.joint_limits(), Err(Error::BadScale), "acceleration_scale {bad}");
        }
        let l = Limits {
            velocity_scale: 0.5,
            acceleration_scale: 0.25,
            jerk_limited: true,
        };
        let j = l.joint_limits().unwrap();
        assert_eq!(j.velocity[0], 1.0875);
        assert_eq!(j.acceleration[1], 1.875);
        assert_eq!(j.jerk[6], 2500.0);
    }
}
