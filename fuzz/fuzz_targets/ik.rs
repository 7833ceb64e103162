//! Arbitrary poses, preferred configurations, scenes and settings through `ik::solve` (a small,
//! fuzzed budget). A solution must be finite, within the soft limits, within the tolerances and
//! free by `check_end` at the asked clearance; errors must match the input (`BadConfig` for bad
//! settings, `BadInput` for a non-finite or non-orthonormal target or preferred configuration).
#![no_main]

#[path = "common.rs"]
mod common;

use common::{Reader, finite, scene};
use edmp_core::collision::checker::{CheckConfig, check_end};
use edmp_core::robot::ik::{IkConfig, IkError, solve};
use edmp_core::robot::kinematics::Pose;
use edmp_core::robot::PANDA;
use edmp_core::scene::rotation_from_wxyz;
use libfuzzer_sys::fuzz_target;
use nalgebra::{Matrix3, Vector3};

fuzz_target!(|data: &[u8]| {
    let mut r = Reader(data);
    let scene = scene::<4>(&mut r);
    let flags = r.byte();
    let rotation = if flags & 1 == 0 {
        let q = r.array::<4>();
        let n = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        rotation_from_wxyz(q.map(|v| v / n)).unwrap_or_else(|_| Matrix3::identity())
    } else {
        Matrix3::from_iterator(r.array::<9>())
    };
    let translation = Vector3::from(r.array::<3>().map(|v| if flags & 2 == 0 { v / 4.0 } else { v }));
    let target = Pose { rotation, translation };
    let preferred = r.array::<7>();
    let tame = flags & 4 == 0;
    let tol = |r: &mut Reader, default: f32| if tame { default } else { r.raw() };
    let config = IkConfig {
        starts: u16::from(r.byte() % 6),
        iterations: u16::from(r.byte() % 40),
        max_solutions: u16::from(r.byte() % 3),
        position_tolerance: tol(&mut r, 1e-4),
        rotation_tolerance: tol(&mut r, 1e-3),
        damping: tol(&mut r, 0.02),
        clearance: tol(&mut r, 0.00101),
    };
    let sane = config.starts > 0
        && config.iterations > 0
        && config.max_solutions > 0
        && config.damping.is_finite()
        && config.damping >= 0.0
        && config.clearance.is_finite()
        && config.clearance >= 0.0
        && config.position_tolerance > 0.0
        && config.rotation_tolerance > 0.0;
    let target_ok = finite(rotation.as_slice())
        && finite(translation.as_slice())
        && (rotation.transpose() * rotation - Matrix3::identity()).norm() < 1e-3;
    match solve(&edmp_core::robot::PANDA, &target, &preferred, &scene, &config) {
        Ok(s) => {
            assert!(sane && target_ok && finite(&preferred));
            assert!(finite(&s.joints) && s.position_error.is_finite() && s.rotation_error.is_finite());
            assert!(PANDA.within_soft_limits(&s.joints, 0.0), "{:?}", s.joints);
            assert!(s.position_error <= config.position_tolerance && s.rotation_error <= config.rotation_tolerance);
            assert!(s.starts_tried >= 1 && s.starts_tried <= config.starts);
            let check = CheckConfig { end_margin: config.clearance, ..CheckConfig::default() };
            assert_eq!(check_end(&edmp_core::robot::PANDA, &scene, &s.joints, &check), Ok(None));
        }
        Err(IkError::BadConfig) => assert!(!sane),
        Err(IkError::BadInput) => assert!(sane && !(target_ok && finite(&preferred))),
        Err(IkError::NoSolution) => assert!(sane && target_ok && finite(&preferred)),
        Err(e) => panic!("unexpected IK error {e:?}"),
    }
});
