//! Inverse kinematics round trip on 1,000 reachable poses: FK of random self-collision-free
//! configurations within the soft limits, solved from the ready pose as the preferred
//! configuration. Every solution must reproduce its pose within 1 mm / 0.5° and stay in the
//! limits; the success rate is printed and bounded.

use edmp_core::collision::checker::{CheckConfig, check_state};
use edmp_core::rng::Rng;
use edmp_core::robot::PANDA;
use edmp_core::robot::ik::{IkConfig, rotation_error, solve};
use edmp_core::robot::kinematics::forward;
use edmp_core::scene::Scene;

#[test]
fn ik_round_trip_on_1000_reachable_poses() {
    let scene = Scene::<1>::new();
    let ready = [0.0f32, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    let mut rng = Rng::new(42);
    let (mut tried, mut solved, mut starts) = (0, 0, 0u32);
    while tried < 1000 {
        let q: [f32; 7] = core::array::from_fn(|j| {
            PANDA.soft_lower[j] + rng.unit_f32() * (PANDA.soft_upper[j] - PANDA.soft_lower[j])
        });
        if check_state(&edmp_core::robot::PANDA, &scene, &q, &CheckConfig::default()) != Ok(None) {
            continue; // not a valid robot state, so its pose is not a fair target
        }
        tried += 1;
        let target = *forward(&edmp_core::robot::PANDA, &q).unwrap().tcp();
        let Ok(s) = solve(&edmp_core::robot::PANDA, &target, &ready, &scene, &IkConfig::default()) else {
            continue;
        };
        let tcp = *forward(&edmp_core::robot::PANDA, &s.joints).unwrap().tcp();
        let dp = (tcp.translation - target.translation).norm();
        let dr = rotation_error(&target.rotation, &tcp.rotation).norm();
        assert!(
            dp <= 1e-3 && dr <= 0.5f32.to_radians(),
            "pose {tried}: {dp} m, {dr} rad"
        );
        assert!(PANDA.within_soft_limits(&s.joints, 0.0));
        solved += 1;
        starts += u32::from(s.starts_tried);
    }
    println!(
        "IK: {solved} of {tried} reachable poses solved ({:.1} %), {:.1} starts on average",
        100.0 * solved as f64 / tried as f64,
        starts as f64 / solved.max(1) as f64
    );
    assert!(solved >= 980, "only {solved} of {tried} solved");
}
