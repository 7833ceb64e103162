//! The planning core of edmp-rs: `no_std`, no allocation, deterministic.
//!
//! This crate holds the math a controller embeds: each compiled-in arm's kinematics (frozen
//! from its URDF at build time, one cargo feature per arm), the collision costs, the checker,
//! the diffusion prior and the guided planner. Everything runs on fixed-size arrays; bad input
//! is a typed [`Error`], never a panic or a NaN.
//!
//! ```
//! use edmp_core::robot::{PANDA, kinematics::forward};
//! let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
//! let k = forward(&PANDA, &ready).unwrap();
//! let tcp = k.tcp().translation;
//! assert!(tcp.x > 0.2 && tcp.z > 0.2);
//! ```
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(test)]
extern crate std;

pub mod collision;
pub mod cost;
pub mod error;
pub mod executor;
pub mod float;
pub mod guidance;
pub mod path;
pub mod planner;
pub mod prior;
pub mod rng;
pub mod robot;
pub mod scene;
pub mod surface;
pub mod trajectory;
#[cfg(feature = "serde")]
pub mod wire;

pub use error::Error;
