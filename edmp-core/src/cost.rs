//! EDMP's collision costs on a trajectory, with their hand-written adjoint.
//!
//! Every moving robot body (collision bodies not attached to the fixed root, plus the held
//! object) is replaced by the world AABB of its oriented box's 8 corners; every obstacle by the
//! world AABB of its inflated box ([`obstacle_aabb`]). Then, as in the original code:
//! - **intersection volume** (iv): `Σ ∏ max(0, overlap)` over the interior waypoints
//!   `1..H-1`, bodies and obstacles;
//! - **swept volume** (sv): the same over the `H-1` segments, each body's box on a segment
//!   being the union of its boxes at the two ends (start and goal included).
//!
//! The gradient runs backwards through the product, through the min/max that chose each AABB
//! bound (the arg-extremal corner, or the segment end that set a swept bound; ties go to the
//! first), and through [`Kinematics::adjoint`]. Waypoints whose boxes touch nothing get an
//! exact zero without running the adjoint.

use crate::error::Error;
use crate::geometry::{Aabb, CylinderBox, Inflation, box_dims, obstacle_aabb};
use crate::kinematics::{CORNERS, CornerGradient, Joints, Kinematics, forward};
use crate::robot::{BODIES, HAND_FRAME, JOINTS, PANDA};
use crate::scene::{Obstacle, Scene};
use nalgebra::{Matrix3, Vector3};

/// Which of EDMP's two costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CostKind {
    /// Intersection volume over interior waypoints ("iv").
    Intersection,
    /// Swept volume over segments ("sv").
    Swept,
}

/// Everything that selects one cost evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostConfig {
    /// iv or sv.
    pub kind: CostKind,
    /// Obstacle clearance and expansion at this step.
    pub inflation: Inflation,
    /// How cylinders are boxed.
    pub cylinder: CylinderBox,
}

/// Robot box slots per waypoint: every collision body, then the held object.
const SLOTS: usize = BODIES + 1;
const HELD: usize = BODIES;

/// The world AABBs of the robot at one waypoint, with the corner that set each bound.
#[derive(Clone, Copy, Debug)]
struct RobotBoxes {
    aabb: [Aabb; SLOTS],
    /// `[min corner per axis, max corner per axis]`.
    arg: [[[u8; 3]; 2]; SLOTS],
    active: [bool; SLOTS],
}

const EMPTY: Aabb = Aabb {
    min: Vector3::new(0.0, 0.0, 0.0),
    max: Vector3::new(0.0, 0.0, 0.0),
};

fn aabb_of(corners: &[Vector3<f32>; CORNERS]) -> (Aabb, [[u8; 3]; 2]) {
    let mut b = Aabb {
        min: corners[0],
        max: corners[0],
    };
    let mut arg = [[0u8; 3]; 2];
    for (c, p) in corners.iter().enumerate().skip(1) {
        for k in 0..3 {
            if p[k] < b.min[k] {
                b.min[k] = p[k];
                arg[0][k] = c as u8;
            }
            if p[k] > b.max[k] {
                b.max[k] = p[k];
                arg[1][k] = c as u8;
            }
        }
    }
    (b, arg)
}

/// Corners of the held object's box in the hand frame.
fn held_local_corners(held: &Obstacle, cylinder: CylinderBox) -> [Vector3<f32>; CORNERS] {
    let h = box_dims(&held.shape, cylinder) * 0.5;
    core::array::from_fn(|k| {
        let s = Vector3::new(
            if k & 1 == 1 { h.x } else { -h.x },
            if k & 2 == 2 { h.y } else { -h.y },
            if k & 4 == 4 { h.z } else { -h.z },
        );
        held.center + held.rotation * s
    })
}

fn robot_boxes(k: &Kinematics<f32>, held: Option<&[Vector3<f32>; CORNERS]>) -> RobotBoxes {
    let mut out = RobotBoxes {
        aabb: [EMPTY; SLOTS],
        arg: [[[0; 3]; 2]; SLOTS],
        active: [false; SLOTS],
    };
    for b in 0..BODIES {
        // Bodies on the fixed root (link0) never move and are not checked against obstacles.
        if PANDA.bodies[b].frame == 0 {
            continue;
        }
        (out.aabb[b], out.arg[b]) = aabb_of(&k.corners(b));
        out.active[b] = true;
    }
    if let Some(local) = held {
        let hand = &k.frames[HAND_FRAME];
        let world = local.map(|p| hand.transform_point(&p));
        (out.aabb[HELD], out.arg[HELD]) = aabb_of(&world);
        out.active[HELD] = true;
    }
    out
}

