//! The arms as frozen by `edmp-codegen` at build time ([`arms`]): link frames, collision
//! boxes and hulls, limits, self-collision pairs. An arm is a [`Robot`] table; the code that
//! moves one ([`kinematics`], [`reach`]) takes the table and is generic over its number of
//! joints `J`. The one input the tables leave open is the gripper opening, for arms with a
//! gripper: each finger frame is its fixed transform at opening 0 plus [`FrameSpec::slide`]
//! times the opening (see [`crate::robot::kinematics`]).
//!
//! No number of an arm is typed here: the tables come from `OUT_DIR/robot_NAME.rs`, which the
//! build script generates from the arm's URDF and collision meshes. Read the generated file (or
//! run `cargo run -p edmp-codegen -- NAME`) to see each number and its origin.

pub mod arms;
pub mod ik;
pub mod kinematics;
pub mod reach;

use nalgebra::{Matrix3, RealField, Vector3};

/// One link frame: where it sits on its parent and how its joint turns it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSpec<T> {
    /// Index of the parent frame (the root, frame 0, names itself).
    pub parent: usize,
    /// The actuated joint that turns this frame, if any.
    pub joint: Option<usize>,
    /// Joint origin translation in the parent frame (for a finger: at opening 0).
    pub translation: Vector3<T>,
    /// Unit joint axis in this frame: revolute, or a finger's prismatic axis (zero for fixed
    /// frames).
    pub axis: Vector3<T>,
    /// With `rot_cos` and `rot_sin`: the rotation relative to the parent is
    /// `rot_fixed + cos(q)·rot_cos + sin(q)·rot_sin` (Rodrigues folded with the origin rotation).
    pub rot_fixed: Matrix3<T>,
    /// See `rot_fixed`.
    pub rot_cos: Matrix3<T>,
    /// See `rot_fixed`.
    pub rot_sin: Matrix3<T>,
    /// For a finger: its displacement in the parent frame per metre of gripper opening (the
    /// prismatic axis turned into the parent frame; a `<mimic>` joint's multiplier folded in).
    /// The frame's translation is `translation + slide · w`. `None` for every other frame.
    pub slide: Option<Vector3<T>>,
}

/// A collision body's oriented box in its link frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodySpec<T> {
    /// Frame the box is attached to.
    pub frame: usize,
    /// First of this body's collision-mesh vertices in `Robot::hull_points`.
    pub hull_start: usize,
    /// How many vertices: their convex hull is the body's exact geometry.
    pub hull_len: usize,
    /// The vertices farthest along the link frame's +x, −x, +y, −y, +z, −z, where a support
    /// query starts climbing the hull's edges (`Robot::hull_edge_start`); `None`: scan them all.
    pub hull_seeds: Option<[u16; 6]>,
    /// Box centre in that frame.
    pub center: Vector3<T>,
    /// Box axes (columns) in that frame.
    pub rotation: Matrix3<T>,
    /// Half of the full extent along each box axis.
    pub half_extents: Vector3<T>,
}

/// The edges of one body's convex hull: a linear function's largest value over the hull's
/// vertices is at a vertex none of whose neighbours has a larger one, so a support query can
/// climb along edges instead of scanning every vertex (`collision::convex::Hull`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HullGraph<'a> {
    /// Vertex `i`'s neighbours are `neighbours[start[i]..start[i + 1]]`.
    pub start: &'a [u16],
    /// Neighbours, as indices into the body's vertices.
    pub neighbours: &'a [u16],
    /// The vertices farthest along +x, −x, +y, −y, +z, −z of the body's frame.
    pub seeds: [u16; 6],
}

impl HullGraph<'_> {
    /// Vertex `i`'s neighbours (empty for an index outside the body).
    pub fn neighbours(&self, i: usize) -> &[u16] {
        match (self.start.get(i), self.start.get(i + 1)) {
            (Some(&a), Some(&b)) => self.neighbours.get(usize::from(a)..usize::from(b)).unwrap_or(&[]),
            _ => &[],
        }
    }
}

