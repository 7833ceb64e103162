//! Forward kinematics of an arm ([`Robot`]), its hand-written adjoint, and frame Jacobians.
//!
//! [`forward`] maps the arm's `J` joint angles to the world pose of every link frame and of
//! every collision box, the fingers (if any) at the default opening; [`forward_with`] takes the
//! opening (the scene's `gripper.finger`, [`crate::scene::Scene::gripper`]) too. The opening
//! moves the finger frames along their prismatic axes (the Panda hand's ±y) and nothing else:
//! for the adjoint and the Jacobians it is a constant. [`Kinematics::adjoint`] takes an upstream gradient on box corners back to the
//! joints; [`Cotangent`] gathers any other (on points moving with a frame, on frame poses) for
//! [`Kinematics::joint_gradient`]. Both end in one leaf-to-root sweep:
//!
//! a turn `dq` of revolute joint `i` (world axis `a`, through world point `o`) moves every
//! point `p` downstream by `dq·a×(p−o)` and turns every frame by `dq·[a]×R`. So with the
//! "force" `F = Σ g` and "moment" `M = Σ p×g + Σ_j R_j×G_j` of the upstream gradients of the
//! subtree (`R_j`, `G_j` columns of a rotation and of its gradient),
//! `∂L/∂q_i = a · (M − o×F)`. Subtree sums are accumulated child to parent, so the sweep is
//! O(frames + corners), with no matrix of partial derivatives ever formed.

use crate::error::Error;
use crate::robot::{MAX_BODIES, MAX_FRAMES, Real, Robot};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// A rigid transform: `world = rotation · local + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose<T: Real> {
    /// Orientation (columns are the frame's axes in world coordinates).
    pub rotation: Matrix3<T>,
    /// Origin in world coordinates.
    pub translation: Vector3<T>,
}

impl<T: Real> Pose<T> {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// `self ∘ local`: a pose given in this frame, expressed in the world.
    #[inline]
    pub fn compose(&self, rotation: &Matrix3<T>, translation: &Vector3<T>) -> Self {
        Self {
            rotation: self.rotation * rotation,
            translation: self.translation + self.rotation * translation,
        }
    }

    /// Orientation as a unit quaternion `[w, x, y, z]` (the order of the scene format).
    pub fn quaternion_wxyz(&self) -> [T; 4] {
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(self.rotation));
        [q.w, q.i, q.j, q.k]
    }

    /// A point given in this frame, expressed in the world.
    #[inline]
    pub fn transform_point(&self, p: &Vector3<T>) -> Vector3<T> {
        self.rotation * p + self.translation
    }
}

/// Joint angles of an arm's `J` actuated joints, radians (the Panda's 7 unless named).
pub type Joints<T, const J: usize = { crate::robot::JOINTS }> = [T; J];

/// Corner `k` of a box has sign `+` on axis `i` where bit `i` of `k` is set.
pub const CORNERS: usize = 8;

/// Upstream gradient on the 8 world corners of every collision body (bodies past the arm's
/// count are ignored).
pub type CornerGradient<T> = [[Vector3<T>; CORNERS]; MAX_BODIES];

/// An upstream gradient, gathered per frame as the force `F = Σ g` and the moment
/// `M = Σ p×g (+ Σ_j R_j×G_j)` about the world origin that it exerts on that frame; see the
/// module docs. Fill it with [`Self::add_point`] and [`Self::add_frame`], then call
/// [`Kinematics::joint_gradient`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cotangent<T: Real> {
    force: [Vector3<T>; MAX_FRAMES],
    moment: [Vector3<T>; MAX_FRAMES],
    /// Σ x·0 over every input: zero unless some input was NaN or infinite.
    probe: T,
}

impl<T: Real> Default for Cotangent<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> Cotangent<T> {
    /// No gradient yet.
    pub fn new() -> Self {
        Self {
            force: [Vector3::zeros(); MAX_FRAMES],
            moment: [Vector3::zeros(); MAX_FRAMES],
            probe: T::zero(),
        }
    }

    fn probe(&mut self, values: &[Vector3<T>]) {
        for v in values {
            self.probe += v.x * T::zero() + v.y * T::zero() + v.z * T::zero();
        }
    }

