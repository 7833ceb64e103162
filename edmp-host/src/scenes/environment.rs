//! What every scene generator builds with: primitives placed in a frame on the table, regions
//! where ends may lie and how the arm approaches them, clutter, and the environment they make.

use edmp_core::rng::Rng;
use edmp_core::robot::kinematics::Pose;
use edmp_core::scene::{MAX_OBSTACLES, Primitive, Scene};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// The quaternion `[w, x, y, z]` of a turn by `yaw` about world z.
pub(crate) fn yaw_quaternion(yaw: f32) -> [f32; 4] {
    [(yaw * 0.5).cos(), 0.0, 0.0, (yaw * 0.5).sin()]
}

/// A structure's own frame for the unseen kinds: origin on the floor at the middle of its
/// front, local x pointing away from the robot (into the structure), y to its left, z up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    origin: [f32; 2],
    pub yaw: f32,
}

impl Frame {
    /// In front of the robot, within its reach: the front's middle `distance` from the base on
    /// a bearing of U(−bearing, bearing), the structure turned to face the base up to ±`jitter`.
    pub(crate) fn facing(rng: &mut Rng, distance: [f32; 2], bearing: f32, jitter: f32) -> Frame {
        let heading = rng.uniform_f32(-bearing, bearing);
        let d = rng.uniform_f32(distance[0], distance[1]);
        let yaw = heading + rng.uniform_f32(-jitter, jitter);
        Frame {
            origin: [d * heading.cos(), d * heading.sin()],
            yaw,
        }
    }

    /// A local point in the world.
    pub(crate) fn point(&self, p: [f32; 3]) -> [f32; 3] {
        let (s, c) = self.yaw.sin_cos();
        [
            self.origin[0] + c * p[0] - s * p[1],
            self.origin[1] + s * p[0] + c * p[1],
            p[2],
        ]
    }

    /// The cuboid spanning local `lo` to `hi`, turned with the frame.
    pub(crate) fn cuboid(&self, lo: [f32; 3], hi: [f32; 3]) -> Primitive {
        Primitive::Cuboid {
            center: self.point(core::array::from_fn(|i| (lo[i] + hi[i]) / 2.0)),
            dims: core::array::from_fn(|i| hi[i] - lo[i]),
            quaternion: yaw_quaternion(self.yaw),
        }
    }

    /// An upright cylinder standing at local `(x, y, z)`.
    pub(crate) fn cylinder(&self, foot: [f32; 3], radius: f32, height: f32) -> Primitive {
        Primitive::Cylinder {
            center: self.point([foot[0], foot[1], foot[2] + height / 2.0]),
            radius,
            height,
            quaternion: yaw_quaternion(self.yaw),
        }
    }

    /// The region spanning local `lo` to `hi`.
    pub(crate) fn region(&self, lo: [f32; 3], hi: [f32; 3], approach: Approach) -> Region {
        Region {
            center: self.point(core::array::from_fn(|i| (lo[i] + hi[i]) / 2.0)),
            half: core::array::from_fn(|i| (hi[i] - lo[i]) / 2.0),
            yaw: self.yaw,
            approach,
        }
    }

    /// Horizontal distance from the robot's base to a local point (to drop unreachable regions).
    pub(crate) fn reach_of(&self, p: [f32; 3]) -> f32 {
        let w = self.point(p);
        (w[0] * w[0] + w[1] * w[1]).sqrt()
    }
}

/// Up to `count` cans (cylinders) and small boxes standing on the local rectangle
/// `area` = [x range, y range] at height `z`, each at most `max_height` tall, inside the rectangle and 3 cm apart (bounding
/// circles). Fewer are placed when the rectangle is crowded.
pub(crate) fn clutter(
    frame: &Frame,
    rng: &mut Rng,
    area: [[f32; 2]; 2],
    z: f32,
    max_height: f32,
    count: usize,
    out: &mut Vec<Primitive>,
) {
    let [x, y] = area;
    if max_height < 0.06 {
        return;
    }
    let mut placed: Vec<([f32; 2], f32)> = Vec::new();
    for _ in 0..10 * count {
        if placed.len() >= count {
            break;
        }
        let height = rng.uniform_f32(0.06, max_height);
        let can = rng.unit_f32() < 0.5;
        let (radius, dims, yaw) = if can {
            let r = rng.uniform_f32(0.025, 0.045);
            (r, [2.0 * r; 2], 0.0)
        } else {
            let d = [rng.uniform_f32(0.04, 0.12), rng.uniform_f32(0.03, 0.1)];
            (
                0.5 * (d[0] * d[0] + d[1] * d[1]).sqrt(),
                d,
                rng.uniform_f32(0.0, core::f32::consts::PI),
            )
        };
        if x[1] - x[0] < 2.0 * radius || y[1] - y[0] < 2.0 * radius {
            continue;
        }
        let c = [
            rng.uniform_f32(x[0] + radius, x[1] - radius),
            rng.uniform_f32(y[0] + radius, y[1] - radius),
        ];
        if placed
            .iter()
            .any(|(p, r)| ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)).sqrt() < r + radius + 0.03)
        {
            continue;
        }
        placed.push((c, radius));
        if can {
            out.push(frame.cylinder([c[0], c[1], z], radius, height));
        } else {
            out.push(Primitive::Cuboid {
                center: frame.point([c[0], c[1], z + height / 2.0]),
                dims: [dims[0], dims[1], height],
                quaternion: yaw_quaternion(frame.yaw + yaw),
            });
        }
    }
}

