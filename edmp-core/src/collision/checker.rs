//! The exact collision checker: is a state, or a whole trajectory, free of contact?
//!
//! Geometry is exact, never boxed: each robot body is the convex hull of its collision mesh
//! (the same hull PyBullet collides), obstacles and the held object are true cuboids,
//! cylinders and spheres, and the balls and triangles of clouds and meshes
//! ([`crate::surface`]), found near a body through their hierarchy. A pair is declared free
//! only when a GJK separating direction *certifies* a gap larger than the margin
//! ([`crate::collision::gjk::apart`]); anything else counts as contact. Cheap tests run
//! first and can only prove freedom: bounding balls, then the body's oriented box (which holds
//! its hull).
//!
//! Checked, as docs/formats.md defines a solved problem: every moving body of the arm (for the
//! Panda: links 1-7, hand, fingers; the held object) against every obstacle, and every pair of
//! the arm's self-collision table ([`Robot::self_pairs`]; the held object counts as part of
//! the hand's link), at every waypoint and at every state of the linear joint interpolation in
//! steps of at most `max_step`. The arm is a parameter: every entry point takes its tables.

use crate::collision::convex::{Convex, Hull, Solid};
use crate::collision::gjk::{apart_by, distance_lower_bound};
use crate::error::Error;
use crate::float::sqrt_below;
use crate::robot::kinematics::{Kinematics, forward_with};
use crate::robot::reach::motion;
use crate::robot::{BODIES, MAX_BODIES, MAX_FRAMES, Robot};
use crate::scene::{Scene, Shape};
use crate::surface::Probe;
use crate::surface::element::{Aabb, Element, Piece};
use core::cmp::Ordering;
use nalgebra::{Matrix3, Vector3};

/// Clearance demanded between a robot body and an obstacle away from the ends (metres): the
/// planner's own safety margin, twice what PyBullet's inflated hulls need.
pub const DEFAULT_MARGIN: f32 = 0.002;
/// How far PyBullet 3.2.7 inflates each robot hull (its collision margin): on the recorded
/// fixtures our certified hull distance minus PyBullet's is at most 1.0004 mm (median 0.987),
/// so PyBullet calls a hull in contact exactly when its true distance is ≤ about 1 mm.
pub const PYBULLET_HULL_MARGIN: f32 = 0.001;
/// Clearance demanded between a robot body and an obstacle near the ends: PyBullet's own
/// contact rule (docs/formats.md, valid ends) plus 10 µm for the hulls' and the kinematics'
/// differences. A grasp pose 0.05 mm above a table (by PyBullet) passes; one PyBullet finds
/// touching never does.
pub const END_MARGIN: f32 = PYBULLET_HULL_MARGIN + 0.000_01;
/// Clearance demanded between two robot bodies, everywhere: both hulls are inflated, so
/// PyBullet's zero distance is about 2 mm of ours.
pub const SELF_MARGIN: f32 = 2.0 * END_MARGIN;
/// Joint-space radius (max-norm, radians) around the start and the goal inside which
/// [`END_MARGIN`] replaces [`DEFAULT_MARGIN`]: a path may leave a surface the user's end
/// touches, and must be 2 mm clear once it is this far from the end.
pub const END_RADIUS: f32 = 0.05;
/// Largest joint step between checked states (docs/formats.md).
pub const MAX_JOINT_STEP: f32 = 0.01;
/// Fixed budget of interpolated states per segment: the widest joint range (6.6 rad) at
/// 0.01 rad needs 664, so only waypoints outside the limits can exceed it.
pub const MAX_STEPS_PER_SEGMENT: u32 = 1024;
/// Index of the held object in a Panda's [`Contact`] (robot bodies use `robot::BODY_NAMES`
/// indices): [`held_body`] of the Panda.
pub const HELD_BODY: u8 = BODIES as u8;

/// Index of the held object in [`Contact`] for `robot`: the one after its bodies.
pub fn held_body<const J: usize>(robot: &Robot<f32, J>) -> u8 {
    robot.bodies.len().min(MAX_BODIES) as u8
}

/// Checker settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckConfig {
    /// Required clearance between a robot body (or the held object) and an obstacle.
    pub margin: f32,
    /// The same near the ends (states within `end_radius` of the first or last waypoint).
    pub end_margin: f32,
    /// Max-norm joint distance from an end within which `end_margin` applies.
    pub end_radius: f32,
    /// Required clearance between two robot bodies (and the held object).
    pub self_margin: f32,
    /// Largest per-joint step between checked states.
    pub max_step: f32,
    /// Check non-neighbour robot bodies against each other (on by default; off only to study
    /// obstacle contact alone).
    pub self_collision: bool,
}

impl CheckConfig {
    /// The project's definition of a solved problem (docs/formats.md).
    pub const DEFAULT: Self = Self {
        margin: DEFAULT_MARGIN,
        end_margin: END_MARGIN,
        end_radius: END_RADIUS,
        self_margin: SELF_MARGIN,
        max_step: MAX_JOINT_STEP,
        self_collision: true,
    };

    /// Every distance finite and at least 0, the step finite and above 0: else
    /// [`Error::BadParameter`].
    pub fn validate(&self) -> Result<(), Error> {
        let distance = |x: f32| x.is_finite() && x >= 0.0;
        let ok = distance(self.margin)
            && distance(self.end_margin)
            && distance(self.end_radius)
            && distance(self.self_margin)
            && self.max_step.is_finite()
            && self.max_step > 0.0;
        if ok { Ok(()) } else { Err(Error::BadParameter) }
    }
}

impl Default for CheckConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What touched.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Robot body (or [`HELD_BODY`]) `body` against obstacle `obstacle`.
    Obstacle {
        /// Body index.
        body: u8,
        /// Obstacle index in the scene.
        obstacle: u8,
    },
    /// Robot body (or [`HELD_BODY`]) `body` against a piece of a cloud or a mesh.
    Surface {
        /// Body index.
        body: u8,
        /// The piece's obstacle ([`crate::surface::element::Element::obstacle`]).
        obstacle: u16,
    },
    /// Two robot bodies that are not chain neighbours.
    SelfContact {
        /// Lower body index.
        first: u8,
        /// Higher body index (possibly [`HELD_BODY`]).
        second: u8,
    },
}

/// Where along a trajectory a contact was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateContact {
    /// Segment index (waypoint `segment` to `segment + 1`); the last waypoint is step 0 of
    /// segment `H − 1`.
    pub segment: u16,
    /// Interpolation step within the segment (0 is the waypoint itself).
    pub step: u16,
    /// What touched.
    pub contact: Contact,
}

/// The verdict on a trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TrajectoryReport {
    /// States checked (waypoints and interpolated states).
    pub states: u32,
    /// States in contact (a measure of how bad a colliding trajectory is).
    pub colliding_states: u32,
    /// The first contact, if any.
    pub first_contact: Option<StateContact>,
}

impl TrajectoryReport {
    /// No state touched anything.
    pub fn is_free(&self) -> bool {
        self.colliding_states == 0
    }
}

/// How many revolute joints lie between a frame and the root: the held object (rigid with the
/// hand's frame) is checked against the bodies two or more levels away from the hand.
fn level<const J: usize>(robot: &Robot<f32, J>, frame: usize) -> u8 {
    let mut f = frame;
    let mut joints = 0u8;
    for _ in 0..robot.frames.len() {
        let Some(spec) = robot.frames.get(f) else { break };
        if spec.joint.is_some() {
            joints = joints.saturating_add(1);
        }
        if f == 0 {
            break;
        }
        f = spec.parent;
    }
    joints
}

