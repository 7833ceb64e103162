//! Build-time generator of edmp-rs: freezes each arm's kinematic chain ([`arms::ARMS`]) and the
//! trained, int8-quantized diffusion network into Rust tables that `edmp-core` includes from
//! `OUT_DIR`.
//!
//! `edmp-core/build.rs` calls [`generate_robot`] and [`prior::generate_prior`]; the `edmp-codegen` binary prints the same
//! output for review. Nothing here runs on the target.

pub mod arms;
pub mod emit;
pub mod hull_distance;
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

/// Generated robot tables and the sizes a build needs to hold them.
#[derive(Clone, Debug)]
pub struct GeneratedArm {
    /// The source and its inputs.
    pub generated: Generated,
    /// Link frames.
    pub frames: usize,
    /// Collision bodies.
    pub bodies: usize,
    /// Actuated joints.
    pub joints: usize,
}

/// Reads the URDF at `urdf` (arm `arm`'s, or an edited copy) with its collision meshes and
/// returns its tables. The generated comments name the URDF by `arm.urdf`, its
/// repository-relative path.
pub fn generate_robot(urdf: &Path, arm: &arms::ArmSpec) -> Result<GeneratedArm, String> {
    let chain = urdf::read_chain(urdf, arm)?;
    if arm.neutral.len() != chain.joints.len() {
        return Err(format!(
            "arm `{}`: neutral has {} values, the URDF {} actuated joints",
            arm.name,
            arm.neutral.len(),
            chain.joints.len()
        ));
    }
    let d = &arm.dynamics;
    for (what, values) in [
        ("velocity", d.velocity),
        ("acceleration", d.acceleration),
        ("jerk", d.jerk),
    ] {
        if values.len() != chain.joints.len() {
            return Err(format!(
                "arm `{}`: dynamics.{what} has {} values, the URDF {} actuated joints",
                arm.name,
                values.len(),
                chain.joints.len()
            ));
        }
        // The time law divides by every limit: each must be a positive, finite number.
        if let Some(i) = values.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(format!(
                "arm `{}`: dynamics.{what}[{i}] = {} is not a positive, finite limit",
                arm.name, values[i]
            ));
        }
    }
    if let Some(i) = (0..chain.joints.len())
        .find(|&i| !(chain.joints[i].soft[0]..=chain.joints[i].soft[1]).contains(&arm.neutral[i]))
    {
        return Err(format!(
            "arm `{}`: neutral[{i}] = {} is outside the planning range {:?}",
            arm.name, arm.neutral[i], chain.joints[i].soft
        ));
    }
    Ok(GeneratedArm {
        frames: chain.frames.len(),
        bodies: chain.bodies.len(),
        joints: chain.joints.len(),
        generated: Generated {
            source: emit::robot_tables(&chain, arm.urdf),
            inputs: chain.inputs,
        },
    })
}
