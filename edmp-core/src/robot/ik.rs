//! Inverse kinematics for any arm: a TCP pose to joints within the planning limits,
//! collision-free, closest to a given configuration.
//!
//! Damped least squares on the TCP Jacobian ([`Kinematics::tcp_jacobian`](crate::robot::kinematics::Kinematics::tcp_jacobian)) from a fixed list
//! of starts: the preferred configuration first, then a Halton sequence over the soft limits,
//! so the answer is deterministic and the work is bounded (`starts × iterations` FK and 6×6
//! solves at most). The spread starts also find the separate branches (elbow up or down, wrist
//! flipped) of an arm without redundancy, such as a 6-joint one. Each iterate is projected back into the limits; a converged solution is
//! kept only if the exact checker finds it free in the scene (by default PyBullet's rule for
//! valid ends, `checker::END_MARGIN`), the fingers at the scene's opening
//! ([`Scene::gripper`]; the TCP itself does not depend on it, so the descent runs at the default
//! opening). Of the solutions found, the one
//! nearest the preferred configuration (Euclidean, joint space) wins.

use crate::collision::checker::{CheckConfig, END_MARGIN, check_end};
use crate::error::Error;
use crate::robot::kinematics::{Pose, forward};
use crate::robot::{JOINTS, Robot};
use crate::scene::Scene;
use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};

/// Settings of the solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkConfig {
    /// How many starts to try at most (the preferred configuration counts as one).
    pub starts: u16,
    /// Damped-least-squares iterations per start.
    pub iterations: u16,
    /// Stop after this many distinct solutions (then pick the nearest).
    pub max_solutions: u16,
    /// Accepted TCP position error (metres).
    pub position_tolerance: f32,
    /// Accepted TCP orientation error (radians).
    pub rotation_tolerance: f32,
    /// Damping λ of `Jᵀ(JJᵀ + λ²I)⁻¹`.
    pub damping: f32,
    /// Clearance from obstacles a solution must keep (metres): [`END_MARGIN`], PyBullet's own
    /// rule for valid ends, by default; generators that want roomier problems ask for more.
    pub clearance: f32,
}

impl Default for IkConfig {
    fn default() -> Self {
        Self {
            starts: 64,
            iterations: 100,
            max_solutions: 4,
            position_tolerance: 1e-4,
            rotation_tolerance: 1e-3,
            damping: 0.02,
            clearance: END_MARGIN,
        }
    }
}

/// A solution and what it cost to find, for an arm of `J` joints (the Panda's 7 by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkSolution<const J: usize = JOINTS> {
    /// Joints within the planning limits, collision-free in the scene.
    pub joints: [f32; J],
    /// Remaining TCP position error (metres).
    pub position_error: f32,
    /// Remaining TCP orientation error (radians).
    pub rotation_error: f32,
    /// Starts run before the search stopped (at `max_solutions` solutions or out of starts).
    pub starts_tried: u16,
}

/// Why no solution came back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum IkError {
    /// The target or the preferred configuration holds a NaN or an infinity, or the target
    /// rotation is not orthonormal.
    BadInput,
    /// No start converged to a free configuration within the limits.
    NoSolution,
    /// The settings are out of range.
    BadConfig,
}

impl core::fmt::Display for IkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::BadInput => "target pose or preferred configuration is not valid",
            Self::NoSolution => "no collision-free configuration within the limits reaches the pose",
            Self::BadConfig => "inverse kinematics settings are out of range",
        })
    }
}

impl core::error::Error for IkError {}