/// Whether robot body `b` and the held object are checked against each other.
fn held_pair<const J: usize>(robot: &Robot<f32, J>, b: usize) -> bool {
    robot
        .bodies
        .get(b)
        .is_some_and(|body| level(robot, body.frame).abs_diff(level(robot, robot.hand_frame)) >= 2)
}

/// Whether shape `body` (a robot body, or the held object after them) moves with the joints:
/// bodies with no actuated joint between them and the root (the Panda's link0, the xArm's
/// `link_base` under its `world` link) are bolted to the mount.
pub fn moves<const J: usize>(robot: &Robot<f32, J>, body: usize) -> bool {
    robot.bodies.get(body).is_none_or(|b| level(robot, b.frame) > 0)
}

const PLACEHOLDER: Solid = Solid {
    shape: Shape::Sphere { radius: 0.0 },
    rotation: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    center: Vector3::new(0.0, 0.0, 0.0),
};

/// One state's shapes, placed.
struct Placed<'a, const J: usize> {
    robot: &'static Robot<f32, J>,
    k: &'a Kinematics<f32, J>,
    held: Option<Solid>,
    /// Obstacle clearance for this state.
    margin: f32,
    /// Clearance between robot bodies.
    self_margin: f32,
}

impl<const J: usize> Placed<'_, J> {
    /// Robot body `b`'s oriented box (callers pass robot bodies only; a bad index gives a point
    /// at the origin rather than a panic).
    fn obb(&self, b: usize) -> Solid {
        let half = self
            .robot
            .bodies
            .get(b)
            .map_or(Vector3::zeros(), |body| body.half_extents);
        Solid::cuboid(&self.k.boxes[b % MAX_BODIES], &half)
    }

    fn hull(&self, b: usize) -> Hull<'_> {
        let frame = self.robot.bodies.get(b).map_or(0, |body| body.frame);
        Hull::of_body(self.robot, b, &self.k.frames[frame % MAX_FRAMES])
    }

    /// Whether shape `b` is the held object (or past it).
    fn is_held(&self, b: usize) -> bool {
        b >= self.robot.bodies.len()
    }

    /// Shape `b`'s box (a robot body's oriented box, which holds its hull; the held object's
    /// box) proven apart from solid `o`'s by more than the margin along a face normal
    /// ([`Solid::face_gap`]): the gap, `None` when no face normal proves it.
    fn boxes_apart(&self, b: usize, o: &Solid) -> Option<f32> {
        let gap = self.solid(b)?.face_gap(o);
        (gap > self.margin).then_some(gap)
    }

    /// Shape `b` as a solid: a robot body's oriented box, or the held object.
    fn solid(&self, b: usize) -> Option<Solid> {
        if self.is_held(b) { self.held } else { Some(self.obb(b)) }
    }

    /// Body `b` (robot or held) proven apart from primitive `p`: the certified gap (above the
    /// margin), `None` when it is not proven.
    fn body_apart_from<P: Convex>(&self, b: usize, p: &P, hint: &mut Vector3<f32>) -> Option<f32> {
        if self.is_held(b) {
            return match &self.held {
                Some(h) => apart_by(h, p, self.margin, hint),
                None => Some(f32::INFINITY),
            };
        }
        // The oriented box holds the hull: proving the box apart is enough, and cheap.
        apart_by(&self.obb(b), p, self.margin, hint).or_else(|| apart_by(&self.hull(b), p, self.margin, hint))
    }

    /// A cloud's ball proven clear of robot body `b`'s oriented box (which holds its hull) by
    /// more than `margin`, in closed form: the certified gap, `None` when it is not (or `p` is
    /// a triangle, or `b` the held object).
    fn ball_clear_of_box(&self, b: usize, p: &Element, margin: f32) -> Option<f32> {
        let (Piece::Ball { center, radius }, Some(body)) = (p.piece, self.robot.bodies.get(b)) else {
            return None;
        };
        let pose = &self.k.boxes[b % MAX_BODIES];
        let half = &body.half_extents;
        let local = pose.rotation.tr_mul(&(center - pose.translation));
        let outside = local.abs() - half;
        let d2 = outside.map(|x| x.max(0.0)).norm_squared();
        // The box's own rounding is far below the 0.1 % `sqrt_below` leaves.
        let gap = sqrt_below(d2) - radius;
        (gap > margin).then_some(gap)
    }

    /// Bodies `a < b` proven apart: the certified gap, as [`Placed::body_apart_from`].
    fn bodies_apart(&self, a: usize, b: usize, hint: &mut Vector3<f32>) -> Option<f32> {
        let m = self.self_margin;
        if let (Some(sa), Some(sb)) = (self.solid(a), self.solid(b)) {
            let gap = sa.face_gap(&sb);
            if gap > m {
                return Some(gap);
            }
        }
        if self.is_held(b) {
            return match &self.held {
                Some(h) => apart_by(&self.obb(a), h, m, hint).or_else(|| apart_by(&self.hull(a), h, m, hint)),
                None => Some(f32::INFINITY),
            };
        }
        apart_by(&self.obb(a), &self.obb(b), m, hint).or_else(|| apart_by(&self.hull(a), &self.hull(b), m, hint))
    }
}

/// Robot shapes per state, at most: every collision body, then the held object.
const SLOTS: usize = MAX_BODIES + 1;

/// Shape index `i` as an index into the per-shape arrays: `i` itself, which is always below
/// [`SLOTS`]; the `min` proves that to the compiler (no panic path) for a compare, where
/// `% SLOTS` (not a power of two) cost a division in the checker's hottest loops.
#[inline(always)]
fn slot(i: usize) -> usize {
    i.min(SLOTS - 1)
}
const _: () = assert!(SLOTS <= u32::BITS as usize, "one bit per shape in `Prepared::moving`");

/// The separating direction last found for each pair, carried from one state of a trajectory
/// to the next (zero: none yet).
struct Hints<const N: usize> {
    obstacle: [[Vector3<f32>; N]; SLOTS],
    /// Per shape, the direction last found against any piece of the surface.
    surface: [Vector3<f32>; SLOTS],
    body: [[Vector3<f32>; SLOTS]; SLOTS],
}

impl<const N: usize> Hints<N> {
    fn new() -> Self {
        Self {
            obstacle: [[Vector3::zeros(); N]; SLOTS],
            surface: [Vector3::zeros(); SLOTS],
            body: [[Vector3::zeros(); SLOTS]; SLOTS],
        }
    }
}

const PAIRS: usize = SLOTS * SLOTS;

/// How far two shapes can move relative to each other for joint steps `step`: a joint that
/// turns both (bit `j` of `shared`, [`joints_turning_both`]) turns them together and changes
/// nothing between them; one that turns only one moves it by its reach
/// ([`crate::robot::reach`]). Branch-free over the joints: a shared joint adds an exact zero.
fn relative_motion<const J: usize>(a: &[f32; J], b: &[f32; J], shared: u32, step: &[f32; J]) -> f32 {
    let mut m = 0.0f32;
    for (j, ((ra, rb), d)) in a.iter().zip(b).zip(step).enumerate() {
        let both = shared.checked_shr(j as u32).unwrap_or(0) & 1 == 1;
        m += if both { 0.0 } else { (ra + rb) * d };
    }
    m
}

/// Bit `j` set when joint `j` turns both shapes of reaches `a` and `b` (joints past the 32nd
/// count as turning one only: more motion, never less).
fn joints_turning_both<const J: usize>(a: &[f32; J], b: &[f32; J]) -> u32 {
    a.iter().zip(b).enumerate().fold(0u32, |mask, (j, (ra, rb))| {
        if *ra > 0.0 && *rb > 0.0 {
            mask | 1u32.checked_shl(j as u32).unwrap_or(0)
        } else {
            mask
        }
    })
}

