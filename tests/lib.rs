//! Shared helpers of the workspace-level tests: the recorded fixtures and the
//! finite-difference oracle for the kinematics adjoint (also used by `fuzz/`).

use edmp_core::kinematics::{CORNERS, CornerGradient, forward};
use edmp_core::robot::{BODIES, JOINTS};
use nalgebra::Vector3;
use serde::Deserialize;

/// `tests/fixtures/fk_pybullet.json`, as recorded by `tests/fixtures/record_fk.py`.
#[derive(Debug, Deserialize)]
pub struct FkFixture {
    /// Format tag, `edmp-fk-fixture/1`.
    pub format: String,
    /// How the fixture was made.
    pub source: String,
    /// URDF link name of each pose column.
    pub links: Vec<String>,
    /// Layout of each pose.
    pub pose_layout: String,
    /// The recorded configurations.
    pub samples: Vec<FkSample>,
}

/// One configuration and the world pose of every link frame.
#[derive(Debug, Deserialize)]
pub struct FkSample {
    /// The 7 joint angles.
    pub joints: [f64; JOINTS],
    /// `x y z qw qx qy qz` per link, in `FkFixture::links` order.
    pub poses: Vec<[f64; 7]>,
}

/// Reads the committed FK fixture.
pub fn fk_fixture() -> FkFixture {
    let text = include_str!("fixtures/fk_pybullet.json");
    serde_json::from_str(text).expect("tests/fixtures/fk_pybullet.json parses")
}

/// The L1 scale of an upstream gradient, times a lever arm bound of 2 m: the size of the sum
/// of absolute terms that make up any joint gradient, so the natural unit of its rounding error.
pub fn gradient_scale(g: &CornerGradient<f32>) -> f64 {
    2.0 * g
        .iter()
        .flatten()
        .flat_map(|v| v.iter())
        .map(|x| f64::from(x.abs()))
        .sum::<f64>()
}

/// `L(q) = Σ g·corner(q)` in f64, the scalar whose gradient the adjoint computes.
fn corner_objective(q: &[f64; JOINTS], g: &CornerGradient<f32>) -> f64 {
    let k = forward(q).expect("finite joints");
    let mut total = 0.0;
    for (b, grads) in g.iter().enumerate() {
        for (corner, grad) in k.corners(b).iter().zip(grads.iter()) {
            total += corner.dot(&grad.cast::<f64>());
        }
    }
    total
}

/// Central finite differences of [`corner_objective`] in f64, step `h`.
pub fn finite_difference(q: &[f64; JOINTS], g: &CornerGradient<f32>, h: f64) -> [f64; JOINTS] {
    core::array::from_fn(|i| {
        let (mut plus, mut minus) = (*q, *q);
        plus[i] += h;
        minus[i] -= h;
        (corner_objective(&plus, g) - corner_objective(&minus, g)) / (2.0 * h)
    })
}

/// Relative tolerance of the f32 adjoint against the f64 finite difference, in units of
/// [`gradient_scale`]. f32 keeps 2⁻²⁴ ≈ 6e-8 relative; the chain composes 13 frames and the
/// sweep sums ≤ 88 corner moments, so a few hundred ulps of the absolute-term sum (≈ 1e-5)
/// bounds the honest error while a wrong sign, axis or lever arm misses by order 1.
pub const ADJOINT_REL_TOL: f64 = 1e-5;

/// Compares the f32 adjoint with f64 central differences; `Err` describes the worst joint.
pub fn check_adjoint(q: &[f32; JOINTS], g: &CornerGradient<f32>) -> Result<(), String> {
    let k = forward(q).map_err(|e| format!("forward: {e}"))?;
    let adjoint = k.adjoint(g).map_err(|e| format!("adjoint: {e}"))?;
    let q64 = q.map(f64::from);
    let fd = finite_difference(&q64, g, 1e-6);
    let tol = ADJOINT_REL_TOL * gradient_scale(g) + 1e-12;
    for i in 0..JOINTS {
        let err = (f64::from(adjoint[i]) - fd[i]).abs();
        if err > tol {
            return Err(format!(
                "joint {i}: adjoint {} vs finite difference {} (|err| {err:e} > tol {tol:e})",
                adjoint[i], fd[i]
            ));
        }
    }
    Ok(())
}

/// A corner gradient with every entry zero.
pub fn zero_gradient() -> CornerGradient<f32> {
    [[Vector3::zeros(); CORNERS]; BODIES]
}
