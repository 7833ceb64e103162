//! EDMP's collision costs on a trajectory, with their hand-written adjoint.
//!
//! Every moving robot body (collision bodies not attached to the fixed root, plus the held
//! object) is an oriented box; every obstacle the box of its inflated primitive. Each (body,
//! obstacle) pair is compared in one frame ([`BoxFrame`]): the obstacle's own (default; the
//! obstacle box is exact there and the body's box is boxed along its axes as
//! `centre ± |R|·half`) or the world's (the original code: both become world AABBs). Then, as
//! in the original code:
//! - **intersection volume** (iv): `Σ ∏ max(0, overlap)` over the interior waypoints
//!   `1..H-1`, bodies and obstacles;
//! - **swept volume** (sv): the same over the `H-1` segments, each body's box on a segment
//!   being the union of its boxes at the two ends (start and goal included).
//!
//! The gradient runs backwards through the product, through the min/max that chose each box
//! bound (the arg-extremal corner, or the segment end that set a swept bound; ties go to the
//! first), onto that corner as a point moving with its frame ([`Cotangent::add_point`]), and
//! through [`Kinematics::joint_gradient`]. Waypoints whose boxes touch nothing get an exact
//! zero without running the adjoint.
//!
//! The narrow phase's small functions are inlined by force on the host (the `costs` bench: a
//! third less time per evaluation); not on a Cortex-M, where the larger loop kept a bounds
//! check, and so a panic path, that the compiler proves away in the functions apart.

pub mod boxes;
pub mod clearance;
pub mod cover;

use crate::cost::boxes::{Aabb, BoxFrame, CylinderBox, Inflation, box_dims, inflated_dims, obstacle_aabb};
use crate::error::Error;
use crate::robot::kinematics::{CORNERS, Cotangent, Joints, Kinematics, Pose, box_corner, forward_into};
use crate::robot::{MAX_BODIES, MAX_FRAMES, Robot};
use crate::scene::{Obstacle, Scene};
use nalgebra::{Matrix3, Vector3};

/// Which of EDMP's two costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CostKind {
    /// Intersection volume over interior waypoints ("iv").
    Intersection,
    /// Swept volume over segments ("sv").
    Swept,
    /// The exact clearance of the checker's hulls from the true obstacles over the segments,
    /// within the inflation's clearance ([`crate::cost::clearance`]; not EDMP's: an
    /// ablation of the stronger local optimizer). Expansion, cylinder boxes and frame do not
    /// apply.
    Clearance,
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
    /// The frame each pair is boxed in.
    pub frame: BoxFrame,
}

/// Robot box slots per waypoint: every collision body of the largest arm compiled in, then the
/// held object (slot `robot.bodies.len()`: right after the arm's own bodies).
const SLOTS: usize = MAX_BODIES + 1;

/// One bit per slot.
type SlotMask = u32;
const _: () = assert!(SLOTS <= SlotMask::BITS as usize);

/// One obstacle as the costs see it: a frame and the inflated box in it, and a ball holding
/// that box (broad phase).
#[derive(Clone, Copy, Debug)]
struct ObstacleBox {
    /// The frame's axes in world coordinates (columns); `None`: the world's own.
    axes: Option<Matrix3<f32>>,
    /// The frame's origin in the world.
    origin: Vector3<f32>,
    /// The box in that frame.
    bounds: Aabb,
    /// The box's world AABB (broad phase).
    world: Aabb,
}

impl ObstacleBox {
    fn new(o: &Obstacle, config: &CostConfig) -> Self {
        match config.frame {
            BoxFrame::World => {
                let bounds = obstacle_aabb(o, &config.inflation, config.cylinder);
                Self {
                    axes: None,
                    origin: Vector3::zeros(),
                    bounds,
                    world: bounds,
                }
            }
            BoxFrame::Obstacle => {
                let half = inflated_dims(o, &config.inflation, config.cylinder) * 0.5;
                Self {
                    axes: Some(o.rotation),
                    origin: o.center,
                    bounds: Aabb { min: -half, max: half },
                    world: obstacle_aabb(o, &config.inflation, config.cylinder),
                }
            }
        }
    }

    fn is_finite(&self) -> bool {
        let v = [
            self.bounds.min,
            self.bounds.max,
            self.origin,
            self.world.min,
            self.world.max,
        ];
        v.iter().flat_map(|x| x.iter()).all(|x| x.is_finite())
            && self.axes.is_none_or(|a| a.iter().all(|x| x.is_finite()))
    }

    /// A world point in the frame.
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn local(&self, p: &Vector3<f32>) -> Vector3<f32> {
        match &self.axes {
            Some(a) => a.transpose() * (p - self.origin),
            None => *p,
        }
    }