/// How far the surface's pieces are looked for around a body: nearer pieces are proven clear
/// (a small subtree at once, or one by one), and the smallest gap found (at most this) is
/// carried to the next states.
const SURFACE_HORIZON: f32 = 0.05;

/// What a certified gap leaves for the states after it, below the gap less the margin: room for
/// the kinematics' f32 rounding (metres).
const CARRY_SLACK: f32 = 1e-4;

/// Clearance carried from one state to the next ([`crate::robot::reach`]): per pair, how far its
/// shapes may still move, together, before the gap last certified for it no longer proves the
/// margin. A pair with slack left at a state is free there without a test, and a state all of
/// whose pairs have slack left needs no kinematics.
///
/// A shape's obstacle pairs share its motion, so their slack is kept as the motion total at
/// which it runs out: a state adds the shape's motion to one total (`used`) instead of
/// subtracting it from every pair, and a shape whose total stays below the least of its pairs'
/// (`obstacle_least`) skips them all. A scene of many obstacles far from most links is then
/// a few comparisons per state.
struct Slack<const J: usize, const N: usize> {
    /// Per shape and obstacle: the shape's `used` at which the pair's slack runs out.
    obstacle: [[f32; N]; SLOTS],
    /// Per shape, at most the least of its `obstacle` entries.
    obstacle_least: [f32; SLOTS],
    /// Per shape, how far it may have moved since its entries were last rebased (kept below
    /// [`REBASE`], where f32 resolves fractions of a micrometre).
    used: [f32; SLOTS],
    /// Per shape, against the whole surface (its nearest piece).
    surface: [f32; SLOTS],
    body: [[f32; SLOTS]; SLOTS],
    /// The state the slack was last used up to; `None`: nothing carried yet.
    at: Option<[f32; J]>,
}

/// How far a shape's motion total may grow before its obstacle entries are rebased to it
/// (metres).
const REBASE: f32 = 1.0;

impl<const J: usize, const N: usize> Slack<J, N> {
    fn new() -> Self {
        Self {
            obstacle: [[0.0; N]; SLOTS],
            obstacle_least: [0.0; SLOTS],
            used: [0.0; SLOTS],
            surface: [0.0; SLOTS],
            body: [[0.0; SLOTS]; SLOTS],
            at: None,
        }
    }

    /// Shape `b` moved by `moved`: whether any of its obstacle pairs may need a test.
    fn use_obstacles(&mut self, b: usize, moved: f32, count: usize) -> bool {
        let b = slot(b);
        let used = &mut self.used[b];
        *used += moved;
        if *used > REBASE {
            let base = *used;
            for e in self.obstacle[b].iter_mut().take(count) {
                *e -= base;
            }
            self.obstacle_least[b] -= base;
            *used = 0.0;
        }
        self.obstacle_least[b].partial_cmp(used) != Some(Ordering::Greater)
    }
}

/// What stays the same for every state of one check: the obstacles and their bounding balls,
/// the robot shapes' ball radii, the self-collision pairs, and the separating directions
/// remembered so far.
struct Prepared<'s, const J: usize, const N: usize> {
    robot: &'static Robot<f32, J>,
    scene: &'s Scene<'s, N>,
    config: CheckConfig,
    obstacles: [Solid; N],
    obstacle_radius: [f32; N],
    shapes: usize,
    /// Bit `b`: shape `b` moves with the joints ([`moves`]; the walk to the root was an eighth
    /// of a state's test when it ran per state).
    moving: u32,
    radius: [f32; SLOTS],
    pairs: [(u8, u8); PAIRS],
    pair_count: usize,
    /// Per pair, the joints that turn both its shapes ([`joints_turning_both`]).
    shared: [u32; PAIRS],
    hints: Hints<N>,
    /// Per shape and joint, how far a point of the shape can be from the joint's axis.
    reach: [[f32; J]; SLOTS],
    slack: Slack<J, N>,
    /// The pair found touching last: tested first at the next state (a search's blocked steps
    /// mostly touch where the one before did).
    last: Option<Contact>,
}

impl<'s, const J: usize, const N: usize> Prepared<'s, J, N> {
    /// What a check of `scene` needs, for a `config` that passed [`CheckConfig::validate`].
    /// Not a `Result`: the firmware's stack would hold the few kilobytes of this twice (the
    /// result and the value taken out of it).
    fn new(robot: &'static Robot<f32, J>, scene: &'s Scene<'s, N>, config: &CheckConfig) -> Self {
        let obstacles: [Solid; N] =
            core::array::from_fn(|i| scene.obstacles().get(i).map_or(PLACEHOLDER, Solid::obstacle));
        let obstacle_radius = obstacles.map(|o| o.bounding_radius());
        let bodies = robot.bodies.len().min(MAX_BODIES);
        let shapes = if scene.held().is_some() { bodies + 1 } else { bodies };
        let radius = core::array::from_fn(|b| match (robot.bodies.get(b), scene.held()) {
            (Some(body), _) => crate::float::sqrt(body.half_extents.norm_squared()),
            (None, Some(h)) if b == bodies => Solid::obstacle(h).bounding_radius(),
            _ => 0.0,
        });
        // The held object's points lie within |centre| + its ball's radius of the hand's origin.
        let held_extent = scene.held().map_or(0.0, |h| {
            (crate::float::sqrt(h.center.norm_squared()) + Solid::obstacle(h).bounding_radius()) * (1.0 + 1e-5)
        });
        let reach = core::array::from_fn(|b| match robot.body_reach.get(b) {
            Some(r) => *r,
            None => robot.hand_reach.map(|r| r + held_extent),
        });
        // The arm's pairs (sorted), each body's pair with the held object after its own:
        // ascending `(a, b)`, the order contacts are looked for in.
        let mut pairs = [(0u8, 0u8); PAIRS];
        let mut pair_count = 0;
        let mut push = |pair: (u8, u8)| {
            if let Some(slot) = pairs.get_mut(pair_count) {
                *slot = pair;
                pair_count += 1;
            }
        };
        let mut next = robot.self_pairs.iter().peekable();
        for a in 0..bodies {
            while let Some(&&(x, y)) = next.peek()
                && usize::from(x) <= a
            {
                if usize::from(x) == a && usize::from(y) < bodies {
                    push((x, y));
                }
                next.next();
            }
            if scene.held().is_some() && held_pair(robot, a) {
                push((a as u8, bodies as u8));
            }
        }
        let shared = core::array::from_fn(|p| match pairs.get(p) {
            Some(&(a, b)) if p < pair_count => {
                joints_turning_both(&reach[slot(usize::from(a))], &reach[slot(usize::from(b))])
            }
            _ => 0,
        });
        let moving = (0..shapes)
            .filter(|&b| moves(robot, b))
            .fold(0u32, |mask, b| mask | 1u32.checked_shl(b as u32).unwrap_or(0));
        Self {
            robot,
            scene,
            config: *config,
            obstacles,
            obstacle_radius,
            shapes,
            moving,
            radius,
            pairs,
            pair_count,
            shared,
            hints: Hints::new(),
            reach,
            slack: Slack::new(),
            last: None,
        }
    }

    /// The first contact at configuration `q`, if any; `margin` is the obstacle clearance
    /// this state must keep.
    ///
    /// A pair whose carried slack ([`Slack`]) outlasts the motion since the last state is free
    /// here without a test; the others are tested, and a pair proven apart carries its new gap
    /// less the largest margin a state may need (`margin` or `end_margin`). Every "free" is
    /// still certified: by a separating direction at this state, or at an earlier one whose
    /// gap the motion since (bounded by [`crate::robot::reach`]) cannot have used up.
    ///
    /// The pair that touched at the last contact found is tested first: the contact reported
    /// may then be another than the walk in order would find first, the verdict is the same.
    fn contact_at(&mut self, q: &[f32; J], margin: f32) -> Result<Option<Contact>, Error> {
        let found = self.find_contact(q, margin)?;
        if found.is_some() {
            self.last = found;
        }
        Ok(found)
    }