    /// Gradient `grad` on the world point `point`, which moves rigidly with frame `frame`.
    /// An out-of-range frame poisons the result ([`Error::NonFiniteGradient`]).
    pub fn add_point(&mut self, frame: usize, point: &Vector3<T>, grad: &Vector3<T>) {
        self.probe(core::slice::from_ref(grad));
        match (self.force.get_mut(frame), self.moment.get_mut(frame)) {
            (Some(f), Some(m)) => {
                *f += grad;
                *m += point.cross(grad);
            }
            // Frames come from the robot tables; a wrong index is a bug, reported, not a panic.
            _ => self.probe = T::one(),
        }
    }

    /// Gradient on the world pose of frame `frame` (`pose`, as computed by [`forward`]):
    /// `d_translation = ∂L/∂t`, `d_rotation = ∂L/∂R`.
    pub fn add_frame(&mut self, frame: usize, pose: &Pose<T>, d_translation: &Vector3<T>, d_rotation: &Matrix3<T>) {
        self.probe(core::slice::from_ref(d_translation));
        for j in 0..3 {
            self.probe(&[d_rotation.column(j).into_owned()]);
        }
        match (self.force.get_mut(frame), self.moment.get_mut(frame)) {
            (Some(f), Some(m)) => {
                *f += d_translation;
                *m += pose.translation.cross(d_translation);
                for j in 0..3 {
                    *m += pose.rotation.column(j).cross(&d_rotation.column(j));
                }
            }
            _ => self.probe = T::one(),
        }
    }
}

/// World poses of every link frame and every collision box of an arm for one configuration.
#[derive(Clone, Copy)]
pub struct Kinematics<T: Real + 'static, const J: usize> {
    /// The arm.
    pub robot: &'static Robot<T, J>,
    /// World pose of each link frame (see [`Robot::frame_names`]); identity past the arm's.
    pub frames: [Pose<T>; MAX_FRAMES],
    /// World pose of each collision box (centre and axes; see [`Robot::body_names`]).
    pub boxes: [Pose<T>; MAX_BODIES],
}

impl<T: Real, const J: usize> PartialEq for Kinematics<T, J> {
    fn eq(&self, other: &Self) -> bool {
        core::ptr::eq(self.robot, other.robot) && self.frames == other.frames && self.boxes == other.boxes
    }
}

impl<T: Real, const J: usize> core::fmt::Debug for Kinematics<T, J> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Kinematics")
            .field("robot", &self.robot.name)
            .field("frames", &&self.frames[..self.robot.frames.len().min(MAX_FRAMES)])
            .field("boxes", &&self.boxes[..self.robot.bodies.len().min(MAX_BODIES)])
            .finish()
    }
}

/// Corner `k` of the box with half extents `half` at `pose` (bit `i` of `k` set: `+half_i`).
pub fn box_corner<T: Real>(pose: &Pose<T>, half: &Vector3<T>, k: usize) -> Vector3<T> {
    let s = |bit: usize, h: T| if k >> bit & 1 == 1 { h } else { -h };
    pose.transform_point(&Vector3::new(s(0, half.x), s(1, half.y), s(2, half.z)))
}

/// Forward kinematics: world pose of every frame and collision box, each finger (if the arm
/// has a gripper) at the default opening (0.025 m for the Panda). See [`forward_with`].
///
/// Any finite angle is accepted (limits are the planner's business); NaN or infinity is
/// refused with [`Error::NonFiniteJoint`], so every output is finite.
pub fn forward<T: Real, const J: usize>(robot: &'static Robot<T, J>, q: &[T; J]) -> Result<Kinematics<T, J>, Error> {
    forward_with(robot, q, robot.gripper.map_or(T::zero(), |g| g.default))
}

