//! The arms compiled in, one module each, with the tables `edmp-codegen` generated from the
//! arm's URDF (cargo features `panda`, `iiwa7`, `xarm6`; the firmware picks one). Each module
//! holds its arm's [`Robot`] in `f32` (`ROBOT`, what the planner uses) and `f64` (`ROBOT_F64`,
//! for oracles and host-side tools), and its sizes and names as constants.

use crate::robot::{BodySpec, FrameSpec, Gripper, Robot, reach};
use nalgebra::{Matrix3, Vector3};

// The most frames and bodies of any arm compiled in: the capacity of per-configuration
// buffers ([`crate::robot::kinematics::Kinematics`]).
include!(concat!(env!("OUT_DIR"), "/arms.rs"));

/// Declares one arm's module from its generated tables.
macro_rules! arm {
    ($(#[$doc:meta])* $name:ident, $file:literal) => {
        $(#[$doc])*
        #[allow(clippy::excessive_precision, clippy::approx_constant)]
        pub mod $name {
            use super::*;
            include!(concat!(env!("OUT_DIR"), "/", $file));
            // The tables are written once at f64 precision; the compiler rounds each literal
            // to f32 here. URDF numbers such as the limit -3.1416 are data, not π.
            // The tables as a constant, without the fields derived from them: a `static`
            // cannot be read at compile time.
            const BASE: Robot<f32, JOINTS> = tables!(body_reach: &[], hand_reach: [0.0; JOINTS],);
            const BODY_REACH: [[f32; JOINTS]; BODIES] = reach::body_reach(&BASE);
            const HAND_REACH: [f32; JOINTS] = reach::frame_reach(&BASE, HAND_FRAME, 0.0);
            /// The arm in `f32`: what the planner uses.
            pub static ROBOT: Robot<f32, JOINTS> = tables!(body_reach: &BODY_REACH, hand_reach: HAND_REACH,);
            /// The arm in `f64`: for oracles (finite differences) and host-side tools.
            pub static ROBOT_F64: Robot<f64, JOINTS> =
                tables!(body_reach: &BODY_REACH, hand_reach: HAND_REACH,);
            const _: () = assert!(FRAMES <= MAX_FRAMES && BODIES <= MAX_BODIES);
        }
    };
}

#[cfg(feature = "panda")]
arm!(
    /// The Franka Panda with its hand (`weights/panda/panda.urdf`).
    panda,
    "robot_panda.rs"
);

#[cfg(feature = "iiwa7")]
arm!(
    /// The KUKA LBR iiwa 7 (`weights/iiwa7/model.urdf`), no gripper.
    iiwa7,
    "robot_iiwa7.rs"
);

#[cfg(feature = "xarm6")]
arm!(
    /// The UFACTORY xArm 6 (`weights/xarm6/xarm6_robot.urdf`), no gripper; one collision body
    /// per convex piece of its V-HACD meshes.
    xarm6,
    "robot_xarm6.rs"
);
