//! MpiNets-style scene families and their planning problems (numbers from
//! `shared/notes/mpinets-scenes.md`; simplifications are said where they are made).
//!
//! A generator returns obstacles plus the volumes where the gripper may be asked to go; a
//! problem is then a start and a goal (task-oriented: both poses in those volumes; neutral
//! start / neutral goal: one end near the robot's neutral configuration), each end solved to
//! joints by the core's collision-checked IK, and accepted only when RRT-Connect connects them.

mod cubby;
mod dresser;
mod tabletop;

use edmp_core::checker::{CheckConfig, check_state};
use edmp_core::ik::{IkConfig, solve};
use edmp_core::kinematics::{Joints, Pose};
use edmp_core::rng::Rng;
use edmp_core::robot::PANDA;
use edmp_core::scene::{MAX_OBSTACLES, Obstacle, Scene};
use nalgebra::{Matrix3, Rotation3, Vector3};
use serde_json::{Value, json};

/// The four MpiNets scene families.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Family {
    /// Table with boxes and cylinders on it.
    Tabletop,
    /// A 2×2 shelf of cubbies.
    Cubby,
    /// Cubbies with the wall between start and goal removed.
    MergedCubby,
    /// A dresser with drawers, two of them open.
    Dresser,
}

impl Family {
    /// Every family, in suite order.
    pub(crate) const ALL: [Family; 4] = [Family::Tabletop, Family::Cubby, Family::MergedCubby, Family::Dresser];

    /// The name used in file names and JSON.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Family::Tabletop => "tabletop",
            Family::Cubby => "cubby",
            Family::MergedCubby => "merged_cubby",
            Family::Dresser => "dresser",
        }
    }
}

/// A primitive as the scene format writes it (quaternion `[w, x, y, z]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Prim {
    Cuboid {
        center: [f32; 3],
        dims: [f32; 3],
        quaternion: [f32; 4],
    },
    Cylinder {
        center: [f32; 3],
        radius: f32,
        height: f32,
        quaternion: [f32; 4],
    },
}

impl Prim {
    fn obstacle(&self) -> Option<Obstacle> {
        match *self {
            Prim::Cuboid {
                center,
                dims,
                quaternion,
            } => Obstacle::cuboid(center, dims, quaternion).ok(),
            Prim::Cylinder {
                center,
                radius,
                height,
                quaternion,
            } => Obstacle::cylinder(center, radius, height, quaternion).ok(),
        }
    }

    fn json(&self) -> Value {
        match self {
            Prim::Cuboid {
                center,
                dims,
                quaternion,
            } => {
                json!({"type": "cuboid", "center": center, "dims": dims, "quaternion": quaternion})
            }
            Prim::Cylinder {
                center,
                radius,
                height,
                quaternion,
            } => {
                json!({"type": "cylinder", "center": center, "radius": radius, "height": height, "quaternion": quaternion})
            }
        }
    }
}

/// The quaternion `[w, x, y, z]` of a turn by `yaw` about world z.
pub(crate) fn yaw_quaternion(yaw: f32) -> [f32; 4] {
    [(yaw * 0.5).cos(), 0.0, 0.0, (yaw * 0.5).sin()]
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
    fn sample(&self, rng: &mut Rng) -> Pose<f32> {
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
        };
        Pose { rotation, translation }
    }
}

/// One generated environment: its obstacles, and the regions for start and goal.
#[derive(Clone, Debug)]
pub(crate) struct Environment {
    pub prims: Vec<Prim>,
    /// Candidate regions; a task-oriented problem takes its ends from two of them.
    pub regions: Vec<Region>,
}

impl Environment {
    /// The environment as a core scene (`None` if a primitive is invalid or too many).
    pub(crate) fn scene(&self) -> Option<Scene<MAX_OBSTACLES>> {
        let mut scene = Scene::new();
        for p in &self.prims {
            scene.push(p.obstacle()?).ok()?;
        }
        Some(scene)
    }
}

/// MpiNets' neutral configuration (robofin `FrankaRobot.NEUTRAL`, shared/notes).
pub(crate) const NEUTRAL: Joints<f32> = [-0.0178, -0.7601, 0.0198, -2.3421, 0.0298, 1.5412, 0.7534];

/// The three MpiNets problem kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    TaskOriented,
    NeutralStart,
    NeutralGoal,
}

impl Kind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Kind::TaskOriented => "task_oriented",
            Kind::NeutralStart => "neutral_start",
            Kind::NeutralGoal => "neutral_goal",
        }
    }
}