/// Forward kinematics with each finger opened to `finger` metres (the value of both finger
/// joints; the fingers' frames slide by it along their prismatic axes). With the default
/// opening the result is [`forward`]'s, bit for bit.
///
/// Joints as in [`forward`] (checked first); an opening outside the URDF's finger limits
/// ([`crate::robot::Gripper`]), or NaN, is [`Error::BadParameter`]; an arm without a gripper
/// takes 0 only.
pub fn forward_with<T: Real, const J: usize>(
    robot: &'static Robot<T, J>,
    q: &[T; J],
    finger: T,
) -> Result<Kinematics<T, J>, Error> {
    let mut k = Kinematics {
        robot,
        frames: [Pose::identity(); MAX_FRAMES],
        boxes: [Pose::identity(); MAX_BODIES],
    };
    forward_into(q, finger, &mut k)?;
    Ok(k)
}

/// [`forward_with`] into `out`, for `out`'s arm, in place (the costs' inner loop: no copy of
/// the result). On an error `out` is unchanged.
pub fn forward_into<T: Real, const J: usize>(q: &[T; J], finger: T, out: &mut Kinematics<T, J>) -> Result<(), Error> {
    for (i, &qi) in q.iter().enumerate() {
        if !qi.finite() {
            return Err(Error::NonFiniteJoint { joint: i as u8 });
        }
    }
    let robot = out.robot;
    let (lower, upper) = robot.gripper.map_or((T::zero(), T::zero()), |g| (g.lower, g.upper));
    if !(finger >= lower && finger <= upper) {
        return Err(Error::BadParameter);
    }
    let frames = &mut out.frames;
    frames[0] = Pose::identity();
    // `get`: the tables are well formed (parents before children, within MAX_FRAMES), and the
    // lookups say so without a panic path.
    for (i, spec) in robot.frames.iter().enumerate().skip(1) {
        let rotation = match spec.joint.and_then(|j| q.get(j)) {
            Some(&angle) => {
                let (s, c) = angle.sin_cos_libm();
                spec.rot_fixed + spec.rot_cos * c + spec.rot_sin * s
            }
            None => spec.rot_fixed,
        };
        let translation = match &spec.slide {
            Some(slide) => spec.translation + slide * finger,
            None => spec.translation,
        };
        let parent = frames
            .get(spec.parent.min(i - 1))
            .copied()
            .unwrap_or_else(Pose::identity);
        let Some(frame) = frames.get_mut(i) else { break };
        *frame = parent.compose(&rotation, &translation);
    }
    for (pose, body) in out.boxes.iter_mut().zip(robot.bodies.iter()) {
        let frame = out.frames.get(body.frame).copied().unwrap_or_else(Pose::identity);
        *pose = frame.compose(&body.rotation, &body.center);
    }
    Ok(())
}

impl<T: Real, const J: usize> Kinematics<T, J> {
    /// World pose of the tool centre point (the Panda's `panda_grasptarget`).
    pub fn tcp(&self) -> &Pose<T> {
        &self.frames[self.robot.tcp_frame.min(MAX_FRAMES - 1)]
    }

    /// The 8 world corners of collision body `body` (see [`CORNERS`] for the order); an
    /// out-of-range `body` gives a point box at the origin.
    pub fn corners(&self, body: usize) -> [Vector3<T>; CORNERS] {
        let half = self
            .robot
            .bodies
            .get(body)
            .map_or_else(Vector3::zeros, |b| b.half_extents);
        let pose = &self.boxes[body % MAX_BODIES];
        core::array::from_fn(|k| box_corner(pose, &half, k))
    }

    /// The corners of every collision body (point boxes past the arm's bodies).
    pub fn all_corners(&self) -> [[Vector3<T>; CORNERS]; MAX_BODIES] {
        core::array::from_fn(|b| self.corners(b))
    }

    /// Reverse mode: the gradient with respect to the joints of a scalar whose gradient with
    /// respect to every box corner is `corner_grad`.
    pub fn adjoint(&self, corner_grad: &CornerGradient<T>) -> Result<[T; J], Error> {
        let robot = self.robot;
        let last = robot.frames.len().clamp(1, MAX_FRAMES) - 1;
        let mut cot = Cotangent::new();
        for (b, (grads, body)) in corner_grad.iter().zip(robot.bodies).enumerate() {
            // Costs pull on few bodies at a time: skip the rest without placing their corners.
            let mut any = false;
            for g in grads {
                any |= g.x != T::zero() || g.y != T::zero() || g.z != T::zero();
            }
            if !any {
                cot.probe(grads);
                continue;
            }
            cot.probe(grads);
            let (mut force, mut moment) = (Vector3::zeros(), Vector3::zeros());
            for (c, g) in self.corners(b).iter().zip(grads.iter()) {
                force += g;
                moment += c.cross(g);
            }
            // `% MAX_FRAMES`: the frame is below `last`; the modulo says so without a panic path.
            let frame = body.frame.min(last) % MAX_FRAMES;
            cot.force[frame] += force;
            cot.moment[frame] += moment;
        }
        self.joint_gradient(&cot)
    }