    /// [`Prepared::contact_at`] without remembering what it found.
    fn find_contact(&mut self, q: &[f32; J], margin: f32) -> Result<Option<Contact>, Error> {
        let count = self.scene.obstacles().len();
        let surface = *self.scene.surface();
        let step: [f32; J] = match &self.slack.at {
            Some(last) => core::array::from_fn(|j| (q[j] - last[j]).abs()),
            // Nothing carried: every slack is still 0, so every pair is tested.
            None => [0.0; J],
        };
        let moved: [f32; SLOTS] =
            core::array::from_fn(|b| self.reach.get(b).map_or(f32::INFINITY, |r| motion(r, &step)));
        self.slack.at = Some(*q);
        // Use up every pair's slack; only pairs left without any are tested.
        let mut untested = false;
        let robot = self.robot;
        for b in (0..self.shapes).filter(|&b| self.moving >> b & 1 == 1) {
            untested |= self.slack.use_obstacles(b, moved[slot(b)], count);
            if !surface.is_empty() {
                let s = &mut self.slack.surface[slot(b)];
                *s -= moved[slot(b)];
                untested |= (*s).partial_cmp(&0.0) != Some(Ordering::Greater);
            }
        }
        if self.config.self_collision {
            for (&(a, b), &shared) in self.pairs.iter().zip(&self.shared).take(self.pair_count) {
                let (a, b) = (slot(usize::from(a)), slot(usize::from(b)));
                let s = &mut self.slack.body[a][b];
                *s -= relative_motion(&self.reach[a], &self.reach[b], shared, &step);
                untested |= (*s).partial_cmp(&0.0) != Some(Ordering::Greater);
            }
        }
        if !untested {
            return Ok(None);
        }
        let k = forward_with(robot, q, robot.finger_opening(self.scene.gripper()))?;
        let self_margin = self.config.self_margin;
        let carry = self.config.margin.max(self.config.end_margin) + CARRY_SLACK;
        let carry_self = self_margin + CARRY_SLACK;
        let held = self
            .scene
            .held()
            .map(|h| Solid::attached(h, &k.frames[robot.hand_frame % MAX_FRAMES]));
        let bodies = robot.bodies.len();
        let center: [Vector3<f32>; SLOTS] = core::array::from_fn(|b| match (b < bodies, k.boxes.get(b), &held) {
            (true, Some(pose), _) => pose.translation,
            (false, _, Some(h)) => h.center,
            _ => Vector3::zeros(),
        });
        let placed = Placed {
            robot,
            k: &k,
            held,
            margin,
            self_margin,
        };
        if let Some(contact) = self.last
            && self.still_touching(contact, &placed, &center, carry, carry_self)
        {
            return Ok(Some(contact));
        }
        for b in (0..self.shapes).filter(|&b| self.moving >> b & 1 == 1) {
            let used = self.slack.used[slot(b)];
            if self.slack.obstacle_least[slot(b)].partial_cmp(&used) != Some(Ordering::Greater) {
                let candidates = self
                    .obstacles
                    .iter()
                    .zip(self.obstacle_radius.iter())
                    .zip(self.hints.obstacle[slot(b)].iter_mut())
                    .zip(self.slack.obstacle[slot(b)].iter_mut());
                let ball = (&center[slot(b)], self.radius[slot(b)]);
                for (i, (((o, &r), hint), runs_out)) in candidates.take(count).enumerate() {
                    if *runs_out > used {
                        continue;
                    }
                    match obstacle_gap(&placed, b, ball, (o, r), hint) {
                        Some(gap) => *runs_out = used + (gap - carry),
                        None => {
                            return Ok(Some(Contact::Obstacle {
                                body: b as u8,
                                obstacle: i as u8,
                            }));
                        }
                    }
                }
                self.slack.obstacle_least[slot(b)] = least(self.slack.obstacle[slot(b)].iter().take(count));
            }
            let slack = &mut self.slack.surface[slot(b)];
            if !surface.is_empty() && *slack <= 0.0 {
                let hint = &mut self.hints.surface[slot(b)];
                let around = match (robot.bodies.get(b), k.boxes.get(b)) {
                    (Some(body), Some(pose)) => Aabb::around_box(&pose.translation, &pose.rotation, &body.half_extents),
                    _ => Aabb::around_ball(&center[slot(b)], self.radius[slot(b)]),
                };
                let gap = surface.gap(&around, margin, SURFACE_HORIZON, |probe| match probe {
                    Probe::Piece(e) => placed
                        .ball_clear_of_box(b, e, margin)
                        .or_else(|| placed.body_apart_from(b, e, hint)),
                    Probe::Box(aabb) => placed.body_apart_from(b, &Solid::aabb(aabb), hint),
                });
                match gap {
                    Ok(gap) => *slack = gap - carry,
                    Err(obstacle) => {
                        return Ok(Some(Contact::Surface {
                            body: b as u8,
                            obstacle,
                        }));
                    }
                }
            }
        }
        if !self.config.self_collision {
            return Ok(None);
        }
        for &(a, b) in self.pairs.iter().take(self.pair_count) {
            let (a, b) = (slot(usize::from(a)), slot(usize::from(b)));
            let slack = &mut self.slack.body[a][b];
            if *slack > 0.0 {
                continue;
            }
            match bodies_gap(&placed, [a, b], &center, &self.radius, &mut self.hints.body[a][b]) {
                Some(gap) => *slack = gap - carry_self,
                None => {
                    return Ok(Some(Contact::SelfContact {
                        first: a as u8,
                        second: b as u8,
                    }));
                }
            }
        }
        Ok(None)
    }

    /// Whether the pair of `contact` (an obstacle's or a self pair; a surface's is left to the
    /// walk) still touches at the state `placed`; a pair proven apart takes its gap as slack,
    /// so the walk in order skips it. A pair with slack left is not tested here.
    fn still_touching(
        &mut self,
        contact: Contact,
        placed: &Placed<'_, J>,
        center: &[Vector3<f32>; SLOTS],
        carry: f32,
        carry_self: f32,
    ) -> bool {
        match contact {
            Contact::Obstacle { body, obstacle } => {
                let (b, i) = (slot(usize::from(body)), usize::from(obstacle));
                let used = self.slack.used[b];
                let (Some(o), Some(&r), Some(hint), Some(runs_out)) = (
                    self.obstacles.get(i),
                    self.obstacle_radius.get(i),
                    self.hints.obstacle[b].get_mut(i),
                    self.slack.obstacle[b].get_mut(i),
                ) else {
                    return false;
                };
                if *runs_out > used {
                    return false;
                }
                match obstacle_gap(placed, b, (&center[b], self.radius[b]), (o, r), hint) {
                    // Raised from at most `used`: `obstacle_least` still bounds it from below.
                    Some(gap) => {
                        *runs_out = used + (gap - carry);
                        false
                    }
                    None => true,
                }
            }
            Contact::SelfContact { first, second } => {
                let (a, b) = (slot(usize::from(first)), slot(usize::from(second)));
                let slack = &mut self.slack.body[a][b];
                if !self.config.self_collision || *slack > 0.0 {
                    return false;
                }
                match bodies_gap(placed, [a, b], center, &self.radius, &mut self.hints.body[a][b]) {
                    Some(gap) => {
                        *slack = gap - carry_self;
                        false
                    }
                    None => true,
                }
            }
            Contact::Surface { .. } => false,
        }
    }
}

