//! `edmp-host fk`: print the pose of every link frame and collision box for one configuration.

use edmp_core::Error;
use edmp_core::robot::kinematics::{Joints, Pose, forward};
use edmp_core::robot::{BODY_NAMES, FRAME_NAMES, JOINT_NAMES, JOINTS, PANDA, TCP_FRAME};
use serde::Serialize;

/// Arguments of `edmp-host fk`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The 7 joint angles in radians, joint 1 first.
    #[arg(num_args = JOINTS, value_name = "JOINT", allow_negative_numbers = true, required = true)]
    joints: Vec<f64>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Report {
    joints: [f32; JOINTS],
    within_soft_limits: bool,
    tcp: PoseOut,
    frames: Vec<Named>,
    collision_boxes: Vec<BoxOut>,
}

#[derive(Debug, Serialize)]
struct Named {
    name: &'static str,
    #[serde(flatten)]
    pose: PoseOut,
}

#[derive(Debug, Serialize)]
struct BoxOut {
    name: &'static str,
    #[serde(flatten)]
    pose: PoseOut,
    half_extents: [f32; 3],
}

#[derive(Debug, Serialize)]
struct PoseOut {
    position: [f32; 3],
    quaternion: [f32; 4],
}

impl From<&Pose<f32>> for PoseOut {
    fn from(p: &Pose<f32>) -> Self {
        Self {
            position: p.translation.into(),
            quaternion: p.quaternion_wxyz(),
        }
    }
}

/// Checks the joints (finite, f32-representable) and prints the kinematics.
pub fn run(args: &Args) -> Result<(), String> {
    let mut q = [0.0f32; JOINTS];
    for (i, (&value, slot)) in args.joints.iter().zip(q.iter_mut()).enumerate() {
        if !value.is_finite() || value.abs() > f64::from(f32::MAX) {
            return Err(format!(
                "joints[{i}] ({}): {value} is not a finite number",
                JOINT_NAMES[i]
            ));
        }
        *slot = value as f32;
    }
    let report = report(&q).map_err(|e| format!("joints: {e}"))?;
    if args.json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| format!("cannot write JSON: {e}"))?;
        println!("{text}");
        return Ok(());
    }
    print_table(&report);
    Ok(())
}

/// The `--json` document for `q` (what `edmp-host fk --json` prints): the one writer of it,
/// which the Python package's `fk` shares.
pub fn document(q: &Joints<f32>) -> Result<serde_json::Value, Error> {
    let report = report(q)?;
    Ok(serde_json::to_value(&report).unwrap_or(serde_json::Value::Null))
}

fn report(q: &Joints<f32>) -> Result<Report, Error> {
    let q = *q;
    let k = forward(&PANDA, &q)?;
    Ok(Report {
        joints: q,
        within_soft_limits: PANDA.within_soft_limits(&q, 0.0),
        tcp: k.tcp().into(),
        frames: FRAME_NAMES
            .iter()
            .zip(k.frames.iter())
            .map(|(&name, p)| Named { name, pose: p.into() })
            .collect(),
        collision_boxes: BODY_NAMES
            .iter()
            .zip(k.boxes.iter())
            .zip(PANDA.bodies.iter())
            .map(|((&name, p), spec)| BoxOut {
                name,
                pose: p.into(),
                half_extents: spec.half_extents.into(),
            })
            .collect(),
    })
}

fn print_table(r: &Report) {
    let limits = if r.within_soft_limits { "within" } else { "OUTSIDE" };
    println!("joints (rad): {:?}  ({limits} the soft limits)", r.joints);
    println!(
        "{:<20} {:>9} {:>9} {:>9}   {:>8} {:>8} {:>8} {:>8}",
        "frame", "x", "y", "z", "qw", "qx", "qy", "qz"
    );
    let row = |name: &str, p: &PoseOut| {
        let [x, y, z] = p.position;
        let [w, i, j, k] = p.quaternion;
        println!("{name:<20} {x:>9.5} {y:>9.5} {z:>9.5}   {w:>8.5} {i:>8.5} {j:>8.5} {k:>8.5}");
    };
    for f in &r.frames {
        row(f.name, &f.pose);
    }
    println!();
    println!("collision box centres (half extents in m):");
    for b in &r.collision_boxes {
        row(b.name, &b.pose);
        println!(
            "{:<20} half extents {:.4} {:.4} {:.4}",
            "", b.half_extents[0], b.half_extents[1], b.half_extents[2]
        );
    }
    println!();
    row(&format!("TCP ({})", FRAME_NAMES[TCP_FRAME]), &r.tcp);
}
