//! The exact checker against PyBullet 3.2.7 for the arms beside the Panda
//! (`tests/fixtures/collision_pybullet_NAME.json`, recorded by `record_collision.py --robot
//! NAME`): never "free" where PyBullet finds contact, against obstacles or between the links of
//! the spec's self-collision pairs; the opposite error is measured and bounded.

use edmp_core::collision::checker::{CheckConfig, DEFAULT_MARGIN, END_MARGIN, check_end, check_state, clearance};
use edmp_core::robot::Robot;
use edmp_core::robot::arms::{iiwa7, xarm6};
use edmp_core::scene::{Obstacle, Scene};
use edmp_host::formats::json::primitive;
use serde::Deserialize;

#[derive(Debug, Deserialize)]
struct Fixture {
    format: String,
    source: String,
    self_link_pairs: Vec<[String; 2]>,
    obstacle_pairs: Vec<ObstaclePair>,
    self_pairs: Vec<SelfPair>,
}

#[derive(Debug, Deserialize)]
struct ObstaclePair {
    joints: Vec<f64>,
    obstacle: serde_json::Value,
    distance: f64,
    link: Option<String>,
}

#[derive(Debug, Deserialize)]
struct SelfPair {
    joints: Vec<f64>,
    distance: f64,
    pair: Option<[String; 2]>,
}

fn fixture(text: &str) -> Fixture {
    let f: Fixture = serde_json::from_str(text).expect("fixture parses");
    assert_eq!(f.format, "edmp-collision-fixture/1");
    f
}

fn obstacle(v: &serde_json::Value, i: usize) -> Obstacle {
    primitive(v, &format!("obstacle_pairs[{i}].obstacle"))
        .map(|p| p.to_obstacle().expect("validated by the reader"))
        .expect("fixture obstacles are valid")
}

fn joints<const J: usize>(q: &[f64]) -> [f32; J] {
    assert_eq!(q.len(), J, "joints per configuration");
    core::array::from_fn(|j| q[j] as f32)
}

/// The link (URDF name) of body `b`: the body name up to its piece suffix.
fn link_of<const J: usize>(robot: &Robot<f32, J>, b: usize) -> &'static str {
    let name = robot.body_names[b];
    name.split('#').next().unwrap_or(name)
}

fn obstacles_never_missed<const J: usize>(robot: &'static Robot<f32, J>, f: &Fixture) {
    let contacts = f.obstacle_pairs.iter().filter(|p| p.distance <= 0.0).count();
    assert!(
        contacts >= 400 && f.obstacle_pairs.len() - contacts >= 400,
        "{}",
        f.source
    );
    let cfg = CheckConfig {
        self_collision: false,
        ..CheckConfig::default()
    };
    let (mut false_contact, mut worst_hidden) = (0, 0.0f32);
    for (i, pair) in f.obstacle_pairs.iter().enumerate() {
        let mut scene = Scene::<1>::new();
        scene.push(obstacle(&pair.obstacle, i)).unwrap();
        let q = joints::<J>(&pair.joints);
        let ours = check_state(robot, &scene, &q, &cfg).unwrap();
        if pair.distance <= 0.0 {
            assert!(
                ours.is_some(),
                "{} pair {i}: PyBullet finds contact ({} m, {:?}), the checker says free",
                robot.name,
                pair.distance,
                pair.link
            );
            assert!(
                check_end(robot, &scene, &q, &cfg).unwrap().is_some(),
                "{} pair {i}: check_end accepts",
                robot.name
            );
            worst_hidden = worst_hidden.max(clearance(robot, &scene, &q).unwrap());
        } else if ours.is_some() {
            false_contact += 1;
        }
    }
    let free = f.obstacle_pairs.len() - contacts;
    println!(
        "{}: obstacle pairs {contacts} contact, {free} free; false contact {false_contact} ({:.2}% of free); \
         largest hull gap where PyBullet touches {worst_hidden:e} m (END_MARGIN {END_MARGIN} m)",
        robot.name,
        100.0 * false_contact as f64 / free as f64
    );
    assert!(
        worst_hidden < DEFAULT_MARGIN,
        "{}: the margin no longer covers PyBullet's",
        robot.name
    );
    assert!(
        false_contact * 20 <= free,
        "{}: false contacts {false_contact} of {free}",
        robot.name
    );
}

fn self_contacts_never_missed<const J: usize>(robot: &'static Robot<f32, J>, f: &Fixture) {
    // The generated pair table covers exactly the links PyBullet's rule pairs.
    let mut ours: Vec<[String; 2]> = robot
        .self_pairs
        .iter()
        .map(|&(a, b)| [link_of(robot, a.into()).to_owned(), link_of(robot, b.into()).to_owned()])
        .collect();
    ours.dedup();
    let mut theirs = f.self_link_pairs.clone();
    theirs.sort();
    ours.sort();
    ours.dedup();
    assert_eq!(ours, theirs, "{}: self-collision link pairs", robot.name);

    let contacts = f.self_pairs.iter().filter(|p| p.distance <= 0.0).count();
    let scene = Scene::<1>::new();
    let mut false_contact = 0;
    for (i, s) in f.self_pairs.iter().enumerate() {
        let ours = check_state(robot, &scene, &joints::<J>(&s.joints), &CheckConfig::default()).unwrap();
        if s.distance <= 0.0 {
            assert!(
                ours.is_some(),
                "{} config {i}: PyBullet finds self-contact {:?} ({} m), the checker says free",
                robot.name,
                s.pair,
                s.distance
            );
        } else if ours.is_some() {
            false_contact += 1;
        }
    }
    let free = f.self_pairs.len() - contacts;
    println!(
        "{}: self {contacts} in contact, {free} free; false contact {false_contact} ({:.2}% of free)",
        robot.name,
        100.0 * false_contact as f64 / free.max(1) as f64
    );
    assert!(
        contacts >= 20,
        "{}: too few self-contacts recorded to test ({contacts})",
        robot.name
    );
    assert!(
        false_contact * 10 <= free,
        "{}: false self-contacts {false_contact} of {free}",
        robot.name
    );
}

#[test]
fn iiwa7_obstacle_contacts_are_never_missed() {
    obstacles_never_missed(
        &iiwa7::ROBOT,
        &fixture(include_str!("../fixtures/collision_pybullet_iiwa7.json")),
    );
}

#[test]
fn xarm6_obstacle_contacts_are_never_missed() {
    obstacles_never_missed(
        &xarm6::ROBOT,
        &fixture(include_str!("../fixtures/collision_pybullet_xarm6.json")),
    );
}

#[test]
fn iiwa7_self_contacts_are_never_missed() {
    self_contacts_never_missed(
        &iiwa7::ROBOT,
        &fixture(include_str!("../fixtures/collision_pybullet_iiwa7.json")),
    );
}

#[test]
fn xarm6_self_contacts_are_never_missed() {
    self_contacts_never_missed(
        &xarm6::ROBOT,
        &fixture(include_str!("../fixtures/collision_pybullet_xarm6.json")),
    );
}