/// The least of `values`, a NaN counting as minus infinity (a pair never skipped); infinity
/// for none.
fn least<'v>(values: impl Iterator<Item = &'v f32>) -> f32 {
    values.fold(f32::INFINITY, |m, &v| {
        if v >= m {
            m
        } else if v < m {
            v
        } else {
            f32::NEG_INFINITY
        }
    })
}

/// The gap between two balls (centre, radius) when they are apart by more than `margin`: a
/// lower bound on the distance between the shapes they hold.
#[inline(always)]
fn ball_gap((c1, r1): (&Vector3<f32>, f32), (c2, r2): (&Vector3<f32>, f32), margin: f32) -> Option<f32> {
    let d2 = (c1 - c2).norm_squared();
    let reach = r1 + r2 + margin;
    (d2 > reach * reach).then(|| sqrt_below(d2) - r1 - r2)
}

/// Shape `b` (its ball) proven apart from obstacle `o` (its ball) by more than the state's
/// margin: the certified gap, from the cheapest test that proves it (the balls, the boxes'
/// face normals, then GJK on the oriented box and the hull); `None` when none does.
#[inline(always)]
fn obstacle_gap<const J: usize>(
    placed: &Placed<'_, J>,
    b: usize,
    ball: (&Vector3<f32>, f32),
    (o, r): (&Solid, f32),
    hint: &mut Vector3<f32>,
) -> Option<f32> {
    ball_gap(ball, (&o.center, r), placed.margin)
        .or_else(|| placed.boxes_apart(b, o))
        .or_else(|| placed.body_apart_from(b, o, hint))
}

/// Shapes `a` and `b` proven apart by more than the self margin, as [`obstacle_gap`].
fn bodies_gap<const J: usize>(
    placed: &Placed<'_, J>,
    [a, b]: [usize; 2],
    center: &[Vector3<f32>; SLOTS],
    radius: &[f32; SLOTS],
    hint: &mut Vector3<f32>,
) -> Option<f32> {
    ball_gap(
        (&center[slot(a)], radius[slot(a)]),
        (&center[slot(b)], radius[slot(b)]),
        placed.self_margin,
    )
    .or_else(|| placed.bodies_apart(a, b, hint))
}

/// Checks one configuration away from the ends: the first contact found, or `None` when
/// every pair is proven apart by more than its margin.
pub fn check_state<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    q: &[f32; J],
    config: &CheckConfig,
) -> Result<Option<Contact>, Error> {
    config.validate()?;
    Prepared::new(robot, scene, config).contact_at(q, config.margin)
}

/// Checks a start or goal as the user gave it: obstacles at `end_margin`, PyBullet's own
/// contact rule (docs/formats.md, valid ends), not the planner's margin.
pub fn check_end<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    q: &[f32; J],
    config: &CheckConfig,
) -> Result<Option<Contact>, Error> {
    config.validate()?;
    Prepared::new(robot, scene, config).contact_at(q, config.end_margin)
}

/// A certified lower bound on the distance from the moving robot bodies' hulls (and the held
/// object) to the nearest obstacle or surface piece: zero when something may touch. Self-contact is not counted; for
/// diagnostics and for choosing among states that are all free.
pub fn clearance<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    q: &[f32; J],
) -> Result<f32, Error> {
    let k = forward_with(robot, q, robot.finger_opening(scene.gripper()))?;
    let held = scene
        .held()
        .map(|h| Solid::attached(h, &k.frames[robot.hand_frame % MAX_FRAMES]));
    let placed = Placed {
        robot,
        k: &k,
        held: None,
        margin: 0.0,
        self_margin: 0.0,
    };
    let moving = || (0..robot.bodies.len().min(MAX_BODIES)).filter(|&b| moves(robot, b));
    let mut best = f32::INFINITY;
    for o in scene.obstacles().iter().map(Solid::obstacle) {
        for b in moving() {
            let hull = placed.hull(b);
            best = best.min(distance_lower_bound(&hull, &o));
        }
        if let Some(h) = &held {
            best = best.min(distance_lower_bound(h, &o));
        }
    }
    let surface = scene.surface();
    for b in moving() {
        let hull = placed.hull(b);
        let pose = &k.boxes[b % MAX_BODIES];
        let half = robot.bodies.get(b).map_or(Vector3::zeros(), |body| body.half_extents);
        let around = Aabb::around_box(&pose.translation, &pose.rotation, &half);
        let gap = surface.gap(&around, f32::INFINITY, best, |probe| match probe {
            Probe::Piece(e) => Some(distance_lower_bound(&hull, e)),
            Probe::Box(_) => None,
        });
        best = best.min(gap.unwrap_or(0.0));
    }
    if let Some(h) = &held {
        let around = Aabb::around_ball(&h.center, h.bounding_radius());
        let gap = surface.gap(&around, f32::INFINITY, best, |probe| match probe {
            Probe::Piece(e) => Some(distance_lower_bound(h, e)),
            Probe::Box(_) => None,
        });
        best = best.min(gap.unwrap_or(0.0));
    }
    Ok(best)
}

/// Checks every waypoint and every interpolated state between consecutive waypoints; the
/// first and last waypoints are the ends (states within `end_radius` of them keep
/// `end_margin` from obstacles, the rest `margin`). With `stop_at_first`, returns at the first
/// contact (the report then counts states only up to it); otherwise counts every colliding
/// state.
pub fn check_trajectory<const J: usize, const H: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[[f32; J]; H],
    config: &CheckConfig,
    stop_at_first: bool,
) -> Result<TrajectoryReport, Error> {
    check_between_own_ends(robot, scene, trajectory, config, stop_at_first, None)
}

/// [`check_trajectory`] stopping at the first contact, in the order where a candidate of the
/// refinement most likely touches: every state of segment `first` (where it touched at its
/// last check), then the other waypoints, then the states between them (segments from `first`
/// on and round to 0 in each pass). A colliding candidate mostly touches again where it did or
/// at some waypoint, which ends the walk early; a free one costs the same states. The states
/// are the same as [`check_trajectory`]'s; which contact is reported first differs, and so
/// may, rarely, the verdict on a state GJK's carried direction decides at the margin (each
/// "free" is certified either way).
pub fn check_trajectory_from<const J: usize, const H: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[[f32; J]; H],
    config: &CheckConfig,
    first: usize,
) -> Result<TrajectoryReport, Error> {
    check_between_own_ends(robot, scene, trajectory, config, true, Some(first))
}

/// [`check_path`] of a whole trajectory, whose first and last waypoints are the ends.
fn check_between_own_ends<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[[f32; J]],
    config: &CheckConfig,
    stop_at_first: bool,
    first: Option<usize>,
) -> Result<TrajectoryReport, Error> {
    let (Some(start), Some(end)) = (trajectory.first(), trajectory.last()) else {
        return Ok(TrajectoryReport {
            states: 0,
            colliding_states: 0,
            first_contact: None,
        });
    };
    check_path(robot, scene, trajectory, [start, end], config, stop_at_first, first)
}

/// Checks the straight segment `a → b` (both ends included) of a path whose ends are `ends`
/// (the problem's start and goal): what a search over the checker asks of each edge.
///
/// One segment with nothing carried; [`SegmentChecker`] checks many in turn.
pub fn check_segment<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    a: &[f32; J],
    b: &[f32; J],
    ends: [&[f32; J]; 2],
    config: &CheckConfig,
) -> Result<bool, Error> {
    config.validate()?;
    SegmentChecker::validated(robot, scene, ends, config).free(a, b)
}