/// Intersection volume of `a` with `o` and its gradient with respect to `a`'s bounds.
fn volume_with_gradient(a: &Aabb, o: &Aabb) -> Option<(f32, Vector3<f32>, Vector3<f32>)> {
    let overlap = a.max.inf(&o.max) - a.min.sup(&o.min);
    if overlap.iter().any(|&d| d <= 0.0) {
        return None;
    }
    let volume = overlap.x * overlap.y * overlap.z;
    let others = Vector3::new(overlap.y * overlap.z, overlap.x * overlap.z, overlap.x * overlap.y);
    let d_max = Vector3::from_fn(|k, _| if a.max[k] < o.max[k] { others[k] } else { 0.0 });
    let d_min = Vector3::from_fn(|k, _| if a.min[k] > o.min[k] { -others[k] } else { 0.0 });
    Some((volume, d_min, d_max))
}

/// Gradient on the `[min, max]` bounds of each robot box at one waypoint.
type BoundGradient = [[Vector3<f32>; 2]; SLOTS];
const ZERO_BOUNDS: BoundGradient = [[Vector3::new(0.0, 0.0, 0.0); 2]; SLOTS];

/// EDMP's cost of one trajectory of `H` waypoints in `scene`. With `gradient`, also writes
/// `∂cost/∂waypoint` for every waypoint (iv: zero at the two ends; sv: the ends get theirs too,
/// the caller decides whether to apply them).
pub fn trajectory_cost<const H: usize, const N: usize>(
    scene: &Scene<N>,
    trajectory: &[Joints<f32>; H],
    config: &CostConfig,
    gradient: Option<&mut [Joints<f32>; H]>,
) -> Result<f32, Error> {
    let Inflation { clearance, expansion } = config.inflation;
    if !(clearance.is_finite() && expansion.is_finite() && clearance >= 0.0 && expansion >= 0.0) {
        return Err(Error::BadParameter);
    }
    let mut obstacles = [EMPTY; N];
    for (slot, o) in obstacles.iter_mut().zip(scene.obstacles()) {
        *slot = obstacle_aabb(o, &config.inflation, config.cylinder);
    }
    let obstacles = &obstacles[..scene.obstacles().len()];
    let held = scene.held().map(|h| held_local_corners(h, config.cylinder));

    let mut boxes = [RobotBoxes {
        aabb: [EMPTY; SLOTS],
        arg: [[[0; 3]; 2]; SLOTS],
        active: [false; SLOTS],
    }; H];
    for (b, q) in boxes.iter_mut().zip(trajectory.iter()) {
        *b = robot_boxes(&forward(q)?, held.as_ref());
    }

    let mut bounds = [ZERO_BOUNDS; H];
    let total = match config.kind {
        CostKind::Intersection => intersection(&boxes, obstacles, &mut bounds),
        CostKind::Swept => swept(&boxes, obstacles, &mut bounds),
    };
    let bounds_finite = bounds
        .iter()
        .flatten()
        .flatten()
        .all(|v| v.iter().all(|x| x.is_finite()));
    if !total.is_finite() || !bounds_finite {
        return Err(Error::Overflow);
    }

    let Some(gradient) = gradient else { return Ok(total) };
    for ((g, q), (b, bound)) in gradient
        .iter_mut()
        .zip(trajectory.iter())
        .zip(boxes.iter().zip(bounds.iter()))
    {
        *g = if bound.iter().flatten().all(|v| v.iter().all(|&x| x == 0.0)) {
            [0.0; JOINTS]
        } else {
            waypoint_gradient(&forward(q)?, b, bound, held.as_ref())?
        };
    }
    Ok(total)
}

/// Intersection volume over the interior waypoints; adds its gradient to `bounds`.
fn intersection<const H: usize>(boxes: &[RobotBoxes; H], obstacles: &[Aabb], bounds: &mut [BoundGradient; H]) -> f32 {
    let mut total = 0.0;
    let interior = boxes.iter().zip(bounds.iter_mut()).take(H.saturating_sub(1)).skip(1);
    for (robot, bound) in interior {
        for ((aabb, &active), slot) in robot.aabb.iter().zip(robot.active.iter()).zip(bound.iter_mut()) {
            if !active {
                continue;
            }
            for o in obstacles {
                if let Some((v, d_min, d_max)) = volume_with_gradient(aabb, o) {
                    total += v;
                    slot[0] += d_min;
                    slot[1] += d_max;
                }
            }
        }
    }
    total
}

