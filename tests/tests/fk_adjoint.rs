//! Property tests: the hand-written adjoint against f64 central differences, and the TCP
//! Jacobian against the adjoint.

use edmp_core::robot::kinematics::{CORNERS, Cotangent, forward};
use edmp_core::robot::{BODIES, JOINTS, PANDA, TCP_FRAME};
use edmp_tests::{check_adjoint, finite_difference, gradient_scale, zero_gradient};
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;

fn joints_within_soft_limits() -> impl Strategy<Value = [f32; JOINTS]> {
    let ranges: Vec<_> = (0..JOINTS).map(|i| PANDA.soft_lower[i]..=PANDA.soft_upper[i]).collect();
    ranges.prop_map(|v| core::array::from_fn(|i| v[i]))
}

fn corner_gradient() -> impl Strategy<Value = edmp_core::robot::kinematics::CornerGradient<f32>> {
    proptest::collection::vec(-1.0f32..=1.0, BODIES * CORNERS * 3).prop_map(|v| {
        let mut g = zero_gradient();
        for (i, x) in v.into_iter().enumerate() {
            g[i / (CORNERS * 3)][(i / 3) % CORNERS][i % 3] = x;
        }
        g
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// f32 adjoint vs f64 central differences, tolerance `ADJOINT_REL_TOL` × gradient scale.
    #[test]
    fn adjoint_matches_finite_differences(q in joints_within_soft_limits(), g in corner_gradient()) {
        check_adjoint(&q, &g).map_err(TestCaseError::fail)?;
    }

    /// A gradient on a single body corner (sparse upstream, as the costs produce).
    #[test]
    fn adjoint_matches_on_one_corner(
        q in joints_within_soft_limits(),
        body in 0..BODIES,
        corner in 0..CORNERS,
        dir in prop::array::uniform3(-1.0f32..=1.0),
    ) {
        let mut g = zero_gradient();
        g[body][corner] = Vector3::from(dir);
        check_adjoint(&q, &g).map_err(TestCaseError::fail)?;
    }

    /// Any finite angle, not only within limits: the kinematics are periodic, the adjoint exact.
    #[test]
    fn adjoint_matches_outside_limits(q in prop::array::uniform7(-10.0f32..=10.0), g in corner_gradient()) {
        check_adjoint(&q, &g).map_err(TestCaseError::fail)?;
    }

    /// The f64 adjoint is exact up to the finite-difference error itself (≈1e-9 relative).
    #[test]
    fn f64_adjoint_matches_tightly(q in joints_within_soft_limits(), g in corner_gradient()) {
        let q64 = q.map(f64::from);
        let k = forward(&edmp_core::robot::PANDA_F64, &q64).unwrap();
        let g64 = g.map(|b| b.map(|v| v.cast::<f64>()));
        let adjoint = k.adjoint(&g64).unwrap();
        let fd = finite_difference(&q64, &g, 1e-6);
        let tol = 1e-8 * gradient_scale(&g) + 1e-12;
        for i in 0..JOINTS {
            prop_assert!((adjoint[i] - fd[i]).abs() <= tol, "joint {}: {} vs {}", i, adjoint[i], fd[i]);
        }
    }

    /// Each row of the TCP Jacobian is the adjoint of the matching TCP pose component:
    /// position rows from `∂L/∂p = e_r`, orientation rows from `∂L/∂R = ½[e_r]×R`.
    #[test]
    fn tcp_jacobian_matches_adjoint(q in joints_within_soft_limits()) {
        let k = forward(&edmp_core::robot::PANDA, &q).unwrap();
        let jac = k.tcp_jacobian();
        let rot = k.tcp().rotation;
        for r in 0..6 {
            let mut e = Vector3::zeros();
            e[r % 3] = 1.0f32;
            let mut cot = Cotangent::new();
            if r < 3 {
                cot.add_frame(TCP_FRAME, k.tcp(), &e, &Matrix3::zeros());
            } else {
                cot.add_frame(TCP_FRAME, k.tcp(), &Vector3::zeros(), &(e.cross_matrix() * rot * 0.5));
            }
            let row = k.joint_gradient(&cot).unwrap();
            for j in 0..JOINTS {
                prop_assert!((row[j] - jac[r][j]).abs() <= 1e-5, "row {} joint {}: adjoint {} vs jacobian {}", r, j, row[j], jac[r][j]);
            }
        }
    }
}

#[test]
fn a_wrong_adjoint_would_be_caught() {
    // The tolerance is not vacuous: flipping the sign of one joint's gradient fails it.
    let q = [0.3f32, -0.5, 0.2, -2.0, 0.1, 1.8, 0.7];
    let mut g = zero_gradient();
    g[7][3] = Vector3::new(0.4, -0.2, 0.9);
    let k = forward(&edmp_core::robot::PANDA, &q).unwrap();
    let mut adjoint = k.adjoint(&g).unwrap();
    let fd = finite_difference(&q.map(f64::from), &g, 1e-6);
    let tol = edmp_tests::ADJOINT_REL_TOL * gradient_scale(&g);
    assert!((f64::from(adjoint[2]) - fd[2]).abs() <= tol);
    adjoint[2] = -adjoint[2];
    assert!(
        (f64::from(adjoint[2]) - fd[2]).abs() > 100.0 * tol,
        "fd {} tol {tol}",
        fd[2]
    );
}
