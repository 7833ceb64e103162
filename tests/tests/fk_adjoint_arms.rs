//! Property tests of the arms without a gripper (iiwa 7, xArm 6): the hand-written FK adjoint
//! against f64 central differences, as `fk_adjoint.rs` does for the Panda.
//!
//! `CornerGradient` has a row per body of the largest arm compiled in (`MAX_BODIES`); the
//! gradients drawn here fill only the rows of the arm's own bodies, the rest stay zero.

use edmp_core::robot::Robot;
use edmp_core::robot::arms::{iiwa7, xarm6};
use edmp_core::robot::kinematics::{CORNERS, CornerGradient, forward};
use edmp_tests::{ADJOINT_REL_TOL, gradient_scale};
use nalgebra::Vector3;
use proptest::prelude::*;

fn zero_gradient() -> CornerGradient<f32> {
    core::array::from_fn(|_| [Vector3::zeros(); CORNERS])
}

fn joints_within_limits<const J: usize>(robot: &'static Robot<f32, J>) -> impl Strategy<Value = [f32; J]> {
    let ranges: Vec<_> = (0..J).map(|i| robot.soft_lower[i]..=robot.soft_upper[i]).collect();
    ranges.prop_map(|v| core::array::from_fn(|i| v[i]))
}

fn any_joints<const J: usize>() -> impl Strategy<Value = [f32; J]> {
    proptest::collection::vec(-10.0f32..=10.0, J).prop_map(|v| core::array::from_fn(|i| v[i]))
}

/// A gradient on every corner of the arm's `bodies` bodies, zero beyond.
fn corner_gradient(bodies: usize) -> impl Strategy<Value = CornerGradient<f32>> {
    proptest::collection::vec(-1.0f32..=1.0, bodies * CORNERS * 3).prop_map(|v| {
        let mut g = zero_gradient();
        for (i, x) in v.into_iter().enumerate() {
            g[i / (CORNERS * 3)][(i / 3) % CORNERS][i % 3] = x;
        }
        g
    })
}

/// `L(q) = Σ g·corner(q)` over the arm's bodies, in f64.
fn corner_objective<const J: usize>(robot: &'static Robot<f64, J>, q: &[f64; J], g: &CornerGradient<f32>) -> f64 {
    let k = forward(robot, q).expect("finite joints");
    let mut total = 0.0;
    for (b, grads) in g.iter().enumerate().take(robot.bodies.len()) {
        for (corner, grad) in k.corners(b).iter().zip(grads.iter()) {
            total += corner.dot(&grad.cast::<f64>());
        }
    }
    total
}

/// Central finite differences of [`corner_objective`], step `h`.
fn finite_difference<const J: usize>(
    robot: &'static Robot<f64, J>,
    q: &[f64; J],
    g: &CornerGradient<f32>,
    h: f64,
) -> [f64; J] {
    core::array::from_fn(|i| {
        let (mut plus, mut minus) = (*q, *q);
        plus[i] += h;
        minus[i] -= h;
        (corner_objective(robot, &plus, g) - corner_objective(robot, &minus, g)) / (2.0 * h)
    })
}

/// The f32 adjoint against f64 central differences, within `ADJOINT_REL_TOL` × gradient scale.
fn check_adjoint<const J: usize>(
    robot: &'static Robot<f32, J>,
    robot_f64: &'static Robot<f64, J>,
    q: &[f32; J],
    g: &CornerGradient<f32>,
) -> Result<(), TestCaseError> {
    let k = forward(robot, q).map_err(|e| TestCaseError::fail(format!("forward: {e}")))?;
    let adjoint = k.adjoint(g).map_err(|e| TestCaseError::fail(format!("adjoint: {e}")))?;
    let fd = finite_difference(robot_f64, &q.map(f64::from), g, 1e-6);
    let tol = ADJOINT_REL_TOL * gradient_scale(g) + 1e-12;
    for i in 0..J {
        let err = (f64::from(adjoint[i]) - fd[i]).abs();
        prop_assert!(
            err <= tol,
            "{} joint {}: adjoint {} vs finite difference {} (|err| {:e} > tol {:e})",
            robot.name,
            i,
            adjoint[i],
            fd[i],
            err,
            tol
        );
    }
    Ok(())
}