    /// Whether a robot box centred at `c` (in the frame) with `|half| = radius` may reach the
    /// box along axis `k`: its AABB's half extent on any axis is at most `radius`.
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn apart_on(&self, c: &Vector3<f32>, radius: f32, k: usize) -> bool {
        c[k] - radius > self.bounds.max[k] || c[k] + radius < self.bounds.min[k]
    }

    /// World direction of the frame's axis `k`.
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn axis(&self, k: usize) -> Vector3<f32> {
        // Constant column indices: no run-time bounds check (and no panic path) in nalgebra.
        match (&self.axes, k) {
            (Some(a), 0) => a.column(0).into_owned(),
            (Some(a), 1) => a.column(1).into_owned(),
            (Some(a), _) => a.column(2).into_owned(),
            (None, 0) => Vector3::x(),
            (None, 1) => Vector3::y(),
            (None, _) => Vector3::z(),
        }
    }
}

/// One robot box at one waypoint.
#[derive(Clone, Copy, Debug)]
struct RobotBox {
    pose: Pose<f32>,
    half: Vector3<f32>,
    /// `|half|`: the box's AABB in any frame has half extents of at most this.
    radius: f32,
    active: bool,
}

const IDLE: RobotBox = RobotBox {
    pose: Pose {
        rotation: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        translation: Vector3::new(0.0, 0.0, 0.0),
    },
    half: Vector3::new(0.0, 0.0, 0.0),
    radius: 0.0,
    active: false,
};

impl RobotBox {
    /// `radius` is `|half|`, computed once per cost evaluation ([`radius_of`]), not per
    /// waypoint: a square root per box and waypoint was a fifth of a plan's time on x86-64-v3,
    /// where `libm`'s `sqrtss` (not VEX-encoded) stalls among the AVX code around it.
    fn new(pose: Pose<f32>, half: Vector3<f32>, radius: f32) -> Self {
        Self {
            pose,
            half,
            radius,
            active: true,
        }
    }

    /// The box's AABB in the obstacle's frame given its centre `c` there, with the corners
    /// that set its bounds: along axis `k` the highest corner takes `+half_j` exactly where
    /// `M[k][j] > 0`.
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn aabb_in(&self, o: &ObstacleBox, c: Vector3<f32>) -> (Aabb, [[u8; 3]; 2]) {
        let r = match &o.axes {
            Some(a) => a.transpose() * self.pose.rotation,
            None => self.pose.rotation,
        };
        let reach = r.abs() * self.half;
        let mut arg = [[0u8; 3]; 2];
        for k in 0..3 {
            let high = u8::from(r[(k, 0)] > 0.0) | u8::from(r[(k, 1)] > 0.0) << 1 | u8::from(r[(k, 2)] > 0.0) << 2;
            arg[1][k] = high;
            arg[0][k] = !high & 0b111;
        }
        (
            Aabb {
                min: c - reach,
                max: c + reach,
            },
            arg,
        )
    }
}

/// `|half|`, the radius of a box's ball.
fn radius_of(half: &Vector3<f32>) -> f32 {
    crate::float::sqrt(half.norm_squared())
}

/// The held object's box in the hand frame.
fn held_local_pose(held: &Obstacle) -> Pose<f32> {
    Pose {
        rotation: held.rotation,
        translation: held.center,
    }
}

/// Intersection volume of `a` with `o` and its gradient with respect to `a`'s bounds.
#[cfg_attr(not(target_arch = "arm"), inline(always))]
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

/// One waypoint on its way through the cost: its kinematics and boxes, and the gradient its
/// boxes' corners have collected so far. Filled in place ([`Waypoint::place`]): the struct is a
/// few kilobytes and the costs' inner loop must not copy it.
#[derive(Clone, Copy, Debug)]
struct Waypoint<const J: usize> {
    k: Kinematics<f32, J>,
    boxes: [RobotBox; SLOTS],
    /// Per box, a world AABB holding its AABB in any frame, and their union (broad phase).
    balls: SlotBoxes,
    hull: Aabb,
    pulls: Pulls,
}

/// The gradient on each box's corners (world vectors). Bit `s` of `touched` is set once
/// anything was added to slot `s`; the corners of an untouched slot are stale, not zero, so
/// that placing a waypoint does not clear a kilobyte it mostly never reads.
#[derive(Clone, Copy, Debug)]
struct Pulls {
    corners: [[Vector3<f32>; CORNERS]; SLOTS],
    touched: SlotMask,
}

const NO_BOX: Aabb = Aabb {
    min: Vector3::new(0.0, 0.0, 0.0),
    max: Vector3::new(0.0, 0.0, 0.0),
};

impl<const J: usize> Waypoint<J> {
    /// Nothing placed yet, for `robot`.
    const fn empty(robot: &'static Robot<f32, J>) -> Self {
        Self {
            k: Kinematics {
                robot,
                frames: [IDLE.pose; MAX_FRAMES],
                boxes: [IDLE.pose; MAX_BODIES],
            },
            boxes: [IDLE; SLOTS],
            balls: SlotBoxes::EMPTY,
            hull: NO_BOX,
            pulls: Pulls {
                corners: [[Vector3::new(0.0, 0.0, 0.0); CORNERS]; SLOTS],
                touched: 0,
            },
        }
    }