    /// Reverse mode for any upstream gradient collected in `cot`: one leaf-to-root sweep.
    pub fn joint_gradient(&self, cot: &Cotangent<T>) -> Result<[T; J], Error> {
        // x·0 is 0 for every finite x and NaN otherwise: the probe saw every input.
        if cot.probe != T::zero() {
            return Err(Error::NonFiniteGradient);
        }
        let robot = self.robot;
        let (mut force, mut moment) = (cot.force, cot.moment);
        let mut dq = [T::zero(); J];
        for (i, spec) in robot.frames.iter().enumerate().take(MAX_FRAMES).skip(1).rev() {
            // `% MAX_FRAMES` (a no-op: `take`) keeps the indexing free of panic paths.
            let i = i % MAX_FRAMES;
            if let Some(slot) = spec.joint.and_then(|j| dq.get_mut(j)) {
                let pose = &self.frames[i];
                let axis = pose.rotation * spec.axis;
                *slot = axis.dot(&(moment[i] - pose.translation.cross(&force[i])));
            }
            let parent = spec.parent.min(i.saturating_sub(1));
            let (f, m) = (force[i], moment[i]);
            force[parent] += f;
            moment[parent] += m;
        }
        let mut probe = T::zero();
        for &x in &dq {
            probe += x * T::zero();
        }
        if probe == T::zero() {
            Ok(dq)
        } else {
            Err(Error::Overflow)
        }
    }

    /// The 6×J geometric Jacobian of frame `frame`: rows 0-2 the linear velocity of its origin,
    /// rows 3-5 its angular velocity, per unit joint rate. Joints that do not move the frame
    /// give zero columns; an out-of-range `frame` gives all zeros.
    pub fn jacobian(&self, frame: usize) -> [[T; J]; 6] {
        let robot = self.robot;
        let mut jac = [[T::zero(); J]; 6];
        if frame >= robot.frames.len().min(MAX_FRAMES) {
            return jac;
        }
        let target = self.frames[frame].translation;
        for (i, spec) in robot.frames.iter().enumerate().take(MAX_FRAMES) {
            let Some(j) = spec.joint.filter(|&j| j < J) else {
                continue;
            };
            if !robot.is_ancestor(i, frame) {
                continue;
            }
            let pose = &self.frames[i];
            let axis = pose.rotation * spec.axis;
            let linear = axis.cross(&(target - pose.translation));
            for r in 0..3 {
                jac[r][j] = linear[r];
                jac[r + 3][j] = axis[r];
            }
        }
        jac
    }

