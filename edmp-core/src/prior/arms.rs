//! The networks of the arms beside the Panda (cargo features `iiwa7`, `xarm6`), one module
//! each: `edmp-codegen` writes its tables from the folder `ArmSpec::prior` names, and
//! `NETWORK` is `None` while the arm has no trained prior. Every network has the Panda's shape
//! but for its input and output channels, so the Panda's [`super::Scratch`] and schedule serve
//! them all (checked here at compile time).

#![allow(
    missing_docs,
    unreachable_pub,
    unused_imports,
    unused_macros,
    dead_code,
    clippy::unreadable_literal,
    clippy::excessive_precision
)]

use super::layers::{Aligned, Conv, ConvBlock, Down, Linear, Net, ResBlock, Up, slice_of};
use super::net::Network;
use super::weights;

/// Whether two shape lists are equal (in a constant context): each trained arm's generated
/// module asserts its shape and schedule equal to the Panda's with it.
const fn same(a: &[usize], b: &[usize]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Declares one arm's network module from its generated file, with the shape checks.
macro_rules! arm_network {
    ($(#[$doc:meta])* $name:ident, $file:literal) => {
        $(#[$doc])*
        pub mod $name {
            mod tables {
                use super::super::*;
                include!(concat!(env!("OUT_DIR"), "/", $file));
            }
            pub use tables::NETWORK;
        }
    };
}

#[cfg(feature = "iiwa7")]
arm_network!(
    /// The KUKA LBR iiwa 7's network.
    iiwa7,
    "prior_iiwa7.rs"
);

#[cfg(feature = "xarm6")]
arm_network!(
    /// The UFACTORY xArm 6's network.
    xarm6,
    "prior_xarm6.rs"
);
