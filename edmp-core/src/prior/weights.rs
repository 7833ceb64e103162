//! The trained network, frozen at build time: `edmp-codegen` writes `OUT_DIR/prior.rs` (the
//! layer table, the schedule, the checksum) and `OUT_DIR/prior.bin` (the int8 weights) from
//! `weights/prior/`.

#![allow(
    missing_docs,
    unreachable_pub,
    clippy::unreadable_literal,
    clippy::excessive_precision
)]

use super::layers::{Aligned, Conv, ConvBlock, Down, Linear, Net, ResBlock, Up, slice_of};
use super::net::Network;

include!(concat!(env!("OUT_DIR"), "/prior.rs"));

/// The Panda's network (`weights/prior/`).
pub static NETWORK: Network<JOINTS> = Network {
    name: "panda",
    net: &NET,
    blob: WEIGHT_BLOB,
    fnv1a: WEIGHTS_FNV1A,
    wave_budget: Some(crate::planner::WAVE_BUDGET),
};