    /// Places the boxes of the kinematics in `self.k` (and the held object's) and clears the
    /// gradient.
    /// `radii` holds every slot's `|half|` (the held object's last).
    fn place(&mut self, held: Option<(&Pose<f32>, Vector3<f32>)>, radii: &[f32; SLOTS]) {
        let k = &self.k;
        let robot = k.robot;
        let boxes = &mut self.boxes;
        *boxes = [IDLE; SLOTS];
        for (((slot, &radius), body), pose) in boxes.iter_mut().zip(radii).zip(robot.bodies).zip(&k.boxes) {
            // Bodies on the fixed root (link0) never move and are not checked against obstacles.
            if body.frame != 0 {
                *slot = RobotBox::new(*pose, body.half_extents, radius);
            }
        }
        let held_slot = robot.bodies.len();
        if let (Some((local, half)), Some(hand)) = (held, k.frames.get(robot.hand_frame)) {
            let pose = Pose {
                rotation: hand.rotation * local.rotation,
                translation: hand.transform_point(&local.translation),
            };
            if let (Some(slot), Some(&radius)) = (boxes.get_mut(held_slot), radii.get(held_slot)) {
                *slot = RobotBox::new(pose, half, radius);
            }
        }
        let mut hull: Option<Aabb> = None;
        self.balls = SlotBoxes::EMPTY;
        for (s, b) in boxes.iter().enumerate().filter(|(_, b)| b.active) {
            // Each AABB of the box lies in a cube of half side `radius` in its frame, so in a
            // ball of radius √3·radius.
            let r = Vector3::repeat(1.732_051 * b.radius);
            let ball = Aabb {
                min: b.pose.translation - r,
                max: b.pose.translation + r,
            };
            self.balls.set(s, &ball);
            hull = Some(hull.map_or(ball, |h| h.union(&ball)));
        }
        self.hull = hull.unwrap_or(NO_BOX);
        self.pulls.touched = 0;
    }
}

impl Pulls {
    /// Adds the gradient on one bound (axis `k` of the obstacle's frame) to the corner that set it.
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn add(&mut self, slot: usize, corner: u8, o: &ObstacleBox, k: usize, g: f32) {
        let slot = slot % SLOTS;
        if self.touched & (1 << slot) == 0 {
            self.touched |= 1 << slot;
            self.corners[slot] = [Vector3::zeros(); CORNERS];
        }
        if g != 0.0 {
            self.corners[slot][usize::from(corner) % CORNERS] += o.axis(k) * g;
        }
    }
}

/// What one evaluation of a row's cost leaves for the next one at the same [`CostConfig`]: the
/// costs' units (sv: the segments, unit `u` from waypoint `u` to `u + 1`; iv: the interior
/// waypoints) that reached no obstacle box, and the waypoints that have moved since.
///
/// A unit that reached nothing and none of whose waypoints moved a bit reaches nothing again:
/// [`trajectory_cost_memo`] skips it, and its waypoints' FK when no other unit needs them. The
/// result is the same bits as a full evaluation (such a unit adds no volume and no pull).
/// Between the guidance steps at one `t` a waypoint with a zero gradient does not move, so in
/// a cluttered scene many of a row's segments that pass near obstacles without touching them
/// are skipped (docs/benchmark.md measures what that is worth where).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostMemo {
    /// The configuration of the last evaluation; `None`: nothing is known (every unit runs).
    config: Option<CostConfig>,
    /// Bit `u`: unit `u` reached no obstacle box at the last evaluation.
    quiet: u64,
    /// Bit `w`: waypoint `w` changed since the last evaluation ([`CostMemo::moved`]).
    moved: u64,
    /// The cost the last evaluation returned (`+∞`: none yet).
    last: f32,
}

impl CostMemo {
    /// Nothing known: the next evaluation runs every unit.
    pub const NONE: Self = Self {
        config: None,
        quiet: 0,
        moved: 0,
        last: f32::INFINITY,
    };

    /// The cost the last evaluation with this memo returned (`+∞` before the first): how the
    /// refinement tells a row that still makes progress ([`crate::planner::RefineStop::stall`]).
    pub fn last_cost(&self) -> f32 {
        self.last
    }

    /// Waypoints whose bits changed since the last evaluation (bit `w`: waypoint `w`); the caller
    /// reports every change of the row it evaluates, or calls [`CostMemo::forget`].
    pub fn moved(&mut self, waypoints: u64) {
        self.moved |= waypoints;
    }

    /// Forget the last evaluation (the row or the scene changed in a way not reported).
    pub fn forget(&mut self) {
        *self = Self::NONE;
    }

