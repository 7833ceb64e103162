//! The exact collision check: whether the arm's collision hulls touch an obstacle or each other
//! at a configuration or anywhere along a path. Its word decides whether a plan is free.
//!
//! - [`convex`]: the arm's hulls and the obstacles as convex sets (support functions).
//! - [`gjk`]: the distance between two convex sets (GJK), with its witness direction.
//! - [`checker`]: states, segments and whole trajectories against the scene, with the
//!   margins near the ends and the steps that [`crate::robot::reach`] bounds.
//! - [`filter`]: the robot's own points dropped from a cloud.

pub mod checker;
pub mod convex;
pub mod filter;
pub mod gjk;
