//! Build-time generator of edmp-rs: freezes the Panda kinematic chain and the trained,
//! int8-quantized diffusion network into Rust tables that `edmp-core` includes from `OUT_DIR`.
//!
//! `edmp-core/build.rs` calls [`generate_robot`] and [`prior::generate_prior`]; the `edmp-codegen` binary prints the same
//! output for review. Nothing here runs on the target.

pub mod emit;
pub mod math;
pub mod mesh;
pub mod prior;
pub mod urdf;

use std::path::{Path, PathBuf};

/// Generated Rust source plus the files it was made from.
#[derive(Clone, Debug)]
pub struct Generated {
    /// Rust source to `include!`.
    pub source: String,
    /// Every file read, for `cargo:rerun-if-changed`.
    pub inputs: Vec<PathBuf>,
}

/// Reads `urdf` (and its collision meshes) and returns the robot tables. `display` is the
/// name the generated comments give the URDF (a stable, repository-relative path).
pub fn generate_robot(urdf: &Path, display: &str) -> Result<Generated, String> {
    let chain = urdf::read_chain(urdf)?;
    Ok(Generated {
        source: emit::robot_tables(&chain, display),
        inputs: chain.inputs,
    })
}