    /// The TCP Jacobian (see [`Self::jacobian`]); inverse kinematics uses it.
    pub fn tcp_jacobian(&self) -> [[T; J]; 6] {
        self.jacobian(self.robot.tcp_frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{BODIES, FRAMES, PANDA, PANDA_F64};

    const READY: [f32; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

    #[test]
    fn refuses_non_finite_joints() {
        let mut q = READY;
        q[3] = f32::NAN;
        assert_eq!(forward(&PANDA, &q), Err(Error::NonFiniteJoint { joint: 3 }));
        q[3] = f32::INFINITY;
        assert_eq!(forward(&PANDA, &q), Err(Error::NonFiniteJoint { joint: 3 }));
    }

    #[test]
    fn refuses_non_finite_gradients_and_reports_overflow() {
        let k = forward(&PANDA, &READY).unwrap();
        let mut g = [[Vector3::zeros(); CORNERS]; MAX_BODIES];
        g[4][2].y = f32::NAN;
        assert_eq!(k.adjoint(&g), Err(Error::NonFiniteGradient));
        let g = [[Vector3::repeat(f32::MAX); CORNERS]; MAX_BODIES];
        assert_eq!(k.adjoint(&g), Err(Error::Overflow));
    }

    #[test]
    fn zero_configuration_tcp_is_straight_up_and_forward() {
        // All-zero joints: the arm stands up with the flange offset along +x.
        let k = forward(&PANDA_F64, &[0.0f64; 7]).unwrap();
        let p = k.tcp().translation;
        assert!((p.x - 0.088).abs() < 1e-9, "{p}");
        assert!(p.y.abs() < 1e-9, "{p}");
        assert!((p.z - (0.333 + 0.316 + 0.384 - 0.107 - 0.105)).abs() < 1e-9, "{p}");
    }

    #[test]
    fn the_fingers_slide_by_the_opening_along_the_hands_y() {
        use crate::robot::{FINGER_OPENING_DEFAULT, HAND_FRAME};
        let (left, right) = (10, 11);
        let base = forward(&PANDA, &READY).unwrap();
        // The default opening is `forward`'s, bit for bit.
        assert_eq!(forward_with(&PANDA, &READY, FINGER_OPENING_DEFAULT).unwrap(), base);
        let q64 = READY.map(f64::from);
        for w in [0.0, 0.01, 0.025, 0.04] {
            let k = forward_with(&PANDA_F64, &q64, w).unwrap();
            let hand = &k.frames[HAND_FRAME];
            let y = hand.rotation.column(1).into_owned();
            // In the hand frame: each finger sits at (0, ±w, 0.0584), the URDF's origin.
            let l = hand.rotation.transpose() * (k.frames[left].translation - hand.translation);
            let r = hand.rotation.transpose() * (k.frames[right].translation - hand.translation);
            assert!((l - Vector3::new(0.0, w, 0.0584)).norm() < 1e-12, "{w}: {l}");
            assert!((r - Vector3::new(0.0, -w, 0.0584)).norm() < 1e-12, "{w}: {r}");
            // The fingers are 2w apart along the hand's y, their orientation the hand's.
            let gap = k.frames[left].translation - k.frames[right].translation;
            assert!((gap - y * (2.0 * w)).norm() < 1e-12, "{w}: {gap}");
            assert!((k.frames[left].rotation - hand.rotation).norm() < 1e-12);
            // Nothing else moves: every other frame and box is the default's.
            let d = forward(&PANDA_F64, &q64).unwrap();
            for f in (0..FRAMES).filter(|&f| f != left && f != right) {
                assert_eq!(k.frames[f], d.frames[f], "frame {f}");
            }
            for b in 0..BODIES - 2 {
                assert_eq!(k.boxes[b], d.boxes[b], "box {b}");
            }
            // The finger boxes move rigidly with their frames.
            let shift = (w - 0.025) * y;
            assert!((k.boxes[BODIES - 2].translation - d.boxes[BODIES - 2].translation - shift).norm() < 1e-12);
            assert!((k.boxes[BODIES - 1].translation - d.boxes[BODIES - 1].translation + shift).norm() < 1e-12);
        }
    }

    #[test]
    fn refuses_openings_outside_the_finger_limits() {
        for w in [f32::NAN, -1e-6, 0.0401, f32::INFINITY, -f32::INFINITY] {
            assert_eq!(forward_with(&PANDA, &READY, w), Err(Error::BadParameter), "{w}");
        }
        assert!(forward_with(&PANDA, &READY, 0.0).is_ok() && forward_with(&PANDA, &READY, 0.04).is_ok());
        // A bad joint is named first.
        let mut q = READY;
        q[2] = f32::NAN;
        assert_eq!(
            forward_with(&PANDA, &q, f32::NAN),
            Err(Error::NonFiniteJoint { joint: 2 })
        );
    }

    #[test]
    fn rotations_stay_orthonormal() {
        let k = forward(&PANDA, &READY).unwrap();
        for pose in k.frames.iter().chain(k.boxes.iter()) {
            let err = (pose.rotation.transpose() * pose.rotation - Matrix3::identity()).norm();
            assert!(err < 1e-5, "{err}");
        }
    }
}
