//! The path every stage of the planner passes on: [`HORIZON`] waypoints of the arm's joints.
//!
//! It lives here, not in the prior, because the search, the shortcut and the time law make and
//! read paths too; every prior's network is checked at build time to have been trained on this
//! horizon.

use crate::robot::JOINTS;

/// Waypoints of a planned path, the ends included (EDMP's 50).
pub const HORIZON: usize = 50;

/// A trajectory of `H` waypoints of an arm with `J` joints (the Panda's 7 unless named).
pub type Trajectory<const H: usize, const J: usize = JOINTS> = [[f32; J]; H];

/// A planned path: [`HORIZON`] waypoints of an arm with `J` joints (the Panda's 7 unless named).
pub type Path<const J: usize = JOINTS> = Trajectory<HORIZON, J>;
