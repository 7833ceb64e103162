//! The arm's joint limits and the user's scales on them.

use crate::error::Error;
use crate::robot::Robot;

/// What the user asks of the timing: fractions of the arm's limits ([`Robot::max_velocity`],
/// [`Robot::max_acceleration`], [`Robot::max_jerk`]), and whether jerk counts. The scales do not
/// name the arm, so one request serves any arm.
///
/// The velocity limits are multiplied by `velocity_scale`; the acceleration *and* the jerk
/// limits by `acceleration_scale` (slower starts and stops also mean gentler ones). Both scales
/// must lie in (0, 1]; anything else, NaN included, is [`Error::BadScale`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Fraction of the arm's velocity limits, in (0, 1].
    pub velocity_scale: f32,
    /// Fraction of the arm's acceleration and jerk limits, in (0, 1].
    pub acceleration_scale: f32,
    /// Bound the jerk too (off: the time-optimal velocity and acceleration profile alone, whose
    /// acceleration jumps; for comparison with TOPP-RA).
    pub jerk_limited: bool,
}

impl Limits {
    /// The arm's full limits, jerk included.
    pub const DEFAULT: Self = Self {
        velocity_scale: 1.0,
        acceleration_scale: 1.0,
        jerk_limited: true,
    };

    /// The per-joint limits these scales give on `robot`'s, or [`Error::BadScale`].
    pub fn joint_limits<const J: usize>(&self, robot: &Robot<f32, J>) -> Result<JointLimits<J>, Error> {
        let ok = |s: f32| s > 0.0 && s <= 1.0;
        if !ok(self.velocity_scale) || !ok(self.acceleration_scale) {
            return Err(Error::BadScale);
        }
        let (v, a) = (self.velocity_scale, self.acceleration_scale);
        Ok(JointLimits {
            velocity: robot.max_velocity.map(|x| x * v),
            acceleration: robot.max_acceleration.map(|x| x * a),
            jerk: robot.max_jerk.map(|x| x * a),
        })
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Per-joint limits of an arm with `J` joints after scaling (all positive and finite: the
/// generator refuses an arm whose limits are not).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits<const J: usize> {
    /// rad/s.
    pub velocity: [f32; J],
    /// rad/s².
    pub acceleration: [f32; J],
    /// rad/s³.
    pub jerk: [f32; J],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::PANDA;

    #[test]
    fn scales_outside_the_unit_interval_are_refused() {
        for bad in [0.0, -0.5, 1.0001, f32::NAN, f32::INFINITY, f32::MIN_POSITIVE * 0.0] {
            let l = Limits {
                velocity_scale: bad,
                ..Limits::DEFAULT
            };
            assert_eq!(l.joint_limits(&PANDA), Err(Error::BadScale), "velocity_scale {bad}");
            let l = Limits {
                acceleration_scale: bad,
                ..Limits::DEFAULT
            };
            assert_eq!(l.joint_limits(&PANDA), Err(Error::BadScale), "acceleration_scale {bad}");
        }
        let l = Limits {
            velocity_scale: 0.5,
            acceleration_scale: 0.25,
            jerk_limited: true,
        };
        let j = l.joint_limits(&PANDA).unwrap();
        assert_eq!(j.velocity[0], 1.0875);
        assert_eq!(j.acceleration[1], 1.875);
        assert_eq!(j.jerk[6], 2500.0);
    }
}