/// An arm's gripper: the range of its opening and the default an absent `gripper` field means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gripper<T> {
    /// The finger opening an absent `gripper` field means (docs/formats.md): 0.025 m.
    pub default: T,
    /// Smallest finger opening (the driving finger joint's `<limit lower>`).
    pub lower: T,
    /// Largest finger opening (its `<limit upper>`).
    pub upper: T,
}

/// Every table of one arm in one scalar type; `J` is its number of actuated joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Robot<T: 'static, const J: usize> {
    /// The scene format's `robot` name.
    pub name: &'static str,
    /// Link frames, parents before children; frame 0 is the root, the world frame.
    pub frames: &'static [FrameSpec<T>],
    /// Collision bodies.
    pub bodies: &'static [BodySpec<T>],
    /// Collision-mesh vertices of every body (link frame), sliced by `BodySpec::hull_start/len`.
    pub hull_points: &'static [Vector3<T>],
    /// Where each vertex's neighbours along its hull's edges begin in `hull_neighbours`
    /// (indexed like `hull_points`, then one past the end).
    pub hull_edge_start: &'static [u16],
    /// Each hull vertex's neighbours, as indices into its body's vertices.
    pub hull_neighbours: &'static [u16],
    /// Body pairs `(a, b)`, `a < b`, checked against each other for self-collision.
    pub self_pairs: &'static [(u8, u8)],
    /// URDF link name of each frame.
    pub frame_names: &'static [&'static str],
    /// URDF link name of each collision body.
    pub body_names: &'static [&'static str],
    /// URDF joint name of each actuated joint.
    pub joint_names: [&'static str; J],
    /// The tool centre point's frame (pose goals).
    pub tcp_frame: usize,
    /// The frame a held object is attached to.
    pub hand_frame: usize,
    /// The planning range's lower ends (the Panda: Franka's official limits, URDF
    /// `safety_controller`; other arms: `<limit>`).
    pub soft_lower: [T; J],
    /// The planning range's upper ends.
    pub soft_upper: [T; J],
    /// URDF `<limit lower>`: the hardware range, at least as wide as the planning one.
    pub hard_lower: [T; J],
    /// URDF `<limit upper>`.
    pub hard_upper: [T; J],
    /// The ready configuration: the gripper pointing down in front of the base (the Panda:
    /// MpiNets' neutral). Scene generators start or end problems near it.
    pub neutral: [T; J],
    /// Largest joint velocity (rad/s): the time law's bound (`crate::trajectory`). Not in a
    /// URDF for every arm, so each arm's spec in `edmp-codegen` names its source (the
    /// generated tables say it beside the numbers).
    pub max_velocity: [T; J],
    /// Largest joint acceleration (rad/s²), from the same spec.
    pub max_acceleration: [T; J],
    /// Largest joint jerk (rad/s³), from the same spec.
    pub max_jerk: [T; J],
    /// The gripper, for arms with one.
    pub gripper: Option<Gripper<T>>,
    /// Per body and joint, how far a point of the body can be from the joint's axis, in `f32`
    /// whatever `T` ([`reach::body_reach`]: the exact checker's carried clearance).
    pub body_reach: &'static [[f32; J]],
    /// Per joint, how far the hand frame's origin can be from the joint's axis: a held object's
    /// points are at most this plus their distance from the hand's origin.
    pub hand_reach: [f32; J],
}

pub use arms::panda::{
    BODIES, BODY_NAMES, FINGER_OPENING_DEFAULT, FINGER_OPENING_MAX, FINGER_OPENING_MIN, FRAME_NAMES, FRAMES,
    HAND_FRAME, HULL_POINTS, JOINT_NAMES, JOINTS, TCP_FRAME,
};
pub use arms::panda::{ROBOT as PANDA, ROBOT_F64 as PANDA_F64};
pub use arms::{MAX_BODIES, MAX_FRAMES};