/// Checks straight segments of paths between the same ends one after another, carrying what
/// each check learned to the next: every pair's slack and separating direction, and the pair
/// that touched last. A search's edges and a shortener's attempts come back to the same places
/// of the scene again and again; what is carried only saves tests, the verdicts are
/// [`check_segment`]'s.
pub struct SegmentChecker<'s, const J: usize, const N: usize> {
    prepared: Prepared<'s, J, N>,
    ends: [[f32; J]; 2],
}

impl<const J: usize, const N: usize> core::fmt::Debug for SegmentChecker<'_, J, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SegmentChecker")
            .field("ends", &self.ends)
            .field("last", &self.prepared.last)
            .finish_non_exhaustive()
    }
}

impl<'s, const J: usize, const N: usize> SegmentChecker<'s, J, N> {
    /// A checker for `scene` whose paths run between `ends` (the problem's start and goal).
    pub fn new(
        robot: &'static Robot<f32, J>,
        scene: &'s Scene<'s, N>,
        ends: [&[f32; J]; 2],
        config: &CheckConfig,
    ) -> Result<Self, Error> {
        config.validate()?;
        Ok(Self::validated(robot, scene, ends, config))
    }

    /// [`SegmentChecker::new`] for a config known to be valid: a value, not a `Result`, so
    /// that the caller's frame holds the checker once.
    pub(crate) fn validated(
        robot: &'static Robot<f32, J>,
        scene: &'s Scene<'s, N>,
        ends: [&[f32; J]; 2],
        config: &CheckConfig,
    ) -> Self {
        Self {
            prepared: Prepared::new(robot, scene, config),
            ends: ends.map(|e| *e),
        }
    }