    /// Whether unit `u`, whose waypoints are the bits of `span`, can be skipped.
    fn skips(&self, u: usize, span: u64) -> bool {
        u < 64 && self.quiet & (1 << u) != 0 && self.moved & span == 0
    }
}

/// EDMP's cost of one trajectory of `H` waypoints in `scene`. With `gradient`, also writes
/// `∂cost/∂waypoint` for every waypoint (iv: zero at the two ends; sv: the ends get theirs too,
/// the caller decides whether to apply them).
///
/// One streaming pass: each waypoint's FK runs once, and its gradient is finished as soon as
/// the last segment that touches it has been costed, so memory does not grow with `H`.
pub fn trajectory_cost<const H: usize, const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[Joints<f32, J>; H],
    config: &CostConfig,
    gradient: Option<&mut [Joints<f32, J>; H]>,
) -> Result<f32, Error> {
    trajectory_cost_memo(robot, scene, trajectory, config, gradient, None)
}

/// [`trajectory_cost`] that skips what `memo` shows cannot reach an obstacle box, and updates
/// `memo` for the next evaluation of the same row in the same scene. The same bits as
/// [`trajectory_cost`]. Trajectories of more than 64 waypoints are evaluated in full.
pub fn trajectory_cost_memo<const H: usize, const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[Joints<f32, J>; H],
    config: &CostConfig,
    gradient: Option<&mut [Joints<f32, J>; H]>,
    memo: Option<&mut CostMemo>,
) -> Result<f32, Error> {
    let Inflation { clearance, expansion } = config.inflation;
    if !(clearance.is_finite() && expansion.is_finite() && clearance >= 0.0 && expansion >= 0.0) {
        return Err(Error::BadParameter);
    }
    if config.kind == CostKind::Clearance {
        return crate::cost::clearance::trajectory_cost(robot, scene, trajectory, clearance, gradient);
    }
    // Refuse bad input before any work, so the error names it whatever comes later.
    for q in trajectory {
        if let Some(joint) = q.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFiniteJoint { joint: joint as u8 });
        }
    }
    let empty = Aabb {
        min: Vector3::zeros(),
        max: Vector3::zeros(),
    };
    let mut obstacles = [ObstacleBox {
        axes: None,
        origin: Vector3::zeros(),
        bounds: empty,
        world: empty,
    }; N];
    for (slot, o) in obstacles.iter_mut().zip(scene.guide_obstacles()) {
        *slot = ObstacleBox::new(o, config);
        // Finite but huge sizes or inflation can overflow the box (and 0·∞ make it NaN).
        if !slot.is_finite() {
            return Err(Error::Overflow);
        }
    }
    let obstacles = obstacles.get(..scene.guide_obstacles().len()).unwrap_or(&[]);
    let held = scene
        .held()
        .map(|h| (held_local_pose(h), box_dims(&h.shape, config.cylinder) * 0.5));
    let held = held.as_ref().map(|(pose, half)| (pose, *half));
    let mut radii = [0.0f32; SLOTS];
    for (r, body) in radii.iter_mut().zip(robot.bodies.iter()) {
        *r = radius_of(&body.half_extents);
    }
    if let Some(r) = radii.get_mut(robot.bodies.len()) {
        *r = held.map_or(0.0, |(_, half)| radius_of(&half));
    }

    // What the last evaluation of this row left: only for the same configuration.
    let memo = memo.filter(|_| H <= 64);
    let known = match &memo {
        Some(m) if m.config == Some(*config) => **m,
        _ => CostMemo::NONE,
    };
    let swept_kind = config.kind == CostKind::Swept;
    // The units: sv segment `u` joins waypoints `u` and `u + 1`; iv unit `u` is interior waypoint `u`.
    let is_unit = |u: usize| u + 1 < H && (swept_kind || u > 0);
    let runs = |u: usize| -> bool {
        // A unit beyond bit 63 has no memo bits (and a memo only holds for H ≤ 64).
        let span = if swept_kind { 0b11u64 } else { 1 }.checked_shl(u as u32).unwrap_or(0);
        is_unit(u) && !known.skips(u, span)
    };
    // Waypoint `w` is needed by the units that contain it: sv segments `w − 1` and `w`.
    let needed = |w: usize| runs(w) || (swept_kind && w > 0 && runs(w - 1));
    let mut quiet = 0u64;

    let mut gradient = gradient;
    let mut total = 0.0f32;
    // Two waypoints in flight, swapped by reference: `before` is waypoint w − 1. A waypoint no
    // unit needs is not placed (its flag is false) and its gradient is zero.
    let mut pair = [Waypoint::empty(robot); 2];
    let [before, current] = &mut pair;
    let (mut before, mut current) = (before, current);
    let mut before_placed = false;
    for (w, q) in trajectory.iter().enumerate() {
        let placed = needed(w);
        if placed {
            // The scene's finger opening places the finger boxes; for the adjoint it is a constant.
            forward_into(q, robot.finger_opening(scene.gripper()), &mut current.k)?;
            current.place(held, &radii);
        }
        // The unit that ends at this waypoint: sv the segment into it, iv the waypoint itself.
        let unit = if swept_kind { w.checked_sub(1) } else { Some(w) };
        if let Some(u) = unit.filter(|&u| is_unit(u)) {
            // A unit not run was quiet and nothing of it moved: it is quiet still.
            let hit = runs(u) && {
                let (v, hit) = if swept_kind {
                    swept(before, current, obstacles)
                } else {
                    intersection(current, obstacles)
                };
                total += v;
                hit
            };
            if !hit && u < 64 {
                quiet |= 1 << u;
            }
        }
        if w > 0 {
            finish(before, before_placed, w - 1, gradient.as_deref_mut())?;
        }
        core::mem::swap(&mut before, &mut current);
        before_placed = placed;
    }
    if H > 0 {
        finish(before, before_placed, H - 1, gradient)?;
    }
    if let Some(m) = memo {
        *m = CostMemo {
            config: Some(*config),
            quiet,
            moved: 0,
            last: total,
        };
    }
    if total.is_finite() {
        Ok(total)
    } else {
        Err(Error::Overflow)
    }
}