/// Orientation error `ω` with `R_target = exp([ω]×)·R`: axis times angle, in the world frame.
pub fn rotation_error(target: &Matrix3<f32>, current: &Matrix3<f32>) -> Vector3<f32> {
    let e = target * current.transpose();
    let v = Vector3::new(e[(2, 1)] - e[(1, 2)], e[(0, 2)] - e[(2, 0)], e[(1, 0)] - e[(0, 1)]) * 0.5;
    let sin = crate::float::sqrt(v.norm_squared());
    let cos = ((e.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let angle = libm::atan2f(sin, cos);
    if sin > 1e-6 {
        return v * (angle / sin);
    }
    if cos > 0.0 {
        return v; // tiny angle: sin θ ≈ θ
    }
    // Half a turn: the axis is the column of (E + I)/2 with the largest diagonal.
    let b = (e + Matrix3::identity()) * 0.5;
    let k = if b[(0, 0)] >= b[(1, 1)] && b[(0, 0)] >= b[(2, 2)] {
        0
    } else if b[(1, 1)] >= b[(2, 2)] {
        1
    } else {
        2
    };
    let axis = b.column(k).into_owned();
    let n = crate::float::sqrt(axis.norm_squared());
    if n > 0.0 {
        axis * (core::f32::consts::PI / n)
    } else {
        Vector3::zeros()
    }
}

/// The `i`-th point of the Halton sequence in base `base`, in [0, 1).
fn halton(mut i: u32, base: u32) -> f32 {
    let (mut f, mut r) = (1.0f32, 0.0f32);
    while i > 0 {
        f /= base as f32;
        r += f * (i % base) as f32;
        i /= base;
    }
    r
}

/// One Halton base per joint (arms of up to 8 joints get distinct ones).
const PRIMES: [u32; 8] = [2, 3, 5, 7, 11, 13, 17, 19];

/// Start `n`: the preferred configuration for 0, else Halton point `n` scaled to the limits.
fn start<const J: usize>(robot: &Robot<f32, J>, n: u16, preferred: &[f32; J]) -> [f32; J] {
    if n == 0 {
        return clamp(robot, preferred);
    }
    core::array::from_fn(|j| {
        let (lo, hi) = (robot.soft_lower[j], robot.soft_upper[j]);
        lo + (hi - lo) * halton(u32::from(n), PRIMES[j % PRIMES.len()])
    })
}

fn clamp<const J: usize>(robot: &Robot<f32, J>, q: &[f32; J]) -> [f32; J] {
    core::array::from_fn(|j| crate::float::clamp(q[j], robot.soft_lower[j], robot.soft_upper[j]))
}

fn valid_target(target: &Pose<f32>) -> bool {
    let finite = target
        .rotation
        .iter()
        .chain(target.translation.iter())
        .all(|x| x.is_finite());
    finite && (target.rotation.transpose() * target.rotation - Matrix3::identity()).norm() < 1e-3
}

/// One damped-least-squares descent from `q`; the converged configuration and its errors.
fn descend<const J: usize>(
    robot: &'static Robot<f32, J>,
    target: &Pose<f32>,
    mut q: [f32; J],
    config: &IkConfig,
) -> Result<Option<IkSolution<J>>, Error> {
    for _ in 0..config.iterations {
        let k = forward(robot, &q)?;
        let tcp = k.tcp();
        let dp = target.translation - tcp.translation;
        let dw = rotation_error(&target.rotation, &tcp.rotation);
        let (pe, re) = (
            crate::float::sqrt(dp.norm_squared()),
            crate::float::sqrt(dw.norm_squared()),
        );
        if pe <= config.position_tolerance && re <= config.rotation_tolerance {
            return Ok(Some(IkSolution {
                joints: q,
                position_error: pe,
                rotation_error: re,
                starts_tried: 0,
            }));
        }
        let rows = k.tcp_jacobian();
        let jac = SMatrix::<f32, 6, J>::from_fn(|r, c| rows[r][c]);
        let err = Vector6::new(dp.x, dp.y, dp.z, dw.x, dw.y, dw.z);
        let lambda2 = config.damping * config.damping;
        let jjt: Matrix6<f32> = jac * jac.transpose() + Matrix6::identity() * lambda2;
        let Some(chol) = jjt.cholesky() else { return Ok(None) };
        let step = jac.transpose() * chol.solve(&err);
        // Keep steps modest so the linearisation holds; then stay inside the limits.
        let largest = step.amax();
        let scale = if largest > 0.5 { 0.5 / largest } else { 1.0 };
        q = clamp(robot, &core::array::from_fn(|j| q[j] + step[j] * scale));
    }
    Ok(None)
}

/// Solves for joints that put the TCP at `target`, within the soft limits and collision-free
/// in `scene` (pass an empty scene to check self-collision only), nearest `preferred`.
pub fn solve<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    target: &Pose<f32>,
    preferred: &[f32; J],
    scene: &Scene<N>,
    config: &IkConfig,
) -> Result<IkSolution<J>, IkError> {
    let sane = config.starts > 0
        && config.iterations > 0
        && config.max_solutions > 0
        && config.damping.is_finite()
        && config.damping >= 0.0
        && config.clearance.is_finite()
        && config.clearance >= 0.0
        && config.position_tolerance > 0.0
        && config.rotation_tolerance > 0.0;
    if !sane {
        return Err(IkError::BadConfig);
    }
    if !valid_target(target) || !preferred.iter().all(|x| x.is_finite()) {
        return Err(IkError::BadInput);
    }
    let check = CheckConfig {
        end_margin: config.clearance,
        ..CheckConfig::default()
    };
    let mut best: Option<(f32, IkSolution<J>)> = None;
    let (mut found, mut tried) = (0u16, 0u16);
    for n in 0..config.starts {
        tried = n + 1;
        let Ok(Some(solution)) = descend(robot, target, start(robot, n, preferred), config) else {
            continue;
        };
        if !matches!(check_end(robot, scene, &solution.joints, &check), Ok(None)) {
            continue;
        }
        let distance: f32 = solution
            .joints
            .iter()
            .zip(preferred.iter())
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        if best.is_none_or(|(d, _)| distance < d) {
            best = Some((distance, solution));
        }
        found += 1;
        if found >= config.max_solutions {
            break;
        }
    }
    best.map(|(_, s)| IkSolution {
        starts_tried: tried,
        ..s
    })
    .ok_or(IkError::NoSolution)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::PANDA;

    #[test]
    fn rotation_error_is_axis_times_angle() {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3).into_inner();
        let w = rotation_error(&r, &Matrix3::identity());
        assert!((w - Vector3::new(0.0, 0.0, 0.3)).norm() < 1e-6, "{w}");
        let half = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), core::f32::consts::PI).into_inner();
        let w = rotation_error(&half, &Matrix3::identity());
        assert!(
            (w.norm() - core::f32::consts::PI).abs() < 1e-5 && w.x.abs() > 3.0,
            "{w}"
        );
    }

    #[test]
    #[cfg_attr(miri, ignore = "IK: up to 6,400 iterations and the checker: too slow")]
    fn finds_the_ready_pose_again() {
        let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        let target = *forward(&PANDA, &ready).unwrap().tcp();
        let preferred = [0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.5];
        let s = solve(
            &crate::robot::PANDA,
            &target,
            &preferred,
            &Scene::<1>::new(),
            &IkConfig::default(),
        )
        .unwrap();
        let tcp = *forward(&PANDA, &s.joints).unwrap().tcp();
        assert!((tcp.translation - target.translation).norm() < 1e-3);
        assert!(rotation_error(&target.rotation, &tcp.rotation).norm() < 0.5f32.to_radians());
        assert!(PANDA.within_soft_limits(&s.joints, 0.0));
    }

    #[test]
    #[cfg_attr(miri, ignore = "IK: up to 6,400 iterations and the checker: too slow")]
    fn unreachable_and_bad_targets_are_errors() {
        let far = Pose {
            rotation: Matrix3::identity(),
            translation: Vector3::new(3.0, 0.0, 0.5),
        };
        let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        let quick = IkConfig {
            starts: 4,
            ..IkConfig::default()
        };
        assert_eq!(
            solve(&crate::robot::PANDA, &far, &ready, &Scene::<1>::new(), &quick),
            Err(IkError::NoSolution)
        );
        let skew = Pose {
            rotation: Matrix3::identity() * 2.0,
            translation: Vector3::zeros(),
        };
        assert_eq!(
            solve(&crate::robot::PANDA, &skew, &ready, &Scene::<1>::new(), &quick),
            Err(IkError::BadInput)
        );
        let zero = IkConfig {
            starts: 0,
            ..IkConfig::default()
        };
        assert_eq!(
            solve(&crate::robot::PANDA, &far, &ready, &Scene::<1>::new(), &zero),
            Err(IkError::BadConfig)
        );
    }
}