    /// Whether the segment `a → b` is free: the same states as [`check_trajectory`] on
    /// `[a, b]`, in another order: `b` first, then every `COARSE_STRIDE`-th state from `a` on,
    /// then the rest. A search's `a` is a node already known free and its `b` the new step, so
    /// an edge that collides mostly does so at `b`, which one state then proves; a shortcut
    /// between two free waypoints collides somewhere inside, which the coarse pass finds in an
    /// eighth of the states.
    pub fn free(&mut self, a: &[f32; J], b: &[f32; J]) -> Result<bool, Error> {
        let steps = segment_steps(a, b, self.prepared.config.max_step)?;
        let [s, g] = &self.ends;
        let config = self.prepared.config;
        if self.prepared.contact_at(b, margin_at(b, [s, g], &config))?.is_some() {
            return Ok(false);
        }
        let coarse = (0..steps).step_by(COARSE_STRIDE);
        let fine = (0..steps).filter(|s| s % COARSE_STRIDE as u32 != 0);
        for step in coarse.chain(fine) {
            let state = interpolate(a, b, step, steps);
            if self
                .prepared
                .contact_at(&state, margin_at(&state, [s, g], &config))?
                .is_some()
            {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// States between the ones [`check_segment`]'s first pass checks (0.08 rad at most apart: close
/// enough that the separating directions carried from one to the next still mostly hold).
const COARSE_STRIDE: usize = 8;

/// The obstacle clearance state `q` must keep: `end_margin` near an end, `margin` elsewhere.
fn margin_at<const J: usize>(q: &[f32; J], ends: [&[f32; J]; 2], config: &CheckConfig) -> f32 {
    if ends.iter().any(|e| within(q, e, config.end_radius)) {
        config.end_margin
    } else {
        config.margin
    }
}

/// Whether `q` lies within `radius` (max-norm) of `end`.
fn within<const J: usize>(q: &[f32; J], end: &[f32; J], radius: f32) -> bool {
    q.iter().zip(end.iter()).all(|(x, y)| (x - y).abs() <= radius)
}

fn check_path<const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[[f32; J]],
    ends: [&[f32; J]; 2],
    config: &CheckConfig,
    stop_at_first: bool,
    first: Option<usize>,
) -> Result<TrajectoryReport, Error> {
    config.validate()?;
    let mut prepared = Prepared::new(robot, scene, config);
    let mut report = TrajectoryReport {
        states: 0,
        colliding_states: 0,
        first_contact: None,
    };
    // A segment too long is bad input whatever the order of the walk finds first.
    for pair in trajectory.windows(2) {
        if let [a, b] = pair {
            segment_steps(a, b, config.max_step)?;
        }
    }
    let count = trajectory.len();
    // `None`: one walk in order. `Some`: [`check_trajectory_from`]'s three passes.
    let (passes, first) = match first {
        Some(f) if stop_at_first => (3, if f < count { f } else { 0 }),
        _ => (1, 0),
    };
    let walk = passes == 1;
    for pass in 0..passes {
        for segment in (first..count).chain(0..first) {
            let Some(q) = trajectory.get(segment) else { continue };
            let next = trajectory.get(segment + 1);
            let steps = match next {
                Some(b) => segment_steps(q, b, config.max_step)?,
                None => 1,
            };
            let range = match (walk, pass, segment == first) {
                (true, ..) => 0..steps,
                (false, 0, true) => 0..steps,
                (false, 1, false) => 0..1,
                (false, 2, false) => 1..steps,
                _ => 0..0,
            };
            for step in range {
                let state = match next {
                    Some(b) => interpolate(q, b, step, steps),
                    None => *q,
                };
                report.states += 1;
                if let Some(contact) = prepared.contact_at(&state, margin_at(&state, ends, config))? {
                    report.colliding_states += 1;
                    if report.first_contact.is_none() {
                        report.first_contact = Some(StateContact {
                            segment: segment as u16,
                            step: step as u16,
                            contact,
                        });
                    }
                    if stop_at_first {
                        return Ok(report);
                    }
                }
            }
        }
    }
    Ok(report)
}

/// Number of states (the start included, the end excluded) that keep every joint step ≤ `max_step`.
fn segment_steps<const J: usize>(a: &[f32; J], b: &[f32; J], max_step: f32) -> Result<u32, Error> {
    let mut widest = 0.0f32;
    for (x, y) in a.iter().zip(b.iter()) {
        let d = (y - x).abs();
        if !d.is_finite() {
            return Err(Error::NonFiniteJoint { joint: 0 });
        }
        widest = widest.max(d);
    }
    let steps = libm::ceilf(widest / max_step).max(1.0);
    if steps > MAX_STEPS_PER_SEGMENT as f32 {
        return Err(Error::SegmentTooLong);
    }
    Ok(steps as u32)
}

fn interpolate<const J: usize>(a: &[f32; J], b: &[f32; J], step: u32, steps: u32) -> [f32; J] {
    let t = step as f32 / steps as f32;
    core::array::from_fn(|j| a[j] + (b[j] - a[j]) * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::kinematics::{Joints, forward};
    use crate::robot::{HAND_FRAME, PANDA};
    use crate::scene::Obstacle;

    const READY: [f32; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];

    /// A thin plate between the fingers (2 cm across the hand's y, 1 cm thick, 2 cm tall, centred
    /// 9.5 cm from the hand on its z, turned with the hand), as one obstacle.
    fn plate_between_the_fingers() -> Scene<'static, 4> {
        let k = forward(&crate::robot::PANDA, &READY).unwrap();
        let hand = &k.frames[HAND_FRAME];
        let center = hand.transform_point(&Vector3::new(0.0, 0.0, 0.095));
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid(center.into(), [0.01, 0.02, 0.02], hand.quaternion_wxyz()).unwrap())
            .unwrap();
        scene
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker: slow under Miri")]
    fn a_plate_between_open_fingers_is_free_and_closed_fingers_touch_it() {
        let scene = plate_between_the_fingers();
        let config = CheckConfig::default();
        for w in [0.04, 0.025, 0.015] {
            let open = scene.clone().with_gripper(w).unwrap();
            assert_eq!(
                check_state(&crate::robot::PANDA, &open, &READY, &config),
                Ok(None),
                "{w}"
            );
            assert!(clearance(&crate::robot::PANDA, &open, &READY).unwrap() > 0.0, "{w}");
        }
        let closed = scene.with_gripper(0.0).unwrap();
        let contact = check_state(&crate::robot::PANDA, &closed, &READY, &config).unwrap();
        let finger = |b: u8| crate::robot::BODY_NAMES[usize::from(b)].ends_with("finger");
        assert!(
            matches!(contact, Some(Contact::Obstacle { body, obstacle: 0 }) if finger(body)),
            "{contact:?}"
        );
        assert_eq!(
            check_end(&crate::robot::PANDA, &closed, &READY, &config).unwrap(),
            contact
        );
        assert_eq!(clearance(&crate::robot::PANDA, &closed, &READY), Ok(0.0));
        // A trajectory that stays put collides at every state, the first at once.
        let report = check_trajectory(&crate::robot::PANDA, &closed, &[READY; 3], &config, false).unwrap();
        assert_eq!(report.colliding_states, report.states);
    }

    #[test]
    fn ready_pose_in_an_empty_scene_is_free() {
        let scene = Scene::<4>::new();
        assert_eq!(
            check_state(&crate::robot::PANDA, &scene, &READY, &CheckConfig::default()),
            Ok(None)
        );
    }

    #[test]
    #[cfg(all(feature = "iiwa7", feature = "xarm6"))]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn other_arms_bolted_bases_and_missing_grippers() {
        use crate::robot::arms::{iiwa7, xarm6};
        // The mount's top at z = 0: under the iiwa's link 0, and under the xArm's `link_base`
        // (fixed below a geometry-free `world` link, so frame 1, yet bolted down too).
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid([0.0, 0.0, -0.01], [0.4, 0.4, 0.02], ID).unwrap())
            .unwrap();
        // The scene's default `gripper` (the Panda's 0.025 m) means nothing to an arm without
        // a hand: not an error.
        assert!(scene.gripper() > 0.0);
        assert_eq!(
            check_state(&iiwa7::ROBOT, &scene, &iiwa7::ROBOT.neutral, &CheckConfig::default()),
            Ok(None)
        );
        assert_eq!(
            check_state(&xarm6::ROBOT, &scene, &xarm6::ROBOT.neutral, &CheckConfig::default()),
            Ok(None)
        );
        // Moving bodies still collide: the slab raised into the xArm's link 1.
        let mut raised = Scene::<4>::new();
        raised
            .push(Obstacle::cuboid([0.0, 0.0, 0.2], [0.4, 0.4, 0.02], ID).unwrap())
            .unwrap();
        assert!(matches!(
            check_state(&xarm6::ROBOT, &raised, &xarm6::ROBOT.neutral, &CheckConfig::default()),
            Ok(Some(Contact::Obstacle { .. }))
        ));
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn a_box_on_the_hand_is_contact_and_far_away_is_free() {
        let k = forward(&crate::robot::PANDA, &READY).unwrap();
        let hand = k.frames[HAND_FRAME].translation;
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid(hand.into(), [0.05; 3], ID).unwrap())
            .unwrap();
        let contact = check_state(&crate::robot::PANDA, &scene, &READY, &CheckConfig::default()).unwrap();
        assert!(
            matches!(contact, Some(Contact::Obstacle { obstacle: 0, .. })),
            "{contact:?}"
        );
        let mut far = Scene::<4>::new();
        far.push(Obstacle::sphere([2.0, 2.0, 2.0], 0.1).unwrap()).unwrap();
        assert_eq!(
            check_state(&crate::robot::PANDA, &far, &READY, &CheckConfig::default()),
            Ok(None)
        );
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn the_fixed_base_is_not_checked_against_obstacles() {
        // A table top flush with link0's footprint touches only the fixed base.
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid([0.0, 0.0, -0.01], [0.3, 0.3, 0.02], ID).unwrap())
            .unwrap();
        assert_eq!(
            check_state(&crate::robot::PANDA, &scene, &READY, &CheckConfig::default()),
            Ok(None)
        );
    }

    #[test]
    fn sqrt_below_is_a_tight_lower_bound() {
        let mut worst = 1.0f64;
        // Every exponent, many mantissas: the first guess's error repeats with each factor 4.
        for e in -90..90 {
            for m in 0..997 {
                let x = (1.0 + m as f32 / 997.0) * libm::powf(2.0, e as f32);
                let exact = f64::from(x).sqrt();
                let below = f64::from(sqrt_below(x));
                assert!(below <= exact, "{x}: {below} > {exact}");
                worst = worst.min(below / exact);
            }
        }
        assert!(worst > 0.998, "{worst}");
        assert_eq!(sqrt_below(0.0), 0.0);
        assert_eq!(sqrt_below(f32::NAN), 0.0);
        assert_eq!(sqrt_below(f32::INFINITY), 0.0);
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn carried_clearance_gives_the_verdicts_of_testing_every_state_afresh() {
        // A cluttered scene, an object in the hand, and random walks through it: a trajectory
        // check carries clearance from state to state, `check_state` tests each one alone.
        let mut scene = Scene::<8>::new();
        for (center, dims) in [
            ([0.55, 0.0, 0.35], [0.3, 0.02, 0.5]),
            ([0.4, 0.35, 0.2], [0.1, 0.1, 0.4]),
            ([0.35, -0.4, 0.5], [0.2, 0.05, 0.05]),
            ([0.5, 0.0, -0.02], [1.2, 1.2, 0.02]),
        ] {
            scene.push(Obstacle::cuboid(center, dims, ID).unwrap()).unwrap();
        }
        scene.hold(Obstacle::cuboid([0.0, 0.0, 0.15], [0.04, 0.04, 0.08], ID).unwrap());
        // Margins the same at the ends and elsewhere, so that `check_state` is the reference:
        // a fresh check of each state, which must prove what the carried slack proves. Walk 20
        // passes a link 4 mm beside the floor's edge, where GJK's direction is off along the
        // edge by enough to lose the gap over the floor's 1.2 m; it failed until `gjk::feature_gap`
        // tried that direction without its component along the box's axes.
        let cfg = CheckConfig {
            end_margin: DEFAULT_MARGIN,
            ..CheckConfig::default()
        };
        let (mut states, mut colliding, mut free_walks) = (0, 0, 0);
        for seed in 0..24 {
            let mut rng = crate::rng::Rng::new(seed);
            let mut q: Joints<f32> =
                core::array::from_fn(|j| rng.uniform_f32(PANDA.soft_lower[j], PANDA.soft_upper[j]));
            let walk: [Joints<f32>; 6] = core::array::from_fn(|_| {
                q = core::array::from_fn(|j| {
                    (q[j] + rng.uniform_f32(-0.6, 0.6)).clamp(PANDA.soft_lower[j], PANDA.soft_upper[j])
                });
                q
            });
            let carried = check_trajectory(&crate::robot::PANDA, &scene, &walk, &cfg, false).unwrap();
            let mut afresh = 0;
            let mut count = 0;
            for pair in walk.windows(2) {
                let steps = segment_steps(&pair[0], &pair[1], cfg.max_step).unwrap();
                for step in 0..steps {
                    count += 1;
                    let state = interpolate(&pair[0], &pair[1], step, steps);
                    afresh += u32::from(
                        check_state(&crate::robot::PANDA, &scene, &state, &cfg)
                            .unwrap()
                            .is_some(),
                    );
                }
            }
            count += 1;
            afresh += u32::from(
                check_state(&crate::robot::PANDA, &scene, &walk[5], &cfg)
                    .unwrap()
                    .is_some(),
            );
            assert_eq!(carried.states, count);
            assert_eq!(carried.colliding_states, afresh, "walk {walk:?}");
            states += count;
            colliding += afresh;
            free_walks += u32::from(afresh == 0);
        }
        // The walks are not all in contact, nor all free.
        assert!(
            colliding > 0 && colliding < states && free_walks > 0,
            "{colliding} of {states}, {free_walks} free"
        );
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn interpolation_catches_a_thin_wall_between_free_waypoints() {
        // Swing joint 1 through a thin wall that neither end touches.
        let a = [-1.2, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785];
        let b = [1.2, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785];
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid([0.6, 0.0, 0.5], [0.4, 0.005, 0.4], ID).unwrap())
            .unwrap();
        let cfg = CheckConfig::default();
        assert_eq!(check_state(&crate::robot::PANDA, &scene, &a, &cfg), Ok(None));
        assert_eq!(check_state(&crate::robot::PANDA, &scene, &b, &cfg), Ok(None));
        let report = check_trajectory(&crate::robot::PANDA, &scene, &[a, b], &cfg, false).unwrap();
        assert!(!report.is_free());
        // 2.4 rad at 0.01 rad: 240 steps (241 after f32 rounding of the quotient) plus the end.
        assert!((241..=242).contains(&report.states), "{}", report.states);
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn a_segment_checker_gives_every_segment_the_verdict_of_a_fresh_check() {
        // A search's pattern in a drawer-like scene (thin panels, a held object): steps of 0.3
        // rad from earlier nodes, blocked and free, one after another on one checker.
        let mut scene = Scene::<8>::new();
        for (center, dims) in [
            ([0.55, 0.0, 0.2], [0.4, 0.6, 0.01]),
            ([0.55, 0.0, 0.5], [0.4, 0.6, 0.01]),
            ([0.75, 0.0, 0.35], [0.01, 0.6, 0.3]),
            ([0.55, 0.3, 0.35], [0.4, 0.01, 0.3]),
            ([0.5, 0.0, -0.02], [1.2, 1.2, 0.02]),
        ] {
            scene.push(Obstacle::cuboid(center, dims, ID).unwrap()).unwrap();
        }
        scene.hold(Obstacle::cuboid([0.0, 0.0, 0.12], [0.03, 0.03, 0.06], ID).unwrap());
        let cfg = CheckConfig::default();
        let ends = [READY, [0.3, 0.2, 0.0, -1.8, 0.0, 2.0, 0.785]];
        let mut checker = SegmentChecker::new(&PANDA, &scene, [&ends[0], &ends[1]], &cfg).unwrap();
        let mut rng = crate::rng::Rng::new(3);
        let mut nodes = [READY; 64];
        let (mut len, mut free, mut blocked) = (1, 0, 0);
        for _ in 0..400 {
            let from = nodes[rng.below(len as u32) as usize];
            let to: Joints<f32> = core::array::from_fn(|j| {
                (from[j] + rng.uniform_f32(-0.3, 0.3)).clamp(PANDA.soft_lower[j], PANDA.soft_upper[j])
            });
            let carried = checker.free(&from, &to).unwrap();
            let fresh = check_segment(&PANDA, &scene, &from, &to, [&ends[0], &ends[1]], &cfg).unwrap();
            assert_eq!(carried, fresh, "{from:?} → {to:?}");
            if carried {
                free += 1;
                nodes[len % 64] = to;
                len = (len + 1).min(64);
            } else {
                blocked += 1;
            }
        }
        assert!(free > 40 && blocked > 40, "{free} free, {blocked} blocked");
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn a_walk_from_any_segment_finds_the_same_verdict_and_from_the_contact_finds_it_at_once() {
        // Joint 1 swings through a thin wall in 10 segments; only the middle ones touch it.
        let (a, b) = (
            [-1.2f32, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785],
            [1.2f32, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785],
        );
        let path: [Joints<f32>; 11] =
            core::array::from_fn(|i| core::array::from_fn(|j| a[j] + (b[j] - a[j]) * i as f32 / 10.0));
        let mut scene = Scene::<4>::new();
        scene
            .push(Obstacle::cuboid([0.6, 0.0, 0.5], [0.4, 0.005, 0.4], ID).unwrap())
            .unwrap();
        let cfg = CheckConfig::default();
        let plain = check_trajectory(&crate::robot::PANDA, &scene, &path, &cfg, true).unwrap();
        let hit = plain.first_contact.expect("the swing touches the wall").segment;
        for first in 0..14 {
            let from = check_trajectory_from(&crate::robot::PANDA, &scene, &path, &cfg, first).unwrap();
            assert!(!from.is_free(), "from segment {first}");
            assert_eq!(from.colliding_states, 1, "it stops at the first contact");
        }
        let at_contact = check_trajectory_from(&crate::robot::PANDA, &scene, &path, &cfg, usize::from(hit)).unwrap();
        assert!(
            at_contact.states < plain.states,
            "{} vs {}",
            at_contact.states,
            plain.states
        );
        // A free path is walked in full whatever the first segment: every state once.
        let (c, d) = (
            [-1.2f32, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785],
            [-0.6f32, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785],
        );
        let free: [Joints<f32>; 11] =
            core::array::from_fn(|i| core::array::from_fn(|j| c[j] + (d[j] - c[j]) * i as f32 / 10.0));
        let whole = check_trajectory(&crate::robot::PANDA, &scene, &free, &cfg, true).unwrap();
        assert!(whole.is_free());
        for first in [0, 4, 10] {
            assert_eq!(
                check_trajectory_from(&crate::robot::PANDA, &scene, &free, &cfg, first).unwrap(),
                whole
            );
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn self_contact_when_the_hand_folds_onto_the_base() {
        // Joint 4 at its lower limit with joint 2 forward folds link7/hand towards link1-2.
        let folded = [0.0, 1.7, 0.0, -3.07, 0.0, 0.0, 0.0];
        let contact = check_state(
            &crate::robot::PANDA,
            &Scene::<1>::new(),
            &folded,
            &CheckConfig::default(),
        )
        .unwrap();
        assert!(matches!(contact, Some(Contact::SelfContact { .. })), "{contact:?}");
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker at many states: hours under Miri")]
    fn the_held_object_counts_against_obstacles() {
        // A 30 cm rod held along the hand's z: an obstacle at its far end touches only the rod.
        let k = forward(&crate::robot::PANDA, &READY).unwrap();
        let hand = &k.frames[HAND_FRAME];
        let tip = hand.transform_point(&Vector3::new(0.0, 0.0, 0.38));
        let mut scene = Scene::<4>::new();
        scene.push(Obstacle::sphere(tip.into(), 0.03).unwrap()).unwrap();
        assert_eq!(
            check_state(&crate::robot::PANDA, &scene, &READY, &CheckConfig::default()),
            Ok(None)
        );
        scene.hold(Obstacle::cuboid([0.0, 0.0, 0.2], [0.02, 0.02, 0.3], ID).unwrap());
        let contact = check_state(&crate::robot::PANDA, &scene, &READY, &CheckConfig::default()).unwrap();
        assert_eq!(
            contact,
            Some(Contact::Obstacle {
                body: HELD_BODY,
                obstacle: 0
            })
        );
    }

    #[test]
    fn bad_settings_and_huge_segments_are_errors() {
        let scene = Scene::<1>::new();
        let cfg = CheckConfig {
            margin: -1.0,
            ..CheckConfig::default()
        };
        assert_eq!(
            check_state(&crate::robot::PANDA, &scene, &READY, &cfg),
            Err(Error::BadParameter)
        );
        let mut far = READY;
        far[0] = 100.0;
        assert_eq!(
            check_trajectory(
                &crate::robot::PANDA,
                &scene,
                &[READY, far],
                &CheckConfig::default(),
                true
            ),
            Err(Error::SegmentTooLong)
        );
    }
}
