//! EDMP's collision costs on a trajectory, with their hand-written adjoint.
//!
//! Every moving robot body (collision bodies not attached to the fixed root, plus the held
//! object) is replaced by the world AABB of its oriented box's 8 corners (for the robot's
//! boxes computed directly as `centre ± |R|·half`); every obstacle by the
//! world AABB of its inflated box ([`obstacle_aabb`]). Then, as in the original code:
//! - **intersection volume** (iv): `Σ ∏ max(0, overlap)` over the interior waypoints
//!   `1..H-1`, bodies and obstacles;
//! - **swept volume** (sv): the same over the `H-1` segments, each body's box on a segment
//!   being the union of its boxes at the two ends (start and goal included).
//!
//! The gradient runs backwards through the product, through the min/max that chose each AABB
//! bound (the arg-extremal corner, or the segment end that set a swept bound; ties go to the
//! first), onto that corner as a point moving with its frame ([`Cotangent::add_point`]), and
//! through [`Kinematics::joint_gradient`]. Waypoints whose boxes touch nothing get an exact
//! zero without running the adjoint.

use crate::error::Error;
use crate::geometry::{Aabb, CylinderBox, Inflation, box_dims, obstacle_aabb};
use crate::kinematics::{CORNERS, Cotangent, Joints, Kinematics, Pose, box_corner, forward};
use crate::robot::{BODIES, HAND_FRAME, JOINTS, PANDA};
use crate::scene::{Obstacle, Scene};
use nalgebra::Vector3;

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

/// World AABB of an oriented box, `centre ± |R|·half`, with the corners that set its bounds:
/// along world axis `k` the highest corner takes `+half_j` exactly where `R[k][j] > 0`.
fn box_aabb(pose: &Pose<f32>, half: &Vector3<f32>) -> (Aabb, [[u8; 3]; 2]) {
    let r = &pose.rotation;
    let reach = r.abs() * half;
    let mut arg = [[0u8; 3]; 2];
    for k in 0..3 {
        let high = u8::from(r[(k, 0)] > 0.0) | u8::from(r[(k, 1)] > 0.0) << 1 | u8::from(r[(k, 2)] > 0.0) << 2;
        arg[1][k] = high;
        arg[0][k] = !high & 0b111;
    }
    (
        Aabb {
            min: pose.translation - reach,
            max: pose.translation + reach,
        },
        arg,
    )
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
        (out.aabb[b], out.arg[b]) = box_aabb(&k.boxes[b], &PANDA.bodies[b].half_extents);
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
    if overlap.x <= 0.0 || overlap.y <= 0.0 || overlap.z <= 0.0 {
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

/// One waypoint on its way through the cost: its kinematics and boxes, and the gradient its
/// boxes' bounds have collected so far (`touched` once anything was added).
#[derive(Clone, Copy, Debug)]
struct Waypoint {
    k: Kinematics<f32>,
    boxes: RobotBoxes,
    union: Aabb,
    bound: BoundGradient,
    touched: bool,
}

impl Waypoint {
    fn new(k: Kinematics<f32>, held: Option<&[Vector3<f32>; CORNERS]>) -> Self {
        let boxes = robot_boxes(&k, held);
        let mut union: Option<Aabb> = None;
        for (b, _) in boxes.aabb.iter().zip(boxes.active.iter()).filter(|(_, a)| **a) {
            union = Some(union.map_or(*b, |u| u.union(b)));
        }
        Self {
            k,
            boxes,
            union: union.unwrap_or(EMPTY),
            bound: ZERO_BOUNDS,
            touched: false,
        }
    }
}

/// EDMP's cost of one trajectory of `H` waypoints in `scene`. With `gradient`, also writes
/// `∂cost/∂waypoint` for every waypoint (iv: zero at the two ends; sv: the ends get theirs too,
/// the caller decides whether to apply them).
///
/// One streaming pass: each waypoint's FK runs once, and its gradient is finished as soon as
/// the last segment that touches it has been costed, so memory does not grow with `H`.
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
    // Refuse bad input before any work, so the error names it whatever comes later.
    for q in trajectory {
        if let Some(joint) = q.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFiniteJoint { joint: joint as u8 });
        }
    }
    let mut obstacles = [EMPTY; N];
    for (slot, o) in obstacles.iter_mut().zip(scene.obstacles()) {
        *slot = obstacle_aabb(o, &config.inflation, config.cylinder);
        // Finite but huge sizes or inflation can overflow the box (and 0·∞ make it NaN).
        if !(slot.min.iter().chain(slot.max.iter()).all(|x| x.is_finite())) {
            return Err(Error::Overflow);
        }
    }
    let obstacles = &obstacles[..scene.obstacles().len()];
    let held = scene.held().map(|h| held_local_corners(h, config.cylinder));

    let mut gradient = gradient;
    let mut total = 0.0f32;
    let mut previous: Option<Waypoint> = None;
    for (w, q) in trajectory.iter().enumerate() {
        let mut current = Waypoint::new(forward(q)?, held.as_ref());
        match (config.kind, previous.as_mut()) {
            (CostKind::Intersection, _) if w > 0 && w + 1 < H => total += intersection(&mut current, obstacles),
            (CostKind::Swept, Some(before)) => total += swept(before, &mut current, obstacles),
            _ => {}
        }
        if let Some(done) = previous.replace(current) {
            finish(&done, w - 1, gradient.as_deref_mut(), held.as_ref())?;
        }
    }
    if let Some(done) = previous {
        finish(&done, H - 1, gradient, held.as_ref())?;
    }
    if total.is_finite() {
        Ok(total)
    } else {
        Err(Error::Overflow)
    }
}

