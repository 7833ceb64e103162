//! `edmp-host fk`: print the pose of every link frame and collision box for one configuration
//! of any arm the host knows.

use crate::arm::{Arm, with_arm};
use crate::commands::print_stdout;
use core::fmt::Write;
use edmp_core::Error;
use edmp_core::robot::Robot;
use edmp_core::robot::kinematics::{Pose, forward};
use serde::Serialize;

/// Arguments of `edmp-host fk`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The joint angles in radians, joint 1 first: as many as the arm has (7 for the Panda and
    /// the iiwa 7, 6 for the xArm 6).
    #[arg(num_args = 1.., value_name = "JOINT", allow_negative_numbers = true, required = true)]
    joints: Vec<f64>,
    /// The arm (the scene format's `robot` names).
    #[arg(long, value_enum, default_value_t = Arm::Panda)]
    robot: Arm,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Report {
    robot: &'static str,
    joints: Vec<f32>,
    within_soft_limits: bool,
    tcp: PoseOut,
    tcp_frame: &'static str,
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

/// Checks the joints (as many as the arm has, finite, f32-representable) and prints the
/// kinematics.
pub fn run(args: &Args) -> Result<(), String> {
    let report = with_arm!(args.robot, robot => joints(robot, &args.joints)
        .and_then(|q| report(robot, &q).map_err(|e| format!("joints: {e}"))))?;
    if args.json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| format!("cannot write JSON: {e}"))?;
        return print_stdout(&format!("{text}\n"));
    }
    print_stdout(&table(&report))
}

/// The `--json` document for `robot` at `q` (what `edmp-host fk --json` prints): the one
/// writer of it, which the Python package's `fk` shares.
pub fn document<const J: usize>(robot: &'static Robot<f32, J>, q: &[f32; J]) -> Result<serde_json::Value, Error> {
    let report = report(robot, q)?;
    Ok(serde_json::to_value(&report).unwrap_or(serde_json::Value::Null))
}

/// The command line's joints for `robot`: its number of them, each finite in f32.
fn joints<const J: usize>(robot: &Robot<f32, J>, values: &[f64]) -> Result<[f32; J], String> {
    if values.len() != J {
        return Err(format!(
            "joints: {} has {J} joints ({}), {} given",
            robot.name,
            robot.joint_names.join(", "),
            values.len()
        ));
    }
    let mut q = [0.0f32; J];
    for (i, (&value, slot)) in values.iter().zip(q.iter_mut()).enumerate() {
        if !value.is_finite() || value.abs() > f64::from(f32::MAX) {
            return Err(format!(
                "joints[{i}] ({}): {value} is not a finite number",
                robot.joint_names[i]
            ));
        }
        *slot = value as f32;
    }
    Ok(q)
}

fn report<const J: usize>(robot: &'static Robot<f32, J>, q: &[f32; J]) -> Result<Report, Error> {
    let k = forward(robot, q)?;
    Ok(Report {
        robot: robot.name,
        joints: q.to_vec(),
        within_soft_limits: robot.within_soft_limits(q, 0.0),
        tcp: k.tcp().into(),
        tcp_frame: robot.frame_names[robot.tcp_frame],
        frames: robot
            .frame_names
            .iter()
            .zip(k.frames.iter())
            .map(|(&name, p)| Named { name, pose: p.into() })
            .collect(),
        collision_boxes: robot
            .body_names
            .iter()
            .zip(k.boxes.iter())
            .zip(robot.bodies.iter())
            .map(|((&name, p), spec)| BoxOut {
                name,
                pose: p.into(),
                half_extents: spec.half_extents.into(),
            })
            .collect(),
    })
}

fn table(r: &Report) -> String {
    let limits = if r.within_soft_limits { "within" } else { "OUTSIDE" };
    let mut t = format!(
        "{} joints (rad): {:?}  ({limits} the planning limits)\n{:<20} {:>9} {:>9} {:>9}   {:>8} {:>8} {:>8} {:>8}\n",
        r.robot, r.joints, "frame", "x", "y", "z", "qw", "qx", "qy", "qz"
    );
    let row = |t: &mut String, name: &str, p: &PoseOut| {
        let [x, y, z] = p.position;
        let [w, i, j, k] = p.quaternion;
        let _ = writeln!(
            t,
            "{name:<20} {x:>9.5} {y:>9.5} {z:>9.5}   {w:>8.5} {i:>8.5} {j:>8.5} {k:>8.5}"
        );
    };
    for f in &r.frames {
        row(&mut t, f.name, &f.pose);
    }
    t.push_str("\ncollision box centres (half extents in m):\n");
    for b in &r.collision_boxes {
        row(&mut t, b.name, &b.pose);
        let [x, y, z] = b.half_extents;
        let _ = writeln!(t, "{:<20} half extents {x:.4} {y:.4} {z:.4}", "");
    }
    t.push('\n');
    row(&mut t, &format!("TCP ({})", r.tcp_frame), &r.tcp);
    t
}
