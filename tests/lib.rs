//! Shared helpers of the workspace-level tests: the recorded fixtures and the
//! finite-difference oracle for the kinematics adjoint (also used by `fuzz/`).

use edmp_core::robot::kinematics::{CORNERS, CornerGradient, forward};
use edmp_core::robot::{JOINTS, MAX_BODIES, PANDA, PANDA_F64};
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
    let k = forward(&PANDA_F64, q).expect("finite joints");
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
    let k = forward(&PANDA, q).map_err(|e| format!("forward: {e}"))?;
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
    [[Vector3::zeros(); CORNERS]; MAX_BODIES]
}

/// An independent f64 re-implementation of EDMP's costs (straight from the definitions, no
/// shared code with `edmp_core::cost` beyond the f64 FK): the value, and a signature of every
/// discrete choice (arg-extremal corners, positive overlaps, swept-bound ends), so a finite
/// difference can be trusted only where the signature does not change across its stencil.
pub mod reference {
    use core::hash::{Hash, Hasher};
    use edmp_core::cost::boxes::{BoxFrame, box_dims};
    use edmp_core::cost::{CostConfig, CostKind};
    use edmp_core::robot::kinematics::forward_with;
    use edmp_core::robot::{BODIES, HAND_FRAME, JOINTS, PANDA};
    use edmp_core::scene::Scene;
    use nalgebra::Vector3;
    use std::hash::DefaultHasher;

    type Box3 = (Vector3<f64>, Vector3<f64>);

    /// The discrete choices made so far, and how close the nearest of them came to flipping.
    struct Choices {
        sig: DefaultHasher,
        margin: f64,
    }

    impl Choices {
        fn record(&mut self, choice: impl Hash, gap: f64) {
            choice.hash(&mut self.sig);
            self.margin = self.margin.min(gap.abs());
        }
    }

