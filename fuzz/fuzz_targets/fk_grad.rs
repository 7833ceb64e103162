//! Arbitrary bytes as 7 joint angles and a corner gradient (raw f32 bits: NaN, infinities,
//! subnormals, huge values all appear). Checks that FK refuses exactly the non-finite joints,
//! that the adjoint refuses non-finite gradients and otherwise returns finite values or a typed
//! overflow, and, for joints within ±100 rad and gradients within ±1e6, that the adjoint agrees
//! with f64 central differences (`edmp_tests::check_adjoint`).
#![no_main]

use edmp_core::Error;
use edmp_core::robot::kinematics::forward;
use edmp_core::robot::{JOINTS, PANDA};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut words = data.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]));
    let mut q = [0.0f32; JOINTS];
    for slot in &mut q {
        *slot = words.next().unwrap_or(0.0);
    }
    let mut g = edmp_tests::zero_gradient();
    for body in g.iter_mut() {
        for corner in body.iter_mut() {
            for x in corner.iter_mut() {
                *x = words.next().unwrap_or(0.0);
            }
        }
    }

    let k = match forward(&PANDA, &q) {
        Ok(k) => k,
        Err(Error::NonFiniteJoint { joint }) => {
            assert!(!q[joint as usize].is_finite());
            return;
        }
        Err(e) => panic!("unexpected FK error {e:?}"),
    };
    assert!(q.iter().all(|x| x.is_finite()));
    for pose in k.frames.iter().chain(k.boxes.iter()) {
        assert!(pose.rotation.iter().chain(pose.translation.iter()).all(|x| x.is_finite()));
    }
    let grads_finite = g.iter().flatten().flat_map(|v| v.iter()).all(|x| x.is_finite());
    match k.adjoint(&g) {
        Ok(dq) => {
            assert!(grads_finite);
            assert!(dq.iter().all(|x| x.is_finite()));
        }
        Err(Error::NonFiniteGradient) => assert!(!grads_finite),
        Err(Error::Overflow) => assert!(grads_finite),
        Err(e) => panic!("unexpected adjoint error {e:?}"),
    }
    let tame_joints = q.iter().all(|x| x.abs() <= 100.0);
    let tame_grads = g.iter().flatten().flat_map(|v| v.iter()).all(|x| x.abs() <= 1e6);
    if tame_joints && tame_grads {
        if let Err(msg) = edmp_tests::check_adjoint(&q, &g) {
            panic!("adjoint disagrees with finite differences: {msg}");
        }
    }
});
