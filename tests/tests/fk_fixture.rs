//! FK against PyBullet 3.2.7 (`tests/fixtures/fk_pybullet.json`, 500 configurations).

use edmp_core::robot::kinematics::forward;
use edmp_core::robot::{FRAME_NAMES, FRAMES};
use edmp_tests::fk_fixture;
use nalgebra::Vector3;

/// Budgets: position 1e-5 m, rotation 1e-5 rad (the issue's), for the f32 planner FK.
const POSITION_TOL: f64 = 1e-5;
const ROTATION_TOL: f64 = 1e-5;

#[test]
fn fk_matches_pybullet_for_every_recorded_configuration() {
    let fixture = fk_fixture();
    assert_eq!(fixture.format, "edmp-fk-fixture/1");
    assert!(fixture.samples.len() >= 500, "{}", fixture.source);
    assert_eq!(
        fixture.links, FRAME_NAMES,
        "fixture links must be the generated frame order ({})",
        fixture.pose_layout
    );
    let (mut worst_pos, mut worst_rot) = (0.0f64, 0.0f64);
    for (n, sample) in fixture.samples.iter().enumerate() {
        let q = sample.joints.map(|x| x as f32);
        let k = forward(&edmp_core::robot::PANDA, &q).expect("finite joints");
        assert_eq!(sample.poses.len(), FRAMES);
        for (f, pose) in sample.poses.iter().enumerate() {
            let (pos_err, rot_err) = edmp_tests::pose_errors(&k.frames[f], pose);
            assert!(
                pos_err <= POSITION_TOL,
                "sample {n} {}: position off by {pos_err:e} m",
                FRAME_NAMES[f]
            );
            assert!(
                rot_err <= ROTATION_TOL,
                "sample {n} {}: rotation off by {rot_err:e} rad",
                FRAME_NAMES[f]
            );
            worst_pos = worst_pos.max(pos_err);
            worst_rot = worst_rot.max(rot_err);
        }
    }
    println!("worst position error {worst_pos:e} m, worst rotation error {worst_rot:e} rad");
}

#[test]
fn f64_fk_matches_pybullet_to_recording_precision() {
    // The f64 instance (the finite-difference oracle) must be right too. PyBullet is the floor
    // here: it keeps URDF origins in f32 (panda_link1's fixed origin reads z = 0.3330000043,
    // which is 0.333 rounded to f32), so its poses are good to ~1e-7 m; worst seen 1.14e-7.
    let fixture = fk_fixture();
    let mut worst = 0.0f64;
    for sample in &fixture.samples {
        let k = forward(&edmp_core::robot::PANDA_F64, &sample.joints).expect("finite joints");
        for (f, pose) in sample.poses.iter().enumerate() {
            let err = (k.frames[f].translation - Vector3::new(pose[0], pose[1], pose[2])).norm();
            assert!(err < 2e-7, "{}: {err:e}", FRAME_NAMES[f]);
            worst = worst.max(err);
        }
    }
    println!("f64: worst position error {worst:e} m");
}
