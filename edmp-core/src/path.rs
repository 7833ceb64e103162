//! The path every stage of the planner passes on: [`HORIZON`] waypoints of the arm's joints.
//!
//! It lives here, not in the prior, because the search, the shortcut and the time law make and
//! read paths too; the prior's network is checked at build time to have been trained on this
//! horizon.

use crate::robot::JOINTS;

/// Waypoints of a planned path, the ends included (EDMP's 50).
pub const HORIZON: usize = 50;

/// A trajectory of `H` waypoints of the arm's joints.
pub type Trajectory<const H: usize> = [[f32; JOINTS]; H];

/// A planned path: [`HORIZON`] waypoints of the Panda's joints.
pub type Path = Trajectory<HORIZON>;

/// A planned path of an arm with `J` joints: [`HORIZON`] waypoints.
pub type PathOf<const J: usize> = [[f32; J]; HORIZON];
