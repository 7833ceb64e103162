//! FK and self-collision pairs of the arms without a gripper against PyBullet 3.2.7
//! (`tests/fixtures/fk_pybullet_iiwa7.json`, `fk_pybullet_xarm6.json`: the zero configuration
//! and 500 random ones, recorded by `tests/fixtures/record_fk.py --robot NAME`).

use edmp_core::robot::Robot;
use edmp_core::robot::arms::{iiwa7, xarm6};
use edmp_core::robot::kinematics::forward;
use nalgebra::Vector3;
use serde::Deserialize;
use std::collections::BTreeSet;

/// Budgets: position 1e-5 m, rotation 1e-5 rad, for the f32 planner FK (as the Panda's).
const POSITION_TOL: f64 = 1e-5;
const ROTATION_TOL: f64 = 1e-5;
/// The f64 FK: PyBullet keeps URDF origins in f32, so its poses are good to ~1e-7 m.
const F64_POSITION_TOL: f64 = 5e-7;

/// One arm's fixture (the Panda's layout plus `self_pairs`).
#[derive(Debug, Deserialize)]
struct Fixture {
    format: String,
    source: String,
    links: Vec<String>,
    pose_layout: String,
    /// Link-name pairs PyBullet checks: not parent and child, apart at q = 0.
    self_pairs: Vec<[String; 2]>,
    samples: Vec<Sample>,
}

#[derive(Debug, Deserialize)]
struct Sample {
    joints: Vec<f64>,
    /// `x y z qw qx qy qz` per link, in `Fixture::links` order.
    poses: Vec<[f64; 7]>,
}

fn load(text: &str, name: &str) -> Fixture {
    let fixture: Fixture = serde_json::from_str(text).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(fixture.format, "edmp-fk-fixture/1", "{name}");
    assert!(fixture.samples.len() > 500, "{name}: {}", fixture.source);
    fixture
}

fn iiwa7_fixture() -> Fixture {
    load(
        include_str!("../fixtures/fk_pybullet_iiwa7.json"),
        "fk_pybullet_iiwa7.json",
    )
}

fn xarm6_fixture() -> Fixture {
    load(
        include_str!("../fixtures/fk_pybullet_xarm6.json"),
        "fk_pybullet_xarm6.json",
    )
}

fn joints<const J: usize>(sample: &Sample) -> [f64; J] {
    assert_eq!(sample.joints.len(), J);
    core::array::from_fn(|i| sample.joints[i])
}

/// Checks every recorded frame of every sample; returns the worst position and rotation errors.
fn check_fk<const J: usize>(robot: &'static Robot<f32, J>, fixture: &Fixture) -> (f64, f64) {
    assert_eq!(
        fixture.links, robot.frame_names,
        "{}: fixture links must be the generated frame order ({})",
        robot.name, fixture.pose_layout
    );
    let (mut worst_pos, mut worst_rot) = (0.0f64, 0.0f64);
    for (n, sample) in fixture.samples.iter().enumerate() {
        let q = joints::<J>(sample).map(|x| x as f32);
        let k = forward(robot, &q).expect("finite joints");
        assert_eq!(sample.poses.len(), robot.frames.len());
        for (f, pose) in sample.poses.iter().enumerate() {
            let (pos_err, rot_err) = edmp_tests::pose_errors(&k.frames[f], pose);
            let name = robot.frame_names[f];
            assert!(
                pos_err <= POSITION_TOL,
                "{} sample {n} {name}: position off by {pos_err:e} m",
                robot.name
            );
            assert!(
                rot_err <= ROTATION_TOL,
                "{} sample {n} {name}: rotation off by {rot_err:e} rad",
                robot.name
            );
            worst_pos = worst_pos.max(pos_err);
            worst_rot = worst_rot.max(rot_err);
        }
    }
    println!(
        "{}: worst position error {worst_pos:e} m, worst rotation error {worst_rot:e} rad",
        robot.name
    );
    (worst_pos, worst_rot)
}

