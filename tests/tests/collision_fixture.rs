//! The exact checker against PyBullet 3.2.7 (`tests/fixtures/collision_pybullet.json`):
//! never "free" where PyBullet finds contact; the opposite error is measured and bounded.

use edmp_core::collision::checker::{
    CheckConfig, DEFAULT_MARGIN, END_MARGIN, PYBULLET_HULL_MARGIN, check_end, check_state, clearance,
};
use edmp_core::scene::{Obstacle, Scene};
use edmp_host::formats::json::primitive;
use serde::Deserialize;

#[derive(Debug, Deserialize)]
struct Fixture {
    format: String,
    source: String,
    obstacle_pairs: Vec<ObstaclePair>,
    self_pairs: Vec<SelfPair>,
}

#[derive(Debug, Deserialize)]
struct ObstaclePair {
    joints: [f64; 7],
    obstacle: serde_json::Value,
    distance: f64,
    link: Option<String>,
}

#[derive(Debug, Deserialize)]
struct SelfPair {
    joints: [f64; 7],
    distance: f64,
    pair: Option<[String; 2]>,
}

/// A fixture obstacle, written as an `edmp-scene/1` primitive: read by the scene reader.
fn obstacle(v: &serde_json::Value, i: usize) -> Obstacle {
    primitive(v, &format!("obstacle_pairs[{i}].obstacle"))
        .map(|p| p.to_obstacle().expect("validated by the reader"))
        .expect("fixture obstacles are valid")
}

fn fixture() -> Fixture {
    serde_json::from_str(include_str!("../fixtures/collision_pybullet.json")).expect("fixture parses")
}

fn q32(q: &[f64; 7]) -> [f32; 7] {
    q.map(|x| x as f32)
}

#[test]
fn obstacle_contacts_are_never_missed() {
    let f = fixture();
    assert_eq!(f.format, "edmp-collision-fixture/1");
    let contacts = f.obstacle_pairs.iter().filter(|p| p.distance <= 0.0).count();
    assert!(f.obstacle_pairs.len() >= 2000 && contacts >= 900, "{}", f.source);
    let cfg = CheckConfig {
        self_collision: false,
        ..CheckConfig::default()
    };
    let (mut false_contact, mut false_contact_beyond_1cm, mut worst_hidden) = (0, 0, 0.0f32);
    for (i, pair) in f.obstacle_pairs.iter().enumerate() {
        let mut scene = Scene::<1>::new();
        scene.push(obstacle(&pair.obstacle, i)).unwrap();
        let q = q32(&pair.joints);
        let ours = check_state(&edmp_core::robot::PANDA, &scene, &q, &cfg).unwrap();
        if pair.distance <= 0.0 {
            assert!(
                ours.is_some(),
                "pair {i}: PyBullet finds contact ({} m, {:?}), the checker says free",
                pair.distance,
                pair.link
            );
            // How far apart our hulls look where PyBullet touches: what the margin must cover.
            worst_hidden = worst_hidden.max(clearance(&edmp_core::robot::PANDA, &scene, &q).unwrap());
        } else if ours.is_some() {
            false_contact += 1;
            if pair.distance > 0.01 {
                false_contact_beyond_1cm += 1;
            }
        }
    }
    let free = f.obstacle_pairs.len() - contacts;
    println!(
        "obstacle pairs: {contacts} contact, {free} free; false contact {false_contact} ({:.2}% of free), \
         {false_contact_beyond_1cm} of them farther than 1 cm; largest hull gap where PyBullet touches {worst_hidden:e} m \
         (margin {DEFAULT_MARGIN} m)",
        100.0 * false_contact as f64 / free as f64
    );
    assert!(worst_hidden < DEFAULT_MARGIN, "the margin no longer covers PyBullet's");
    // Conservative by design, but not blind: the hull-exact checker should rarely cry wolf.
    assert!(false_contact * 20 <= free, "false contacts: {false_contact} of {free}");
}

#[test]
fn self_contacts_are_never_missed() {
    let f = fixture();
    let contacts = f.self_pairs.iter().filter(|p| p.distance <= 0.0).count();
    assert!(f.self_pairs.len() >= 1000 && contacts >= 100);
    let scene = Scene::<1>::new();
    let mut false_contact = 0;
    for (i, s) in f.self_pairs.iter().enumerate() {
        let ours = check_state(
            &edmp_core::robot::PANDA,
            &scene,
            &q32(&s.joints),
            &CheckConfig::default(),
        )
        .unwrap();
        if s.distance <= 0.0 {
            assert!(
                ours.is_some(),
                "config {i}: PyBullet finds self-contact {:?} ({} m), the checker says free",
                s.pair,
                s.distance
            );
        } else if ours.is_some() {
            false_contact += 1;
        }
    }
    let free = f.self_pairs.len() - contacts;
    println!(
        "self: {contacts} in contact, {free} free; false contact {false_contact} ({:.2}% of free)",
        100.0 * false_contact as f64 / free as f64
    );
    assert!(
        false_contact * 10 <= free,
        "false self-contacts: {false_contact} of {free}"
    );
}

/// The valid-end rule (docs/formats.md): a start or goal PyBullet finds free must be accepted,
/// one it finds touching never. Measures how far PyBullet inflates our hulls (certified distance
/// minus PyBullet's, near contact) and what `check_end` does on every pair within 2 mm.
#[test]
fn ends_follow_pybullets_own_rule() {
    let f = fixture();
    let cfg = CheckConfig {
        self_collision: false,
        ..CheckConfig::default()
    };
    let (mut near_free, mut refused, mut widest) = (0, 0, 0.0f64);
    for (i, pair) in f.obstacle_pairs.iter().enumerate() {
        let mut scene = Scene::<1>::new();
        scene.push(obstacle(&pair.obstacle, i)).unwrap();
        let q = q32(&pair.joints);
        let ours = check_end(&edmp_core::robot::PANDA, &scene, &q, &cfg).unwrap();
        if pair.distance <= 0.0 {
            assert!(
                ours.is_some(),
                "pair {i}: PyBullet touches ({} m), check_end accepts",
                pair.distance
            );
        }
        let gap = f64::from(clearance(&edmp_core::robot::PANDA, &scene, &q).unwrap());
        if gap > 0.0 && pair.distance.abs() < 0.01 {
            widest = widest.max(gap - pair.distance);
        }
        if pair.distance > 0.0 && pair.distance < 0.002 {
            near_free += 1;
            if ours.is_some() {
                refused += 1;
            }
        }
    }
    println!(
        "valid ends: {near_free} pairs 0-2 mm apart by PyBullet, {refused} refused by check_end; \
         our certified distance exceeds PyBullet's by at most {:.4} mm (END_MARGIN {} mm)",
        widest * 1000.0,
        END_MARGIN * 1000.0
    );
    // PyBullet's hull margin is what END_MARGIN covers, with room for f32.
    assert!(widest < f64::from(END_MARGIN) && widest > 0.9 * f64::from(PYBULLET_HULL_MARGIN));
    // The refusals left are against cylinders, whose rims PyBullet rounds (see ARCHITECTURE.md).
    assert!(refused * 10 <= near_free, "refused {refused} of {near_free}");
}
