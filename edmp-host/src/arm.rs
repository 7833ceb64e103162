//! The arms compiled into the host, by the scene format's `robot` name (docs/formats.md,
//! "Other arms"), and [`with_arm!`], which runs code generic over the number of joints on the
//! tables of the arm a user named.

use std::fmt;

/// An arm the host knows: each has its generated tables in `edmp_core::robot::arms`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Arm {
    /// Franka Emika Panda with its hand (7 joints).
    #[default]
    Panda,
    /// KUKA LBR iiwa 7 (7 joints).
    Iiwa7,
    /// UFACTORY xArm 6 (6 joints).
    Xarm6,
}

impl Arm {
    /// Every arm, the Panda first.
    pub const ALL: [Arm; 3] = [Arm::Panda, Arm::Iiwa7, Arm::Xarm6];

    /// The scene format's `robot` name.
    pub fn name(self) -> &'static str {
        match self {
            Arm::Panda => "panda",
            Arm::Iiwa7 => "iiwa7",
            Arm::Xarm6 => "xarm6",
        }
    }

    /// The arm called `name`, if the host knows it.
    pub fn from_name(name: &str) -> Option<Arm> {
        Arm::ALL.into_iter().find(|a| a.name() == name)
    }

    /// The number of joints.
    pub fn joints(self) -> usize {
        with_arm!(self, robot => robot.joint_names.len())
    }
}

/// The error for an arm whose prior is not trained yet.
pub fn untrained(arm: Arm) -> String {
    format!("{arm}: no trained prior yet (weights/README.md: `gen-data --robot {arm}`, then train.py)")
}

impl fmt::Display for Arm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `with_arm!(arm, robot => expr)`: evaluates `expr` with `robot` bound to the arm's `f32`
/// tables (`&'static Robot<f32, J>`, each arm its own `J`), so generic code runs for the
/// arm named at run time. `with_arm!(arm, robot, network => expr)` also binds `network` to
/// the arm's trained prior (`&'static Network<J>`) and is `Ok(expr)`, or an `Err` naming the
/// arm when it has no trained prior yet.
#[macro_export]
macro_rules! with_arm {
    ($arm:expr, $robot:ident, $network:ident => $body:expr) => {
        match $arm {
            $crate::arm::Arm::Panda => {
                let ($robot, $network) = (&edmp_core::robot::arms::panda::ROBOT, edmp_core::prior::PANDA);
                Ok($body)
            }
            $crate::arm::Arm::Iiwa7 => {
                let $robot = &edmp_core::robot::arms::iiwa7::ROBOT;
                match edmp_core::prior::arms::iiwa7::NETWORK {
                    Some($network) => Ok($body),
                    None => Err($crate::arm::untrained($crate::arm::Arm::Iiwa7)),
                }
            }
            $crate::arm::Arm::Xarm6 => {
                let $robot = &edmp_core::robot::arms::xarm6::ROBOT;
                match edmp_core::prior::arms::xarm6::NETWORK {
                    Some($network) => Ok($body),
                    None => Err($crate::arm::untrained($crate::arm::Arm::Xarm6)),
                }
            }
        }
    };
    ($arm:expr, $robot:ident => $body:expr) => {
        match $arm {
            $crate::arm::Arm::Panda => {
                let $robot = &edmp_core::robot::arms::panda::ROBOT;
                $body
            }
            $crate::arm::Arm::Iiwa7 => {
                let $robot = &edmp_core::robot::arms::iiwa7::ROBOT;
                $body
            }
            $crate::arm::Arm::Xarm6 => {
                let $robot = &edmp_core::robot::arms::xarm6::ROBOT;
                $body
            }
        }
    };
}
pub use with_arm;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_the_generated_tables() {
        for arm in Arm::ALL {
            assert_eq!(Arm::from_name(arm.name()), Some(arm));
            assert_eq!(with_arm!(arm, robot => robot.name), arm.name());
        }
        assert_eq!(Arm::from_name("ur5"), None);
        assert_eq!(
            (Arm::Panda.joints(), Arm::Iiwa7.joints(), Arm::Xarm6.joints()),
            (7, 7, 6)
        );
    }
}