/// Writes waypoint `w`'s joint gradient once its corners' gradients are final.
fn finish<const H: usize, const J: usize>(
    done: &Waypoint<J>,
    placed: bool,
    w: usize,
    gradient: Option<&mut [Joints<f32, J>; H]>,
) -> Result<(), Error> {
    let Some(slot) = gradient.and_then(|g| g.get_mut(w)) else {
        return Ok(());
    };
    *slot = if placed && done.pulls.touched != 0 {
        // Finite inputs whose volumes' gradients overflowed are an overflow, not bad input.
        waypoint_gradient(done).map_err(|e| match e {
            Error::NonFiniteGradient => Error::Overflow,
            other => other,
        })?
    } else {
        [0.0; J]
    };
    Ok(())
}

/// Whether two boxes overlap with positive volume.
#[cfg_attr(not(target_arch = "arm"), inline(always))]
fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    let (lo, hi) = (a.min.sup(&b.min), a.max.inf(&b.max));
    hi.x > lo.x && hi.y > lo.y && hi.z > lo.z
}

/// Lanes of [`SlotBoxes`]: every slot, rounded up to a multiple of 8 (whole AVX registers).
const LANES: usize = SLOTS.div_ceil(8) * 8;
const _: () = assert!(SLOTS <= LANES && LANES <= SlotMask::BITS as usize);

/// One box per robot slot, as structure of arrays (a lane per slot, an array per bound and
/// axis), so that the broad phase tests every slot against one obstacle in a few vector
/// compares instead of a branch per slot. An unused lane is empty (min +∞, max −∞).
#[derive(Clone, Copy, Debug)]
struct SlotBoxes {
    min: [[f32; LANES]; 3],
    max: [[f32; LANES]; 3],
    /// Bit `s` set where lane `s` holds a box of positive volume.
    solid: SlotMask,
}

impl SlotBoxes {
    const EMPTY: Self = Self {
        min: [[f32::INFINITY; LANES]; 3],
        max: [[f32::NEG_INFINITY; LANES]; 3],
        solid: 0,
    };

    fn set(&mut self, slot: usize, b: &Aabb) {
        for k in 0..3 {
            if let (Some(lo), Some(hi)) = (self.min[k].get_mut(slot), self.max[k].get_mut(slot)) {
                (*lo, *hi) = (b.min[k], b.max[k]);
            }
        }
        let solid = b.max.x > b.min.x && b.max.y > b.min.y && b.max.z > b.min.z;
        if solid && slot < LANES {
            self.solid |= 1 << slot;
        }
    }

    /// Bit `s` set exactly where [`overlaps`] holds for slot `s`'s box and `o`: for finite
    /// bounds `min(a.max, o.max) > max(a.min, o.min)` on an axis is `a.max > o.min`,
    /// `o.max > a.min` and both boxes' own `max > min`, so the decisions (and the costs' bits)
    /// are the scalar test's.
    fn overlapping(&self, o: &Aabb) -> SlotMask {
        if !(o.max.x > o.min.x && o.max.y > o.min.y && o.max.z > o.min.z) {
            return 0;
        }
        let [lx, ly, lz] = [o.min.x, o.min.y, o.min.z];
        let [hx, hy, hz] = [o.max.x, o.max.y, o.max.z];
        let [min_x, min_y, min_z] = &self.min;
        let [max_x, max_y, max_z] = &self.max;
        let mut mask: SlotMask = 0;
        for s in 0..LANES {
            let hit = (max_x[s] > lx)
                & (hx > min_x[s])
                & (max_y[s] > ly)
                & (hy > min_y[s])
                & (max_z[s] > lz)
                & (hz > min_z[s]);
            mask |= SlotMask::from(hit) << s;
        }
        mask & self.solid
    }
}