/// A problem, ready to plan.
#[derive(Clone, Debug)]
pub(crate) struct Problem {
    pub family: Family,
    pub kind: Kind,
    pub seed: u64,
    pub env: Environment,
    pub scene: Scene<MAX_OBSTACLES>,
    pub start: Joints<f32>,
    pub goal: Joints<f32>,
    pub goal_pose: Pose<f32>,
}

/// Generates one environment of `family`.
pub(crate) fn environment(family: Family, rng: &mut Rng) -> Environment {
    match family {
        Family::Tabletop => tabletop::generate(rng),
        Family::Cubby => cubby::generate(rng, false),
        Family::MergedCubby => cubby::generate(rng, true),
        Family::Dresser => dresser::generate(rng),
    }
}

/// A collision-free configuration reaching a random pose of `region`, tried `attempts` times.
pub(crate) fn reach(
    scene: &Scene<MAX_OBSTACLES>,
    region: &Region,
    rng: &mut Rng,
    attempts: u32,
) -> Option<(Joints<f32>, Pose<f32>)> {
    let ik = IkConfig {
        starts: 16,
        max_solutions: 1,
        ..IkConfig::default()
    };
    for _ in 0..attempts {
        let pose = region.sample(rng);
        if let Ok(s) = solve(&pose, &NEUTRAL, scene, &ik) {
            let reached = *edmp_core::kinematics::forward(&s.joints).ok()?.tcp();
            return Some((s.joints, reached));
        }
    }
    None
}

/// `NEUTRAL + U(0, 0.25)` per joint, collision-free (MpiNets' neutral candidates).
pub(crate) fn neutral(scene: &Scene<MAX_OBSTACLES>, rng: &mut Rng) -> Option<Joints<f32>> {
    for _ in 0..50 {
        let q: Joints<f32> =
            core::array::from_fn(|j| (NEUTRAL[j] + rng.uniform_f32(0.0, 0.25)).min(PANDA.soft_upper[j]));
        if check_state(scene, &q, &CheckConfig::default()) == Ok(None) {
            return Some(q);
        }
    }
    None
}

/// Draws a problem of `family` and `kind` from `seed`: `None` when this seed's environment
/// gives no reachable, collision-free ends (the caller moves on to the next seed).
pub(crate) fn problem(family: Family, kind: Kind, seed: u64) -> Option<Problem> {
    let mut rng = Rng::new(seed);
    let env = environment(family, &mut rng);
    let scene = env.scene()?;
    let n = env.regions.len() as u32;
    let first = rng.below(n) as usize;
    // Task-oriented ends come from different regions when there are several (cubby pockets,
    // drawers); neutral problems use one region for their posed end.
    let second = if n > 1 {
        (first + 1 + rng.below(n - 1) as usize) % n as usize
    } else {
        first
    };
    let (start, goal, goal_pose) = match kind {
        Kind::TaskOriented => {
            let (s, _) = reach(&scene, &env.regions[first], &mut rng, 20)?;
            let (g, pose) = reach(&scene, &env.regions[second], &mut rng, 20)?;
            (s, g, pose)
        }
        Kind::NeutralStart => {
            let s = neutral(&scene, &mut rng)?;
            let (g, pose) = reach(&scene, &env.regions[second], &mut rng, 20)?;
            (s, g, pose)
        }
        Kind::NeutralGoal => {
            let (s, _) = reach(&scene, &env.regions[first], &mut rng, 20)?;
            let g = neutral(&scene, &mut rng)?;
            let pose = *edmp_core::kinematics::forward(&g).ok()?.tcp();
            (s, g, pose)
        }
    };
    Some(Problem {
        family,
        kind,
        seed,
        env,
        scene,
        start,
        goal,
        goal_pose,
    })
}

impl Problem {
    /// The problem as an `edmp-scene/1` document (joint goal), with the matching TCP pose goal
    /// and provenance under the optional `meta` field.
    pub(crate) fn json(&self) -> Value {
        let q = self.goal_pose.quaternion_wxyz();
        json!({
            "format": "edmp-scene/1",
            "obstacles": self.env.prims.iter().map(Prim::json).collect::<Vec<_>>(),
            "start": self.start,
            "goal": {"joints": self.goal},
            "meta": {
                "family": self.family.name(),
                "kind": self.kind.name(),
                "seed": self.seed,
                "goal_pose": {
                    "position": [self.goal_pose.translation.x, self.goal_pose.translation.y, self.goal_pose.translation.z],
                    "quaternion": q,
                },
            },
        })
    }
}