/// The scalar types the kinematics run in: `f32` (planner) and `f64` (oracles).
///
/// Every transcendental goes through the `libm` crate, so results are bit-identical on every
/// target (x86_64, thumbv7em) whatever the platform's own math library does.
pub trait Real: RealField + Copy {
    /// `(sin x, cos x)` through `libm`.
    fn sin_cos_libm(self) -> (Self, Self);
    /// Neither NaN nor infinite.
    fn finite(self) -> bool;
}

impl Real for f32 {
    fn sin_cos_libm(self) -> (Self, Self) {
        libm::sincosf(self)
    }
    fn finite(self) -> bool {
        self.is_finite()
    }
}

impl Real for f64 {
    fn sin_cos_libm(self) -> (Self, Self) {
        libm::sincos(self)
    }
    fn finite(self) -> bool {
        self.is_finite()
    }
}

impl<T: Real, const J: usize> Robot<T, J> {
    /// The finger opening a scene's `gripper` means for this arm: the scene's where the arm
    /// has a gripper, 0 where it has none (docs/formats.md: `gripper` applies where the arm
    /// has a hand).
    pub fn finger_opening(&self, scene_gripper: T) -> T {
        if self.gripper.is_some() {
            scene_gripper
        } else {
            T::zero()
        }
    }

    /// Whether every joint lies within the soft (planning) limits, `tolerance` outside allowed.
    pub fn within_soft_limits(&self, q: &[T; J], tolerance: T) -> bool {
        (0..J).all(|i| q[i] >= self.soft_lower[i] - tolerance && q[i] <= self.soft_upper[i] + tolerance)
    }

    /// The frame turned by actuated joint `joint`.
    pub fn joint_frame(&self, joint: usize) -> Option<usize> {
        self.frames.iter().position(|f| f.joint == Some(joint))
    }

    /// The collision-mesh vertices of body `body` in its link frame (empty if out of range).
    pub fn hull(&self, body: usize) -> &[Vector3<T>] {
        self.bodies
            .get(body)
            .and_then(|b| self.hull_points.get(b.hull_start..b.hull_start + b.hull_len))
            .unwrap_or(&[])
    }