fn check_fk_f64<const J: usize>(robot: &'static Robot<f64, J>, fixture: &Fixture) {
    let mut worst = 0.0f64;
    for sample in &fixture.samples {
        let k = forward(robot, &joints::<J>(sample)).expect("finite joints");
        for (f, pose) in sample.poses.iter().enumerate() {
            let err = (k.frames[f].translation - Vector3::new(pose[0], pose[1], pose[2])).norm();
            assert!(
                err < F64_POSITION_TOL,
                "{} {}: {err:e}",
                robot.name,
                robot.frame_names[f]
            );
            worst = worst.max(err);
        }
    }
    println!("{} f64: worst position error {worst:e} m", robot.name);
}

/// The generated body pairs, as link-name pairs, must be PyBullet's, and every pair of two
/// such links' pieces must be in the table (the rule checks each piece against each piece).
fn check_self_pairs<const J: usize>(robot: &'static Robot<f32, J>, fixture: &Fixture) {
    let link_of = |body: u8| robot.frame_names[robot.bodies[usize::from(body)].frame];
    let ordered = |a: &str, b: &str| {
        let (fa, fb) = (
            robot.frame_names.iter().position(|n| *n == a),
            robot.frame_names.iter().position(|n| *n == b),
        );
        if fa <= fb {
            (a.to_owned(), b.to_owned())
        } else {
            (b.to_owned(), a.to_owned())
        }
    };
    let generated: BTreeSet<_> = robot
        .self_pairs
        .iter()
        .map(|&(a, b)| ordered(link_of(a), link_of(b)))
        .collect();
    let recorded: BTreeSet<_> = fixture.self_pairs.iter().map(|[a, b]| ordered(a, b)).collect();
    assert_eq!(generated, recorded, "{}: self-collision link pairs", robot.name);
    let pieces = |link: &str| {
        robot
            .bodies
            .iter()
            .filter(|b| robot.frame_names[b.frame] == link)
            .count()
    };
    let expanded: usize = recorded.iter().map(|(a, b)| pieces(a) * pieces(b)).sum();
    assert_eq!(
        robot.self_pairs.len(),
        expanded,
        "{}: every piece against every piece",
        robot.name
    );
    for w in robot.self_pairs.windows(2) {
        assert!(w[0] < w[1], "{}: table not ascending at {:?}", robot.name, w);
    }
    println!(
        "{}: {} link pairs, {} body pairs",
        robot.name,
        recorded.len(),
        robot.self_pairs.len()
    );
}

#[test]
fn iiwa7_fk_matches_pybullet() {
    let fixture = iiwa7_fixture();
    check_fk(&iiwa7::ROBOT, &fixture);
    check_fk_f64(&iiwa7::ROBOT_F64, &fixture);
}

#[test]
fn xarm6_fk_matches_pybullet() {
    let fixture = xarm6_fixture();
    check_fk(&xarm6::ROBOT, &fixture);
    check_fk_f64(&xarm6::ROBOT_F64, &fixture);
}

#[test]
fn iiwa7_self_pairs_match_pybullet() {
    check_self_pairs(&iiwa7::ROBOT, &iiwa7_fixture());
}

#[test]
fn xarm6_self_pairs_match_pybullet() {
    check_self_pairs(&xarm6::ROBOT, &xarm6_fixture());
}

#[test]
fn the_tool_frames_and_bodies_are_the_specified_ones() {
    assert_eq!(iiwa7::ROBOT.frame_names[iiwa7::ROBOT.tcp_frame], "lbr_iiwa_link_7");
    assert_eq!(iiwa7::ROBOT.hand_frame, iiwa7::ROBOT.tcp_frame);
    assert_eq!((iiwa7::JOINTS, iiwa7::BODIES), (7, 8));
    assert_eq!(xarm6::ROBOT.frame_names[xarm6::ROBOT.tcp_frame], "link6");
    assert_eq!(xarm6::ROBOT.hand_frame, xarm6::ROBOT.tcp_frame);
    // V-HACD pieces: base 5, link1 2, link2 3, link3 3, link4 5, link5 2, link6 1.
    assert_eq!((xarm6::JOINTS, xarm6::BODIES), (6, 21));
    assert!(iiwa7::ROBOT.gripper.is_none() && xarm6::ROBOT.gripper.is_none());
}