/// The set bits of a slot mask, lowest first (the slots' order of the scalar loops).
fn slots_of(mut mask: SlotMask) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        (mask != 0).then(|| {
            let s = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            s
        })
    })
}

/// Intersection volume of one interior waypoint's boxes; adds its gradient to the waypoint.
/// Also whether any pair overlapped (added a volume and pulls).
fn intersection<const J: usize>(w: &mut Waypoint<J>, obstacles: &[ObstacleBox]) -> (f32, bool) {
    let mut total = 0.0;
    let mut hit = false;
    let Waypoint {
        boxes,
        balls,
        hull,
        pulls,
        ..
    } = w;
    for o in obstacles.iter().filter(|o| overlaps(hull, &o.world)) {
        for s in slots_of(balls.overlapping(&o.world)) {
            let Some(b) = boxes.get(s) else { continue };
            let c = o.local(&b.pose.translation);
            if (0..3).any(|k| o.apart_on(&c, b.radius, k)) {
                continue;
            }
            let (aabb, arg) = b.aabb_in(o, c);
            if let Some((v, d_min, d_max)) = volume_with_gradient(&aabb, &o.bounds) {
                total += v;
                hit = true;
                for k in 0..3 {
                    pulls.add(s, arg[0][k], o, k, d_min[k]);
                    pulls.add(s, arg[1][k], o, k, d_max[k]);
                }
            }
        }
    }
    (total, hit)
}

/// Swept volume of the segment between two waypoints; each swept bound's share of the
/// gradient goes to the end that set it (ties to the first end). Also whether any pair
/// overlapped (added a volume and pulls).
fn swept<const J: usize>(a: &mut Waypoint<J>, b: &mut Waypoint<J>, obstacles: &[ObstacleBox]) -> (f32, bool) {
    let mut total = 0.0;
    let mut hit = false;
    // In an obstacle's frame the union of the two ends' AABBs lies in a ball around the
    // midpoint of radius |ca − cb| / 2 + √3·|half| (not in the world-axis union of the ends'
    // balls: the frame may be turned).
    let mut reach = SlotBoxes::EMPTY;
    let mut hull: Option<Aabb> = None;
    for (s, (ba, bb)) in a.boxes.iter().zip(b.boxes.iter()).enumerate() {
        if !ba.active {
            continue;
        }
        let (pa, pb) = (ba.pose.translation, bb.pose.translation);
        // |pa − pb|₁ ≥ |pa − pb|: a looser ball with no square root (this runs per box and
        // segment), which only lets a few more pairs through to the exact volume.
        let d = pa - pb;
        let radius = 0.5 * (d.x.abs() + d.y.abs() + d.z.abs()) + 1.732_051 * ba.radius.max(bb.radius);
        let mid = (pa + pb) * 0.5;
        let r = Aabb {
            min: mid - Vector3::repeat(radius),
            max: mid + Vector3::repeat(radius),
        };
        reach.set(s, &r);
        hull = Some(hull.map_or(r, |h| h.union(&r)));
    }
    let Some(hull) = hull else {
        return (0.0, false);
    };
    let (boxes_a, pulls_a, boxes_b, pulls_b) = (&a.boxes, &mut a.pulls, &b.boxes, &mut b.pulls);
    for o in obstacles.iter().filter(|o| overlaps(&hull, &o.world)) {
        for s in slots_of(reach.overlapping(&o.world)) {
            let (Some(box_a), Some(box_b)) = (boxes_a.get(s), boxes_b.get(s)) else {
                continue;
            };
            let (ca, cb) = (o.local(&box_a.pose.translation), o.local(&box_b.pose.translation));
            // Both ends' AABBs beyond the box on the same side of one axis: the union is too.
            if (0..3).any(|k| {
                let (ra, rb) = (box_a.radius, box_b.radius);
                (ca[k] - ra > o.bounds.max[k] && cb[k] - rb > o.bounds.max[k])
                    || (ca[k] + ra < o.bounds.min[k] && cb[k] + rb < o.bounds.min[k])
            }) {
                continue;
            }
            let ((la, arg_a), (lb, arg_b)) = (box_a.aabb_in(o, ca), box_b.aabb_in(o, cb));
            if let Some((v, d_min, d_max)) = volume_with_gradient(&la.union(&lb), &o.bounds) {
                total += v;
                hit = true;
                for k in 0..3 {
                    if lb.min[k] < la.min[k] {
                        pulls_b.add(s, arg_b[0][k], o, k, d_min[k]);
                    } else {
                        pulls_a.add(s, arg_a[0][k], o, k, d_min[k]);
                    }
                    if lb.max[k] > la.max[k] {
                        pulls_b.add(s, arg_b[1][k], o, k, d_max[k]);
                    } else {
                        pulls_a.add(s, arg_a[1][k], o, k, d_max[k]);
                    }
                }
            }
        }
    }
    (total, hit)
}