    /// The edges of body `body`'s hull, if the tables have them.
    pub fn hull_graph(&self, body: usize) -> Option<HullGraph<'_>> {
        let b = self.bodies.get(body)?;
        Some(HullGraph {
            start: self.hull_edge_start.get(b.hull_start..=b.hull_start + b.hull_len)?,
            neighbours: self.hull_neighbours,
            seeds: b.hull_seeds?,
        })
    }

    /// Whether `ancestor` is `frame` or lies on its path to the root.
    pub fn is_ancestor(&self, ancestor: usize, frame: usize) -> bool {
        let mut f = frame;
        for _ in 0..self.frames.len() {
            if f == ancestor {
                return true;
            }
            match self.frames.get(f) {
                Some(spec) if f != 0 => f = spec.parent,
                _ => return false,
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_consistent() {
        assert_eq!(JOINTS, 7);
        for (i, f) in PANDA.frames.iter().enumerate().skip(1) {
            assert!(f.parent < i, "frame {i} comes before its parent");
        }
        for j in 0..JOINTS {
            assert!(PANDA.joint_frame(j).is_some());
            assert!(PANDA.soft_lower[j] < PANDA.soft_upper[j]);
            assert!(PANDA.hard_lower[j] <= PANDA.soft_lower[j] && PANDA.soft_upper[j] <= PANDA.hard_upper[j]);
        }
        for b in PANDA_F64.bodies {
            let r = b.rotation;
            assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-9);
            assert!(r.determinant() > 0.0);
            assert!(b.half_extents.iter().all(|&h| h > 0.0));
        }
        for (body, (b, name)) in PANDA_F64.bodies.iter().zip(BODY_NAMES).enumerate() {
            let hull = PANDA_F64.hull(body);
            assert!(hull.len() >= 4, "{name}");
            // Every vertex lies in the body's box (the box was fitted to them).
            for p in hull {
                let local = b.rotation.transpose() * (p - b.center);
                assert!((0..3).all(|k| local[k].abs() <= b.half_extents[k] + 1e-9), "{name}");
            }
        }
        assert_eq!(FRAME_NAMES[TCP_FRAME], "panda_grasptarget");
        // The fingers, and only they, slide with the opening; both open along the hand's y.
        let sliding: [usize; 2] = [10, 11];
        for (i, (f, name)) in PANDA_F64.frames.iter().zip(FRAME_NAMES).enumerate() {
            assert_eq!(f.slide.is_some(), sliding.contains(&i), "{name}");
        }
        assert_eq!(FRAME_NAMES[10], "panda_leftfinger");
        assert_eq!(PANDA_F64.frames[10].slide, Some(Vector3::new(0.0, 1.0, 0.0)));
        assert_eq!(PANDA_F64.frames[11].slide, Some(Vector3::new(0.0, -1.0, 0.0)));
        assert_eq!(PANDA_F64.frames[10].parent, HAND_FRAME);
        // At the default opening the fingers sit exactly where the tables with 0.025 m folded
        // into the translation (before the opening was an input) put them, in f32 bits.
        for (f, y) in [(10, 0.025f32), (11, -0.025)] {
            let spec = &PANDA.frames[f];
            let at_default = spec.translation + spec.slide.unwrap() * FINGER_OPENING_DEFAULT;
            assert_eq!(at_default, Vector3::new(0.0f32, y, 0.0584), "frame {f}");
        }
        let gripper = PANDA.gripper.unwrap();
        assert_eq!(
            (gripper.default, gripper.lower, gripper.upper),
            (FINGER_OPENING_DEFAULT, FINGER_OPENING_MIN, FINGER_OPENING_MAX)
        );
        assert_eq!((PANDA.tcp_frame, PANDA.hand_frame), (TCP_FRAME, HAND_FRAME));
        assert_eq!((PANDA.frames.len(), PANDA.bodies.len()), (FRAMES, BODIES));
        assert_eq!(
            (FINGER_OPENING_MIN, FINGER_OPENING_DEFAULT, FINGER_OPENING_MAX),
            (0.0, 0.025, 0.04)
        );
        assert_eq!(FRAME_NAMES[HAND_FRAME], "panda_hand");
        assert!(PANDA.is_ancestor(1, TCP_FRAME) && !PANDA.is_ancestor(10, TCP_FRAME));
    }

    /// The checker merges the held object's pairs into the arm's table by walking it once: the
    /// table must be ascending, each pair `(a, b)` with `a < b` below the body count.
    fn assert_pair_table<T, const J: usize>(robot: &Robot<T, J>) {
        let n = robot.bodies.len();
        for w in robot.self_pairs.windows(2) {
            assert!(w[0] < w[1], "{}: {:?} before {:?}", robot.name, w[0], w[1]);
        }
        for &(a, b) in robot.self_pairs {
            assert!(a < b && usize::from(b) < n, "{}: pair {a}, {b}", robot.name);
        }
    }

    #[test]
    fn the_self_pair_tables_are_ascending_and_the_pandas_are_its_chain_levels_rule() {
        assert_pair_table(&PANDA);
        // The Panda's rule: bodies two or more revolute joints apart (link7, hand and fingers
        // share a level), as the checker used to derive it.
        let level = |frame: usize| {
            let (mut f, mut n) = (frame, 0);
            while f != 0 {
                n += usize::from(PANDA.frames[f].joint.is_some());
                f = PANDA.frames[f].parent;
            }
            n
        };
        let mut expected = std::vec::Vec::new();
        for a in 0..BODIES {
            for b in a + 1..BODIES {
                if level(PANDA.bodies[a].frame).abs_diff(level(PANDA.bodies[b].frame)) >= 2 {
                    expected.push((a as u8, b as u8));
                }
            }
        }
        assert_eq!(PANDA.self_pairs, &expected[..]);
    }
}