    fn aabb(points: &[Vector3<f64>], sig: &mut Choices) -> Box3 {
        let mut lo = points[0];
        let mut hi = points[0];
        for p in points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        for k in 0..3 {
            // Which corner is extremal (a change means a kink in the cost), and by how much.
            let amin = points.iter().position(|p| p[k] == lo[k]);
            let amax = points.iter().position(|p| p[k] == hi[k]);
            let runner_up = |best: f64, pick: Option<usize>| {
                points
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| Some(*i) != pick)
                    .map(|(_, p)| (p[k] - best).abs())
                    .fold(f64::INFINITY, f64::min)
            };
            sig.record((amin, amax), runner_up(lo[k], amin).min(runner_up(hi[k], amax)));
        }
        (lo, hi)
    }

    fn corners(center: Vector3<f64>, rot: nalgebra::Matrix3<f64>, half: Vector3<f64>) -> Vec<Vector3<f64>> {
        (0..8)
            .map(|k| {
                let s = Vector3::new(
                    if k & 1 == 1 { 1.0 } else { -1.0 },
                    if k & 2 == 2 { 1.0 } else { -1.0 },
                    if k & 4 == 4 { 1.0 } else { -1.0 },
                );
                center + rot * s.component_mul(&half)
            })
            .collect()
    }

    /// Every moving robot box's 8 world corners at `q` (bodies off the root, then the held object).
    fn robot_corners(q: &[f64; JOINTS], scene: &Scene<16>, cfg: &CostConfig) -> Vec<Vec<Vector3<f64>>> {
        // The scene's finger opening (in f64, from the scene's f32) places the finger boxes.
        let k = forward_with(&edmp_core::robot::PANDA_F64, q, f64::from(scene.gripper()))
            .expect("finite, opening validated");
        let mut out = Vec::new();
        for b in 0..BODIES {
            if PANDA.bodies[b].frame == 0 {
                continue;
            }
            out.push(k.corners(b).to_vec());
        }
        if let Some(h) = scene.held() {
            let half = box_dims(&h.shape, cfg.cylinder).cast::<f64>() * 0.5;
            let hand = &k.frames[HAND_FRAME];
            let local = corners(h.center.cast(), h.rotation.cast(), half);
            out.push(local.iter().map(|p| hand.transform_point(p)).collect());
        }
        out
    }

    /// An obstacle as the cost compares it: a frame (world → frame coordinates) and its box there.
    struct Costed {
        /// The frame's axes (columns) and origin in the world.
        axes: nalgebra::Matrix3<f64>,
        origin: Vector3<f64>,
        bounds: Box3,
    }

    fn costed(o: &edmp_core::scene::Obstacle, cfg: &CostConfig) -> Costed {
        let dims = box_dims(&o.shape, cfg.cylinder)
            .cast::<f64>()
            .map(|d| d.max(f64::from(cfg.inflation.expansion)) + f64::from(cfg.inflation.clearance));
        match cfg.frame {
            BoxFrame::World => {
                let pts = corners(o.center.cast(), o.rotation.cast(), dims * 0.5);
                let mut lo = pts[0];
                let mut hi = pts[0];
                for p in &pts {
                    lo = lo.inf(p);
                    hi = hi.sup(p);
                }
                Costed {
                    axes: nalgebra::Matrix3::identity(),
                    origin: Vector3::zeros(),
                    bounds: (lo, hi),
                }
            }
            BoxFrame::Obstacle => Costed {
                axes: o.rotation.cast(),
                origin: o.center.cast(),
                bounds: (-dims * 0.5, dims * 0.5),
            },
        }
    }

    /// The AABB, in the obstacle's frame, of a box given by its world corners.
    fn boxed_in(corners: &[Vector3<f64>], o: &Costed, sig: &mut Choices) -> Box3 {
        let local: Vec<Vector3<f64>> = corners.iter().map(|p| o.axes.transpose() * (p - o.origin)).collect();
        aabb(&local, sig)
    }

    fn volume(a: &Box3, o: &Box3, sig: &mut Choices) -> f64 {
        let d = a.1.inf(&o.1) - a.0.sup(&o.0);
        let positive = d.iter().all(|&x| x > 0.0);
        // Where the boxes are apart, only the axis closest to touching matters.
        let gap = if positive {
            d.min()
        } else {
            d.iter().map(|x| -x).fold(0.0f64, f64::max)
        };
        sig.record(positive, gap);
        if !positive {
            return 0.0;
        }
        for k in 0..3 {
            sig.record(
                (a.1[k] < o.1[k], a.0[k] > o.0[k]),
                (a.1[k] - o.1[k]).abs().min((a.0[k] - o.0[k]).abs()),
            );
        }
        d.x * d.y * d.z
    }

    /// A cost evaluation: value, signature of its discrete choices, and the smallest gap by
    /// which any choice was made (metres): a finite difference is trusted only away from kinks.
    #[derive(Clone, Copy, Debug)]
    pub struct Evaluation {
        /// The cost.
        pub value: f64,
        /// Hash of every discrete choice.
        pub signature: u64,
        /// Smallest gap of any choice.
        pub margin: f64,
    }

    /// Evaluates the cost of `trajectory`.
    pub fn cost(scene: &Scene<16>, trajectory: &[[f64; JOINTS]], cfg: &CostConfig) -> Evaluation {
        let mut sig = Choices {
            sig: DefaultHasher::new(),
            margin: f64::INFINITY,
        };
        let obstacles: Vec<Costed> = scene.obstacles().iter().map(|o| costed(o, cfg)).collect();
        let bodies: Vec<Vec<Vec<Vector3<f64>>>> = trajectory.iter().map(|q| robot_corners(q, scene, cfg)).collect();
        let h = trajectory.len();
        let mut total = 0.0;
        match cfg.kind {
            CostKind::Intersection => {
                for w in bodies.iter().take(h - 1).skip(1) {
                    for body in w {
                        for o in &obstacles {
                            let b = boxed_in(body, o, &mut sig);
                            total += volume(&b, &o.bounds, &mut sig);
                        }
                    }
                }
            }
            CostKind::Swept => {
                for pair in bodies.windows(2) {
                    for (ca, cb) in pair[0].iter().zip(pair[1].iter()) {
                        for o in &obstacles {
                            let (a, b) = (boxed_in(ca, o, &mut sig), boxed_in(cb, o, &mut sig));
                            for k in 0..3 {
                                sig.record(
                                    (b.0[k] < a.0[k], b.1[k] > a.1[k]),
                                    (b.0[k] - a.0[k]).abs().min((b.1[k] - a.1[k]).abs()),
                                );
                            }
                            let swept = (a.0.inf(&b.0), a.1.sup(&b.1));
                            total += volume(&swept, &o.bounds, &mut sig);
                        }
                    }
                }
            }
            // Not one of EDMP's box costs: its GJK gaps have no f64 twin here; the core's own
            // tests check it (finite differences, descent, segments through thin boards).
            CostKind::Clearance => panic!("reference::cost models EDMP's box costs, not CostKind::Clearance"),
        }
        Evaluation {
            value: total,
            signature: sig.sig.finish(),
            margin: sig.margin,
        }
    }
}

/// Position (metres) and rotation (radians) error of an f32 pose against a recorded PyBullet
/// pose `[x, y, z, qw, qx, qy, qz]` (the FK fixtures' layout).
pub fn pose_errors(got: &edmp_core::robot::kinematics::Pose<f32>, recorded: &[f64]) -> (f64, f64) {
    let expected_pos = Vector3::new(recorded[0], recorded[1], recorded[2]);
    let quat = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        recorded[3],
        recorded[4],
        recorded[5],
        recorded[6],
    ));
    let expected_rot = *quat.to_rotation_matrix().matrix();
    let position = (got.translation.cast::<f64>() - expected_pos).norm();
    // Angle of aᵀb from its skew part: well conditioned for the tiny angles measured here.
    let d = got.rotation.cast::<f64>().transpose() * expected_rot;
    let v = Vector3::new(d[(2, 1)] - d[(1, 2)], d[(0, 2)] - d[(2, 0)], d[(1, 0)] - d[(0, 1)]) * 0.5;
    let cos = (d.trace() - 1.0) * 0.5;
    (position, v.norm().atan2(cos))
}