/// Writes waypoint `w`'s joint gradient once its bounds are final.
fn finish<const H: usize>(
    done: &Waypoint,
    w: usize,
    gradient: Option<&mut [Joints<f32>; H]>,
    held: Option<&[Vector3<f32>; CORNERS]>,
) -> Result<(), Error> {
    let Some(slot) = gradient.and_then(|g| g.get_mut(w)) else {
        return Ok(());
    };
    *slot = if done.touched {
        // Finite inputs whose volumes' gradients overflowed are an overflow, not bad input.
        waypoint_gradient(done, held).map_err(|e| match e {
            Error::NonFiniteGradient => Error::Overflow,
            other => other,
        })?
    } else {
        [0.0; JOINTS]
    };
    Ok(())
}

/// Whether two boxes overlap with positive volume.
fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    let (lo, hi) = (a.min.sup(&b.min), a.max.inf(&b.max));
    hi.x > lo.x && hi.y > lo.y && hi.z > lo.z
}

/// Intersection volume of one interior waypoint's boxes; adds its gradient to the waypoint.
fn intersection(w: &mut Waypoint, obstacles: &[Aabb]) -> f32 {
    let mut total = 0.0;
    for o in obstacles.iter().filter(|o| overlaps(&w.union, o)) {
        for s in 0..SLOTS {
            if !w.boxes.active[s] {
                continue;
            }
            if let Some((v, d_min, d_max)) = volume_with_gradient(&w.boxes.aabb[s], o) {
                total += v;
                w.bound[s][0] += d_min;
                w.bound[s][1] += d_max;
                w.touched = true;
            }
        }
    }
    total
}

/// Swept volume of the segment between two waypoints; each swept bound's share of the
/// gradient goes to the end that set it (ties to the first end).
fn swept(a: &mut Waypoint, b: &mut Waypoint, obstacles: &[Aabb]) -> f32 {
    let mut total = 0.0;
    let union = a.union.union(&b.union);
    for o in obstacles.iter().filter(|o| overlaps(&union, o)) {
        for s in 0..SLOTS {
            if !a.boxes.active[s] {
                continue;
            }
            let (box_a, box_b) = (a.boxes.aabb[s], b.boxes.aabb[s]);
            if let Some((v, d_min, d_max)) = volume_with_gradient(&box_a.union(&box_b), o) {
                total += v;
                for k in 0..3 {
                    let min_end = if box_b.min[k] < box_a.min[k] { &mut *b } else { &mut *a };
                    min_end.bound[s][0][k] += d_min[k];
                    min_end.touched = true;
                    let max_end = if box_b.max[k] > box_a.max[k] { &mut *b } else { &mut *a };
                    max_end.bound[s][1][k] += d_max[k];
                    max_end.touched = true;
                }
            }
        }
    }
    total
}

/// Joint gradient of one waypoint from the gradient on its boxes' bounds: each bound's share
/// pulls on the corner that set it, a point moving with the body's frame (the held object's
/// with the hand), and the FK adjoint takes it to the joints.
fn waypoint_gradient(w: &Waypoint, held: Option<&[Vector3<f32>; CORNERS]>) -> Result<Joints<f32>, Error> {
    let mut cot = Cotangent::new();
    for (s, (sides, args)) in w.bound.iter().zip(w.boxes.arg.iter()).enumerate() {
        for (side, arg) in sides.iter().zip(args.iter()) {
            for (axis, (&g, &corner)) in side.iter().zip(arg.iter()).enumerate() {
                if g == 0.0 {
                    continue;
                }
                let corner = usize::from(corner) % CORNERS;
                let (frame, point) = match (PANDA.bodies.get(s), held) {
                    (Some(body), _) => (body.frame, box_corner(&w.k.boxes[s], &body.half_extents, corner)),
                    (None, Some(local)) => (HAND_FRAME, w.k.frames[HAND_FRAME].transform_point(&local[corner])),
                    (None, None) => continue,
                };
                let mut pull = Vector3::zeros();
                pull[axis] = g;
                cot.add_point(frame, &point, &pull);
            }
        }
    }
    w.k.joint_gradient(&cot)
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
    fn a_bad_joint_is_named_even_after_an_overflow() {
        // Found by the `costs` fuzz target: with finite but huge inflation the overflow used to
        // be reported before the NaN at waypoint 3 was reached.
        let mut scene = Scene::<1>::new();
        scene.push(Obstacle::cuboid([0.0; 3], [0.1; 3], ID).unwrap()).unwrap();
        let mut traj = [READY; 5];
        let mut c = config(CostKind::Intersection);
        c.inflation = Inflation {
            clearance: 3e38,
            expansion: 3e38,
        };
        assert_eq!(
            trajectory_cost(&scene, &traj, &c, Some(&mut [[0.0; 7]; 5])),
            Err(Error::Overflow)
        );
        traj[3][2] = f32::NAN;
        assert_eq!(
            trajectory_cost(&scene, &traj, &c, Some(&mut [[0.0; 7]; 5])),
            Err(Error::NonFiniteJoint { joint: 2 })
        );
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