/// Swept volume over the segments; adds its gradient to `bounds`, each swept bound's share
/// going to the segment end that set it (ties to the first end).
fn swept<const H: usize>(boxes: &[RobotBoxes; H], obstacles: &[Aabb], bounds: &mut [BoundGradient; H]) -> f32 {
    let mut total = 0.0;
    for w in 0..H.saturating_sub(1) {
        for (s, &active) in boxes[w].active.iter().enumerate() {
            if !active {
                continue;
            }
            let (a, b) = (&boxes[w].aabb[s], &boxes[w + 1].aabb[s]);
            let swept = a.union(b);
            for o in obstacles {
                if let Some((v, d_min, d_max)) = volume_with_gradient(&swept, o) {
                    total += v;
                    for k in 0..3 {
                        let from_min = w + usize::from(b.min[k] < a.min[k]);
                        let from_max = w + usize::from(b.max[k] > a.max[k]);
                        bounds[from_min][s][0][k] += d_min[k];
                        bounds[from_max][s][1][k] += d_max[k];
                    }
                }
            }
        }
    }
    total
}

/// Joint gradient of one waypoint from the gradient on its boxes' bounds: each bound's share
/// goes to the corner that set it, then through the FK adjoint (the held object's corners are
/// points fixed in the hand frame: `∂/∂t += g`, `∂/∂R += g·localᵀ`).
fn waypoint_gradient(
    k: &Kinematics<f32>,
    robot: &RobotBoxes,
    bound: &BoundGradient,
    held: Option<&[Vector3<f32>; CORNERS]>,
) -> Result<Joints<f32>, Error> {
    let mut corner_grad: CornerGradient<f32> = [[Vector3::zeros(); CORNERS]; BODIES];
    let mut hand = (HAND_FRAME, Vector3::zeros(), Matrix3::zeros());
    for (s, (sides, args)) in bound.iter().zip(robot.arg.iter()).enumerate() {
        for (side, arg) in sides.iter().zip(args.iter()) {
            for (axis, (&g, &corner)) in side.iter().zip(arg.iter()).enumerate() {
                if g == 0.0 {
                    continue;
                }
                let corner = usize::from(corner) % CORNERS;
                if let Some(body) = corner_grad.get_mut(s) {
                    body[corner][axis] += g;
                } else if let Some(local) = held {
                    let mut gv = Vector3::zeros();
                    gv[axis] = g;
                    hand.1 += gv;
                    hand.2 += gv * local[corner].transpose();
                }
            }
        }
    }
    k.adjoint_with_frames(&corner_grad, &[hand])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Obstacle;

    const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];
    const READY: [f32; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

    fn config(kind: CostKind) -> CostConfig {
        CostConfig {
            kind,
            inflation: Inflation::default(),
            cylinder: CylinderBox::Enclosing,
        }
    }

    #[test]
    fn far_obstacles_cost_nothing() {
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid([3.0, 3.0, 3.0], [0.5; 3], ID).unwrap())
            .unwrap();
        let traj = [READY; 5];
        let mut g = [[1.0; 7]; 5];
        for kind in [CostKind::Intersection, CostKind::Swept] {
            assert_eq!(trajectory_cost(&scene, &traj, &config(kind), Some(&mut g)), Ok(0.0));
            assert!(g.iter().flatten().all(|&x| x == 0.0));
        }
    }

    #[test]
    fn a_box_around_the_hand_costs_and_pulls() {
        let k = forward(&READY).unwrap();
        let hand = k.frames[HAND_FRAME].translation;
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid(hand.into(), [0.1; 3], ID).unwrap())
            .unwrap();
        let traj = [READY; 4];
        let mut g = [[0.0; 7]; 4];
        let iv = trajectory_cost(&scene, &traj, &config(CostKind::Intersection), Some(&mut g)).unwrap();
        assert!(iv > 0.0);
        assert!(
            g[0].iter().chain(g[3].iter()).all(|&x| x == 0.0),
            "iv leaves start and goal alone"
        );
        assert!(g[1].iter().any(|&x| x != 0.0));
        // A stationary trajectory sweeps exactly its boxes: sv over 3 segments = iv over 2 interior waypoints × 3/2.
        let sv = trajectory_cost(&scene, &traj, &config(CostKind::Swept), None).unwrap();
        assert!((sv - iv * 1.5).abs() <= 1e-6 * sv, "{sv} vs {iv}");
    }

    #[test]
    fn rejects_bad_parameters() {
        let scene = Scene::<1>::new();
        let mut c = config(CostKind::Swept);
        c.inflation.clearance = -0.1;
        assert_eq!(trajectory_cost(&scene, &[READY; 3], &c, None), Err(Error::BadParameter));
        c.inflation.clearance = f32::NAN;
        assert_eq!(trajectory_cost(&scene, &[READY; 3], &c, None), Err(Error::BadParameter));
    }
}