/// Joint gradient of one waypoint from the gradient on its boxes' corners: each corner is a
/// point moving with its body's frame (the held object's with the hand), and the FK adjoint
/// takes it to the joints.
fn waypoint_gradient<const J: usize>(w: &Waypoint<J>) -> Result<Joints<f32, J>, Error> {
    let mut cot = Cotangent::new();
    for (s, (pulls, b)) in w.pulls.corners.iter().zip(w.boxes.iter()).enumerate() {
        if !b.active || w.pulls.touched & (1 << s) == 0 {
            continue;
        }
        let frame = w.k.robot.bodies.get(s).map_or(w.k.robot.hand_frame, |body| body.frame);
        for (corner, g) in pulls.iter().enumerate() {
            if *g != Vector3::zeros() {
                cot.add_point(frame, &box_corner(&b.pose, &b.half, corner), g);
            }
        }
    }
    w.k.joint_gradient(&cot)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::kinematics::forward;
    use crate::robot::{HAND_FRAME, PANDA};
    use crate::scene::Obstacle;

    const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];
    const READY: [f32; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

    fn config(kind: CostKind) -> CostConfig {
        CostConfig {
            kind,
            inflation: Inflation::default(),
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
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
            assert_eq!(
                trajectory_cost(&PANDA, &scene, &traj, &config(kind), Some(&mut g)),
                Ok(0.0)
            );
            assert!(g.iter().flatten().all(|&x| x == 0.0));
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "costs and gradient of a whole trajectory: too slow")]
    fn a_box_around_the_hand_costs_and_pulls() {
        let k = forward(&crate::robot::PANDA, &READY).unwrap();
        let hand = k.frames[HAND_FRAME].translation;
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid(hand.into(), [0.1; 3], ID).unwrap())
            .unwrap();
        let traj = [READY; 4];
        let mut g = [[0.0; 7]; 4];
        let iv = trajectory_cost(&PANDA, &scene, &traj, &config(CostKind::Intersection), Some(&mut g)).unwrap();
        assert!(iv > 0.0);
        assert!(
            g[0].iter().chain(g[3].iter()).all(|&x| x == 0.0),
            "iv leaves start and goal alone"
        );
        assert!(g[1].iter().any(|&x| x != 0.0));
        // A stationary trajectory sweeps exactly its boxes: sv over 3 segments = iv over 2 interior waypoints × 3/2.
        let sv = trajectory_cost(&PANDA, &scene, &traj, &config(CostKind::Swept), None).unwrap();
        assert!((sv - iv * 1.5).abs() <= 1e-6 * sv, "{sv} vs {iv}");
    }

    #[test]
    #[cfg_attr(miri, ignore = "costs and gradient of a whole trajectory: too slow")]
    fn the_finger_boxes_follow_the_scenes_opening() {
        // A plate between the fingers: the finger boxes overlap it only when closed.
        let k = forward(&crate::robot::PANDA, &READY).unwrap();
        let hand = &k.frames[HAND_FRAME];
        let center = hand.transform_point(&Vector3::new(0.0, 0.0, 0.095));
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid(center.into(), [0.01, 0.02, 0.02], hand.quaternion_wxyz()).unwrap())
            .unwrap();
        let traj = [READY; 4];
        let open = scene.clone().with_gripper(0.04).unwrap();
        let closed = scene.with_gripper(0.0).unwrap();
        for kind in [CostKind::Intersection, CostKind::Swept] {
            let mut g = [[1.0; 7]; 4];
            assert_eq!(
                trajectory_cost(&PANDA, &open, &traj, &config(kind), Some(&mut g)),
                Ok(0.0)
            );
            assert!(g.iter().flatten().all(|&x| x == 0.0));
            let cost = trajectory_cost(&PANDA, &closed, &traj, &config(kind), Some(&mut g)).unwrap();
            assert!(cost > 0.0, "{kind:?}");
            assert!(g.iter().flatten().any(|&x| x != 0.0), "{kind:?}");
        }
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
            trajectory_cost(&PANDA, &scene, &traj, &c, Some(&mut [[0.0; 7]; 5])),
            Err(Error::Overflow)
        );
        traj[3][2] = f32::NAN;
        assert_eq!(
            trajectory_cost(&PANDA, &scene, &traj, &c, Some(&mut [[0.0; 7]; 5])),
            Err(Error::NonFiniteJoint { joint: 2 })
        );
    }

    /// A sweep of joints 0 and 1 past three boxes, some waypoints in contact.
    fn sweep<const H: usize>() -> [Joints<f32>; H] {
        core::array::from_fn(|w| {
            let s = w as f32 / (H - 1) as f32;
            let mut q = READY;
            q[0] = -1.2 + 2.4 * s;
            q[1] = -0.785 + 0.6 * s;
            q
        })
    }

    #[test]
    #[cfg_attr(miri, ignore = "hundreds of trajectory costs: too slow")]
    fn the_memo_gives_the_bits_of_a_full_evaluation() {
        let mut scene = Scene::<4>::new();
        for (center, half) in [
            ([0.5, 0.0, 0.4], [0.05, 0.3, 0.05]),
            ([0.2, 0.45, 0.5], [0.1, 0.02, 0.2]),
            ([0.3, -0.5, 0.1], [0.2, 0.1, 0.1]),
        ] {
            scene.push(Obstacle::cuboid(center, half, ID).unwrap()).unwrap();
        }
        let mut rng = crate::rng::Rng::new(11);
        for kind in [CostKind::Intersection, CostKind::Swept] {
            let mut traj: [Joints<f32>; 16] = sweep();
            let mut memo = CostMemo::NONE;
            let mut skipped_some = false;
            for step in 0..60 {
                // Every 20 steps the inflation changes: the memo must notice by itself.
                let mut c = config(kind);
                c.inflation.clearance = 0.01 * (step / 20) as f32;
                let (mut full, mut memoed) = ([[0.0; 7]; 16], [[9.0; 7]; 16]);
                let want = trajectory_cost(&PANDA, &scene, &traj, &c, Some(&mut full)).unwrap();
                let quiet_before = memo.quiet;
                let got = trajectory_cost_memo(&PANDA, &scene, &traj, &c, Some(&mut memoed), Some(&mut memo)).unwrap();
                assert_eq!(got.to_bits(), want.to_bits(), "{kind:?} step {step}");
                let bits = |g: &[Joints<f32>; 16]| g.map(|q| q.map(f32::to_bits));
                assert_eq!(bits(&memoed), bits(&full), "{kind:?} step {step}");
                skipped_some |= quiet_before != 0 && step % 20 != 0;
                // Move a few waypoints (those with a gradient, and now and then a random one).
                let mut moved = 0u64;
                for (w, (q, g)) in traj.iter_mut().zip(&full).enumerate().skip(1).take(14) {
                    let random = rng.below(8) == 0;
                    if g.iter().any(|&v| v != 0.0) || random {
                        for (qj, gj) in q.iter_mut().zip(g) {
                            *qj -= 0.05 * gj.clamp(-1.0, 1.0) + if random { 0.01 } else { 0.0 };
                        }
                        moved |= 1 << w;
                    }
                }
                memo.moved(moved);
            }
            assert!(skipped_some, "{kind:?}: the memo never had a quiet unit to skip");
        }
    }

    /// One bar across the sweep's path.
    fn bar() -> Scene<'static, 1> {
        let mut scene = Scene::<1>::new();
        scene
            .push(Obstacle::cuboid([0.5, 0.0, 0.4], [0.05, 0.3, 0.05], ID).unwrap())
            .unwrap();
        scene
    }

    #[test]
    #[cfg_attr(miri, ignore = "trajectory costs: too slow")]
    fn a_trajectory_longer_than_the_memo_is_costed_in_full() {
        let scene = bar();
        let traj: [Joints<f32>; 70] = sweep();
        for kind in [CostKind::Intersection, CostKind::Swept] {
            let c = config(kind);
            let mut memo = CostMemo::NONE;
            let want = trajectory_cost(&PANDA, &scene, &traj, &c, None).unwrap();
            for _ in 0..2 {
                let got = trajectory_cost_memo(&PANDA, &scene, &traj, &c, None, Some(&mut memo)).unwrap();
                assert_eq!(got.to_bits(), want.to_bits(), "{kind:?}");
            }
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "trajectory costs: too slow")]
    fn a_forgotten_memo_runs_everything() {
        let scene = bar();
        let c = config(CostKind::Swept);
        let mut traj: [Joints<f32>; 8] = sweep();
        let mut memo = CostMemo::NONE;
        trajectory_cost_memo(&PANDA, &scene, &traj, &c, None, Some(&mut memo)).unwrap();
        // A change the memo is not told of, then forgotten: the full cost again.
        traj[3][0] += 0.3;
        memo.forget();
        let want = trajectory_cost(&PANDA, &scene, &traj, &c, None).unwrap();
        let got = trajectory_cost_memo(&PANDA, &scene, &traj, &c, None, Some(&mut memo)).unwrap();
        assert_eq!(got.to_bits(), want.to_bits());
    }

    #[test]
    fn rejects_bad_parameters() {
        let scene = Scene::<1>::new();
        let mut c = config(CostKind::Swept);
        c.inflation.clearance = -0.1;
        assert_eq!(
            trajectory_cost(&PANDA, &scene, &[READY; 3], &c, None),
            Err(Error::BadParameter)
        );
        c.inflation.clearance = f32::NAN;
        assert_eq!(
            trajectory_cost(&PANDA, &scene, &[READY; 3], &c, None),
            Err(Error::BadParameter)
        );
    }
}
