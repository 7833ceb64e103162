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

    /// The Panda's tables carry Franka's datasheet numbers exactly, so its timed plans keep
    /// their bits.
    #[test]
    fn the_pandas_limits_are_frankas_datasheet() {
        assert_eq!(PANDA.max_velocity, [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61]);
        assert_eq!(PANDA.max_acceleration, [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0]);
        assert_eq!(
            PANDA.max_jerk,
            [7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0]
        );
    }

    fn scaled_within<const J: usize>(robot: &Robot<f32, J>) {
        let all = [robot.max_velocity, robot.max_acceleration, robot.max_jerk];
        assert!(
            all.iter().flatten().all(|x| x.is_finite() && *x > 0.0),
            "{}",
            robot.name
        );
        let l = Limits {
            velocity_scale: 0.5,
            acceleration_scale: 0.25,
            jerk_limited: true,
        };
        let j = l.joint_limits(robot).unwrap();
        for i in 0..J {
            assert_eq!(j.velocity[i], robot.max_velocity[i] * 0.5);
            assert_eq!(j.acceleration[i], robot.max_acceleration[i] * 0.25);
            assert_eq!(j.jerk[i], robot.max_jerk[i] * 0.25);
        }
    }

    #[test]
    fn every_arms_limits_are_its_own_and_scale() {
        scaled_within(&PANDA);
        #[cfg(feature = "iiwa7")]
        {
            let iiwa = &crate::robot::arms::iiwa7::ROBOT;
            scaled_within(iiwa);
            // KUKA's datasheet axis speeds, °/s.
            for (v, deg) in iiwa
                .max_velocity
                .iter()
                .zip([98.0f32, 98.0, 100.0, 130.0, 140.0, 180.0, 180.0])
            {
                assert!((v - deg.to_radians()).abs() < 1e-6, "{v} vs {deg} °/s");
            }
        }
        #[cfg(feature = "xarm6")]
        {
            let xarm = &crate::robot::arms::xarm6::ROBOT;
            scaled_within(xarm);
            // UFACTORY's datasheet: 180 °/s on every joint.
            assert!(
                xarm.max_velocity
                    .iter()
                    .all(|v| (v - core::f32::consts::PI).abs() < 1e-6)
            );
        }
    }
}