/// How the gripper faces in a region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Approach {
    /// Roughly top-down (tabletop): roll U(3π/4, 5π/4), pitch U(−π/8, π/8), yaw U(−π/2, π/2).
    RoughlyDown,
    /// Exactly top-down, yaw U(−π/4, π/4) about `yaw` (dresser drawers).
    Down { yaw: f32 },
    /// Horizontal, U(−π/4, π/4) from the +x axis turned by `yaw`; gripper x = −world z (cubbies).
    Horizontal { yaw: f32 },
    /// Horizontal, U(−spread, spread) from the +x axis turned by `yaw`. `upright`: the fingers
    /// open along world z (the hand's wide side vertical, to pass between vertical bars);
    /// otherwise gripper x = −world z as in `Horizontal` (wide side horizontal, between boards).
    Level { yaw: f32, spread: f32, upright: bool },
}

/// A box-shaped volume the gripper may be sent into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Region {
    pub center: [f32; 3],
    pub half: [f32; 3],
    pub yaw: f32,
    pub approach: Approach,
}

impl Region {
    /// A random TCP pose in the region.
    pub(crate) fn sample(&self, rng: &mut Rng) -> Pose<f32> {
        let local = Vector3::new(
            rng.uniform_f32(-self.half[0], self.half[0]),
            rng.uniform_f32(-self.half[1], self.half[1]),
            rng.uniform_f32(-self.half[2], self.half[2]),
        );
        let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), self.yaw);
        let translation = Vector3::from(self.center) + turn * local;
        let rotation: Matrix3<f32> = match self.approach {
            Approach::RoughlyDown => {
                let roll = rng.uniform_f32(0.75 * core::f32::consts::PI, 1.25 * core::f32::consts::PI);
                let pitch = rng.uniform_f32(-core::f32::consts::FRAC_PI_8, core::f32::consts::FRAC_PI_8);
                let yaw = rng.uniform_f32(-core::f32::consts::FRAC_PI_2, core::f32::consts::FRAC_PI_2);
                Rotation3::from_euler_angles(roll, pitch, yaw).into_inner()
            }
            Approach::Down { yaw } => {
                let turn = yaw + rng.uniform_f32(-core::f32::consts::FRAC_PI_4, core::f32::consts::FRAC_PI_4);
                (Rotation3::from_axis_angle(&Vector3::z_axis(), turn)
                    * Rotation3::from_axis_angle(&Vector3::x_axis(), core::f32::consts::PI))
                .into_inner()
            }
            Approach::Horizontal { yaw } => {
                let theta = yaw + rng.uniform_f32(-core::f32::consts::FRAC_PI_4, core::f32::consts::FRAC_PI_4);
                let z = Vector3::new(theta.cos(), theta.sin(), 0.0);
                let x = Vector3::new(0.0, 0.0, -1.0);
                Matrix3::from_columns(&[x, z.cross(&x), z])
            }
            Approach::Level { yaw, spread, upright } => {
                let theta = yaw + rng.uniform_f32(-spread, spread);
                let z = Vector3::new(theta.cos(), theta.sin(), 0.0);
                if upright {
                    let y = Vector3::new(0.0, 0.0, 1.0);
                    Matrix3::from_columns(&[y.cross(&z), y, z])
                } else {
                    let x = Vector3::new(0.0, 0.0, -1.0);
                    Matrix3::from_columns(&[x, z.cross(&x), z])
                }
            }
        };
        Pose { rotation, translation }
    }
}

/// One generated environment: its obstacles, and the regions for start and goal.
#[derive(Clone, Debug)]
pub(crate) struct Environment {
    pub prims: Vec<Primitive>,
    /// Candidate regions; a task-oriented problem takes its ends from two of them.
    pub regions: Vec<Region>,
    /// Goal regions (the unseen kinds): when not empty, posed goals come from here and
    /// `regions` holds the task-oriented starts. Empty for the MpiNets families.
    pub goals: Vec<Region>,
}

impl Environment {
    /// The environment as a core scene (`None` if a primitive is invalid or too many).
    pub(crate) fn scene(&self) -> Option<Scene<'static, MAX_OBSTACLES>> {
        let mut scene = Scene::new();
        for p in &self.prims {
            scene.push(p.to_obstacle().ok()?).ok()?;
        }
        Some(scene)
    }
}