/// The f64 adjoint is exact up to the finite-difference error itself.
fn check_adjoint_f64<const J: usize>(
    robot_f64: &'static Robot<f64, J>,
    q: &[f32; J],
    g: &CornerGradient<f32>,
) -> Result<(), TestCaseError> {
    let q64 = q.map(f64::from);
    let k = forward(robot_f64, &q64).map_err(|e| TestCaseError::fail(format!("forward: {e}")))?;
    let g64: CornerGradient<f64> = g.map(|b| b.map(|v| v.cast::<f64>()));
    let adjoint = k
        .adjoint(&g64)
        .map_err(|e| TestCaseError::fail(format!("adjoint: {e}")))?;
    let fd = finite_difference(robot_f64, &q64, g, 1e-6);
    let tol = 1e-8 * gradient_scale(g) + 1e-12;
    for i in 0..J {
        prop_assert!(
            (adjoint[i] - fd[i]).abs() <= tol,
            "{} joint {}: {} vs {}",
            robot_f64.name,
            i,
            adjoint[i],
            fd[i]
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn iiwa7_adjoint_matches_finite_differences(
        q in joints_within_limits(&iiwa7::ROBOT),
        g in corner_gradient(iiwa7::BODIES),
    ) {
        check_adjoint(&iiwa7::ROBOT, &iiwa7::ROBOT_F64, &q, &g)?;
    }

    #[test]
    fn xarm6_adjoint_matches_finite_differences(
        q in joints_within_limits(&xarm6::ROBOT),
        g in corner_gradient(xarm6::BODIES),
    ) {
        check_adjoint(&xarm6::ROBOT, &xarm6::ROBOT_F64, &q, &g)?;
    }

    /// A gradient on a single body corner (sparse upstream, as the costs produce).
    #[test]
    fn adjoints_match_on_one_corner(
        q7 in joints_within_limits(&iiwa7::ROBOT),
        q6 in joints_within_limits(&xarm6::ROBOT),
        body in 0..xarm6::BODIES,
        corner in 0..CORNERS,
        dir in prop::array::uniform3(-1.0f32..=1.0),
    ) {
        let mut g = zero_gradient();
        g[body][corner] = Vector3::from(dir);
        check_adjoint(&xarm6::ROBOT, &xarm6::ROBOT_F64, &q6, &g)?;
        let mut g = zero_gradient();
        g[body % iiwa7::BODIES][corner] = Vector3::from(dir);
        check_adjoint(&iiwa7::ROBOT, &iiwa7::ROBOT_F64, &q7, &g)?;
    }

    /// Any finite angle, not only within limits.
    #[test]
    fn adjoints_match_outside_limits(
        q7 in any_joints::<7>(),
        q6 in any_joints::<6>(),
        g7 in corner_gradient(iiwa7::BODIES),
        g6 in corner_gradient(xarm6::BODIES),
    ) {
        check_adjoint(&iiwa7::ROBOT, &iiwa7::ROBOT_F64, &q7, &g7)?;
        check_adjoint(&xarm6::ROBOT, &xarm6::ROBOT_F64, &q6, &g6)?;
    }

    #[test]
    fn f64_adjoints_match_tightly(
        q7 in joints_within_limits(&iiwa7::ROBOT),
        q6 in joints_within_limits(&xarm6::ROBOT),
        g7 in corner_gradient(iiwa7::BODIES),
        g6 in corner_gradient(xarm6::BODIES),
    ) {
        check_adjoint_f64(&iiwa7::ROBOT_F64, &q7, &g7)?;
        check_adjoint_f64(&xarm6::ROBOT_F64, &q6, &g6)?;
    }
}

#[test]
fn rows_past_the_arms_bodies_are_ignored() {
    // The iiwa has fewer bodies than the largest arm: a gradient on a row past them must not
    // change its joint gradient.
    let q = [0.3f32, -0.5, 0.2, -1.0, 0.1, 0.8, 0.7];
    let mut g = zero_gradient();
    g[3][5] = Vector3::new(0.4, -0.2, 0.9);
    let k = forward(&iiwa7::ROBOT, &q).unwrap();
    let clean = k.adjoint(&g).unwrap();
    for row in g.iter_mut().skip(iiwa7::BODIES) {
        row[0] = Vector3::new(1.0, 1.0, 1.0);
    }
    assert_eq!(k.adjoint(&g).unwrap(), clean);
}

#[test]
fn a_wrong_adjoint_would_be_caught() {
    // The tolerance is not vacuous: flipping the sign of one joint's gradient fails it.
    let q = [0.3f32, -0.5, -1.2, 0.4, 0.9, 0.7];
    let mut g = zero_gradient();
    g[15][3] = Vector3::new(0.4, -0.2, 0.9);
    let k = forward(&xarm6::ROBOT, &q).unwrap();
    let mut adjoint = k.adjoint(&g).unwrap();
    let fd = finite_difference(&xarm6::ROBOT_F64, &q.map(f64::from), &g, 1e-6);
    let tol = ADJOINT_REL_TOL * gradient_scale(&g);
    assert!((f64::from(adjoint[1]) - fd[1]).abs() <= tol);
    adjoint[1] = -adjoint[1];
    assert!(
        (f64::from(adjoint[1]) - fd[1]).abs() > 100.0 * tol,
        "fd {} tol {tol}",
        fd[1]
    );
}
