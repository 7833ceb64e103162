//! The core's one error type: small, `Copy`, no strings.

use core::fmt;

/// Why a core computation refused its input or could not give a finite answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// A joint value is NaN or infinite (`joint` is its index).
    NonFiniteJoint {
        /// Index of the offending joint.
        joint: u8,
    },
    /// An upstream gradient holds a NaN or infinite value.
    NonFiniteGradient,
    /// The inputs were finite but the result overflowed (gradients near `f32::MAX`, or
    /// obstacles so large that their volumes do).
    Overflow,
    /// A tuning parameter (clearance, expansion, ...) is negative or not finite.
    BadParameter,
    /// Two consecutive waypoints are so far apart that interpolating them at the checker's
    /// step would exceed its fixed budget of states per segment.
    SegmentTooLong,
    /// A joint of a start or goal lies outside the soft limits where the computation needs it
    /// inside (the global stage's search: its trees live within the limits).
    OutsideLimits {
        /// Index of the offending joint.
        joint: u8,
    },
    /// A velocity or acceleration scale of a trajectory is not in (0, 1] (NaN included).
    BadScale,
    /// A waypoint joint is finite but beyond what a trajectory can be timed over
    /// (`trajectory::spline::MAX_JOINT_MAGNITUDE`).
    OutOfRange {
        /// Index of the offending joint.
        joint: u8,
    },
    /// A trajectory's fixed grid has fewer points than its path has spans.
    GridTooSmall,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFiniteJoint { joint } => write!(f, "joint {joint} is not a finite number"),
            Self::NonFiniteGradient => f.write_str("upstream gradient is not finite"),
            Self::Overflow => f.write_str("result overflowed to a non-finite value"),
            Self::BadParameter => f.write_str("a parameter is negative or not finite"),
            Self::SegmentTooLong => f.write_str("consecutive waypoints are too far apart to interpolate"),
            Self::OutsideLimits { joint } => write!(f, "joint {joint} is outside the soft limits"),
            Self::BadScale => f.write_str("a velocity or acceleration scale is not in (0, 1]"),
            Self::OutOfRange { joint } => write!(f, "joint {joint} of a waypoint is beyond +-100 rad"),
            Self::GridTooSmall => f.write_str("the trajectory grid is too small for the path"),
        }
    }
}

impl core::error::Error for Error {}
