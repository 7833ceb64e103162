//! MpiNets-style scene families and their planning problems (numbers from
//! MpiNets' scene generation, NVlabs/motion-policy-networks; simplifications are said where they are made).
//!
//! A generator returns obstacles plus the volumes where the gripper may be asked to go; a
//! problem is then a start and a goal (task-oriented: both poses in those volumes; neutral
//! start / neutral goal: one end near the robot's neutral configuration), each end solved to
//! joints by the core's collision-checked IK, and accepted only when RRT-Connect connects them.
//!
//! Four more kinds (cage, window box, bookshelf, under table) are never drawn for training: they
//! make the unseen suite, which measures how the prior generalizes.

mod bookshelf;
mod cage;
mod cubby;
mod dresser;
mod environment;
mod tabletop;
mod under_table;
mod window_box;

use crate::formats::json::primitive_json;
use edmp_core::collision::checker::{CheckConfig, check_state};
use edmp_core::rng::Rng;
use edmp_core::robot::ik::{IkConfig, solve};
use edmp_core::robot::kinematics::{Joints, Pose};
use edmp_core::robot::{JOINTS, PANDA, Robot};
use edmp_core::scene::{MAX_OBSTACLES, Scene};
pub(crate) use environment::{Environment, Region};
use serde_json::{Value, json};

/// The four MpiNets scene families (the training families) and the four unseen kinds.
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
    /// Unseen: a closed cage whose front is vertical bars; the goal inside, through a slot.
    Cage,
    /// Unseen: a closed box with a window in its front wall; the goal inside.
    WindowBox,
    /// Unseen: a bookshelf of 2-6 boards with cans and boxes; goals between boards.
    Bookshelf,
    /// Unseen: a table or shelf; the goal under its top, the start above or beside it.
    UnderTable,
}

impl Family {
    /// The training families, in suite order: the only ones `gen-data` draws.
    pub(crate) const ALL: [Family; 4] = [Family::Tabletop, Family::Cubby, Family::MergedCubby, Family::Dresser];

    /// The kinds the prior never sees in training (the unseen suite), in suite order.
    pub(crate) const UNSEEN: [Family; 4] = [Family::Cage, Family::WindowBox, Family::Bookshelf, Family::UnderTable];

    /// The name used in file names and JSON.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Family::Tabletop => "tabletop",
            Family::Cubby => "cubby",
            Family::MergedCubby => "merged_cubby",
            Family::Dresser => "dresser",
            Family::Cage => "cage",
            Family::WindowBox => "window_box",
            Family::Bookshelf => "bookshelf",
            Family::UnderTable => "under_table",
        }
    }
}

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

/// A problem for an arm of `J` joints, ready to plan.
#[derive(Clone, Debug)]
pub(crate) struct Problem<const J: usize = JOINTS> {
    pub robot: &'static Robot<f32, J>,
    pub family: Family,
    pub kind: Kind,
    pub seed: u64,
    pub env: Environment,
    pub scene: Scene<'static, MAX_OBSTACLES>,
    pub start: Joints<f32, J>,
    pub goal: Joints<f32, J>,
    pub goal_pose: Pose<f32>,
}

/// Generates one environment of `family`.
pub(crate) fn environment(family: Family, rng: &mut Rng) -> Environment {
    match family {
        Family::Tabletop => tabletop::generate(rng),
        Family::Cubby => cubby::generate(rng, false),
        Family::MergedCubby => cubby::generate(rng, true),
        Family::Dresser => dresser::generate(rng),
        Family::Cage => cage::generate(rng),
        Family::WindowBox => window_box::generate(rng),
        Family::Bookshelf => bookshelf::generate(rng),
        Family::UnderTable => under_table::generate(rng),
    }
}

/// A collision-free configuration of `robot` reaching a random pose of `region`, tried
/// `attempts` times.
pub(crate) fn reach<const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<MAX_OBSTACLES>,
    region: &Region,
    rng: &mut Rng,
    attempts: u32,
) -> Option<([f32; J], Pose<f32>)> {
    // The planner's 2 mm rather than the valid-end rule: generated ends keep the room the
    // committed suite was made with.
    let ik = IkConfig {
        starts: 16,
        max_solutions: 1,
        clearance: edmp_core::collision::checker::DEFAULT_MARGIN,
        ..IkConfig::default()
    };
    for _ in 0..attempts {
        let pose = region.sample(rng);
        if let Ok(s) = solve(robot, &pose, &robot.neutral, scene, &ik) {
            let reached = *edmp_core::robot::kinematics::forward(robot, &s.joints).ok()?.tcp();
            return Some((s.joints, reached));
        }
    }
    None
}

/// `neutral + U(0, 0.25)` per joint, collision-free (MpiNets' neutral candidates).
pub(crate) fn neutral<const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<MAX_OBSTACLES>,
    rng: &mut Rng,
) -> Option<[f32; J]> {
    for _ in 0..50 {
        let q: [f32; J] =
            core::array::from_fn(|j| (robot.neutral[j] + rng.uniform_f32(0.0, 0.25)).min(robot.soft_upper[j]));
        if check_state(robot, scene, &q, &CheckConfig::default()) == Ok(None) {
            return Some(q);
        }
    }
    None
}

/// Draws `robot`'s problem of `family` and `kind` from `seed`: `None` when this seed's
/// environment gives no reachable, collision-free ends (the caller moves on to the next seed).
/// Every arm gets the same environment from a seed; the ends are its own (its IK in the same
/// regions, its neutral configuration).
pub(crate) fn problem_for<const J: usize>(
    robot: &'static Robot<f32, J>,
    family: Family,
    kind: Kind,
    seed: u64,
) -> Option<Problem<J>> {
    let mut rng = Rng::new(seed);
    let env = environment(family, &mut rng);
    let scene = env.scene()?;
    if !env.goals.is_empty() {
        return targeted(robot, family, kind, seed, env, scene, &mut rng);
    }
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
            let (s, _) = reach(robot, &scene, &env.regions[first], &mut rng, 20)?;
            let (g, pose) = reach(robot, &scene, &env.regions[second], &mut rng, 20)?;
            (s, g, pose)
        }
        Kind::NeutralStart => {
            let s = neutral(robot, &scene, &mut rng)?;
            let (g, pose) = reach(robot, &scene, &env.regions[second], &mut rng, 20)?;
            (s, g, pose)
        }
        Kind::NeutralGoal => {
            let (s, _) = reach(robot, &scene, &env.regions[first], &mut rng, 20)?;
            let g = neutral(robot, &scene, &mut rng)?;
            let pose = *edmp_core::robot::kinematics::forward(robot, &g).ok()?.tcp();
            (s, g, pose)
        }
    };
    Some(Problem {
        robot,
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

/// A problem of an environment with goal regions (the unseen kinds): the posed goal (or, for
/// a neutral goal, the posed start) in a goal region, a task-oriented start in another region.
fn targeted<const J: usize>(
    robot: &'static Robot<f32, J>,
    family: Family,
    kind: Kind,
    seed: u64,
    env: Environment,
    scene: Scene<'static, MAX_OBSTACLES>,
    rng: &mut Rng,
) -> Option<Problem<J>> {
    let target = env.goals[rng.below(env.goals.len() as u32) as usize];
    // A task-oriented start avoids the goal's own region when there is another one.
    let others: Vec<&Region> = env.regions.iter().filter(|r| **r != target).collect();
    let (start, goal, goal_pose) = match kind {
        Kind::TaskOriented => {
            let from = *others.get(rng.below(others.len().max(1) as u32) as usize)?;
            let (s, _) = reach(robot, &scene, from, rng, 20)?;
            let (g, pose) = reach(robot, &scene, &target, rng, 20)?;
            (s, g, pose)
        }
        Kind::NeutralStart => {
            let s = neutral(robot, &scene, rng)?;
            let (g, pose) = reach(robot, &scene, &target, rng, 20)?;
            (s, g, pose)
        }
        Kind::NeutralGoal => {
            let (s, _) = reach(robot, &scene, &target, rng, 20)?;
            let g = neutral(robot, &scene, rng)?;
            let pose = *edmp_core::robot::kinematics::forward(robot, &g).ok()?.tcp();
            (s, g, pose)
        }
    };
    Some(Problem {
        robot,
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

impl<const J: usize> Problem<J> {
    /// The problem as an `edmp-scene/1` document (joint goal), with the matching TCP pose goal
    /// and provenance under the optional `meta` field; `robot` names any arm but the Panda
    /// (whose scenes the format's default covers).
    pub(crate) fn json(&self) -> Value {
        let q = self.goal_pose.quaternion_wxyz();
        let mut doc = json!({
            "format": "edmp-scene/1",
            "obstacles": self.env.prims.iter().map(primitive_json).collect::<Vec<_>>(),
            "start": self.start.to_vec(),
            "goal": {"joints": self.goal.to_vec()},
            "meta": {
                "family": self.family.name(),
                "kind": self.kind.name(),
                "seed": self.seed,
                "goal_pose": {
                    "position": [self.goal_pose.translation.x, self.goal_pose.translation.y, self.goal_pose.translation.z],
                    "quaternion": q,
                },
            },
        });
        if self.robot.name != PANDA.name {
            doc["robot"] = json!(self.robot.name);
        }
        doc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use edmp_core::scene::Primitive;
    use nalgebra::{Quaternion, Rotation3, UnitQuaternion, Vector3};

    /// Whether world point `p` is inside primitive `prim` (for the geometry tests).
    fn inside(prim: &Primitive, p: Vector3<f32>) -> bool {
        let local = |center: [f32; 3], q: [f32; 4]| {
            let turn = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
            turn.inverse() * (p - Vector3::from(center))
        };
        match *prim {
            Primitive::Cuboid {
                center,
                dims,
                quaternion,
            } => {
                let l = local(center, quaternion);
                (0..3).all(|i| l[i].abs() <= dims[i] / 2.0)
            }
            Primitive::Cylinder {
                center,
                radius,
                height,
                quaternion,
            } => {
                let l = local(center, quaternion);
                l.x * l.x + l.y * l.y <= radius * radius && l.z.abs() <= height / 2.0
            }
            Primitive::Sphere { center, radius } => (p - Vector3::from(center)).norm() <= radius,
        }
    }

    /// A grid of world points over the local box `lo`..`hi` of `region`'s frame.
    fn grid(region: &Region, lo: [f32; 3], hi: [f32; 3]) -> Vec<Vector3<f32>> {
        let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), region.yaw);
        let steps = 8;
        let mut out = Vec::new();
        for i in 0..=steps {
            for j in 0..=steps {
                for k in 0..=steps {
                    let f = |a: f32, b: f32, n: usize| a + (b - a) * n as f32 / steps as f32;
                    let l = Vector3::new(f(lo[0], hi[0], i), f(lo[1], hi[1], j), f(lo[2], hi[2], k));
                    out.push(Vector3::from(region.center) + turn * l);
                }
            }
        }
        out
    }

    #[test]
    fn training_families_are_not_unseen() {
        for f in Family::ALL {
            assert!(!Family::UNSEEN.contains(&f), "{f:?}");
        }
    }

    #[test]
    fn unseen_environments_are_valid_scenes_of_thick_primitives() {
        for family in Family::UNSEEN {
            for seed in 0..300u64 {
                let env = environment(family, &mut Rng::new(seed));
                assert!(env.prims.len() <= MAX_OBSTACLES, "{family:?} {seed}");
                assert!(env.scene().is_some(), "{family:?} {seed}");
                assert!(!env.goals.is_empty() && !env.regions.is_empty(), "{family:?} {seed}");
                for p in &env.prims {
                    let thin = match *p {
                        Primitive::Cuboid { dims, .. } => dims.iter().copied().fold(f32::INFINITY, f32::min),
                        Primitive::Cylinder { radius, height, .. } => (2.0 * radius).min(height),
                        Primitive::Sphere { radius, .. } => 2.0 * radius,
                    };
                    assert!(thin >= 0.01, "{family:?} seed {seed}: {p:?}");
                }
                for r in env.regions.iter().chain(&env.goals) {
                    assert!(r.half.iter().all(|&h| h > 0.0), "{family:?} seed {seed}: {r:?}");
                }
            }
        }
    }

    /// The way into every goal region is open: the region itself and 30 cm in front of it
    /// (towards the robot) touch no obstacle (the cage's slot, the window's hole, the space
    /// under the table). Bookshelf gaps hold cans, so there only the 30 cm in front of the
    /// shelf and its open front are checked.
    #[test]
    fn the_way_into_the_goals_is_open() {
        for family in Family::UNSEEN {
            for seed in 0..100u64 {
                let env = environment(family, &mut Rng::new(seed));
                for g in &env.goals {
                    let h = g.half;
                    let far = if family == Family::Bookshelf {
                        -h[0] - 0.045
                    } else {
                        h[0]
                    };
                    for p in grid(g, [-h[0] - 0.3, -h[1], -h[2]], [far, h[1], h[2]]) {
                        let hit = env.prims.iter().find(|prim| inside(prim, p));
                        assert!(hit.is_none(), "{family:?} seed {seed}: {p:?} in {hit:?}");
                    }
                }
            }
        }
    }

    /// Goals are really enclosed: a goal region of the cage and the window box is surrounded
    /// by obstacles above, below, behind and on both sides (rays along ±y, ±z and +x from
    /// its centre meet an obstacle within 1 m), and is under the table top for under-table.
    #[test]
    fn goals_are_inside_their_structure() {
        for family in [Family::Cage, Family::WindowBox, Family::UnderTable] {
            for seed in 0..100u64 {
                let env = environment(family, &mut Rng::new(seed));
                for g in &env.goals {
                    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), g.yaw);
                    let rays: &[[f32; 3]] = if family == Family::UnderTable {
                        &[[0.0, 0.0, 1.0]]
                    } else {
                        &[
                            [1.0, 0.0, 0.0],
                            [0.0, 1.0, 0.0],
                            [0.0, -1.0, 0.0],
                            [0.0, 0.0, 1.0],
                            [0.0, 0.0, -1.0],
                        ]
                    };
                    for d in rays {
                        let hit = (1..=200).any(|i| {
                            let p = Vector3::from(g.center) + turn * (Vector3::from(*d) * (i as f32 * 0.005));
                            env.prims.iter().any(|prim| inside(prim, p))
                        });
                        assert!(hit, "{family:?} seed {seed}: nothing along {d:?}");
                    }
                }
            }
        }
    }

    /// The cage's front really is bars with 24-28 cm slots: every slot's middle line, from
    /// floor to roof, is free, and a bar stands between neighbouring slots.
    #[test]
    fn cage_slots_are_between_bars() {
        for seed in 0..100u64 {
            let env = environment(Family::Cage, &mut Rng::new(seed));
            let bars: Vec<&Primitive> = env.prims[6..]
                .iter()
                .filter(|p| match p {
                    Primitive::Cylinder { radius, height, .. } => *radius <= 0.015 && *height >= 0.38,
                    Primitive::Cuboid { dims, .. } => dims[0] <= 0.03 && dims[1] <= 0.03 && dims[2] >= 0.38,
                    Primitive::Sphere { .. } => false,
                })
                .collect();
            assert_eq!(bars.len(), env.goals.len() + 1, "seed {seed}");
            let centre = |p: &Primitive| match *p {
                Primitive::Cuboid { center, .. }
                | Primitive::Cylinder { center, .. }
                | Primitive::Sphere { center, .. } => Vector3::from(center),
            };
            for pair in bars.windows(2) {
                let gap = (centre(pair[1]) - centre(pair[0])).norm();
                assert!((0.255..=0.31).contains(&gap), "seed {seed}: bars {gap} m apart");
            }
        }
    }

    #[test]
    fn unseen_goals_are_posed_in_a_goal_region() {
        for family in Family::UNSEEN {
            let mut found = 0;
            for seed in 0..12u64 {
                let kind = [Kind::TaskOriented, Kind::NeutralStart][(seed % 2) as usize];
                let Some(p) = problem_for(&PANDA, family, kind, seed) else {
                    continue;
                };
                found += 1;
                let t = p.goal_pose.translation;
                let within = p.env.goals.iter().any(|g| {
                    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), -g.yaw);
                    let l = turn * (t - Vector3::from(g.center));
                    (0..3).all(|i| l[i].abs() <= g.half[i] + 0.01)
                });
                assert!(within, "{family:?} seed {seed}: goal at {t:?}");
            }
            assert!(found >= 3, "{family:?}: {found} problems of 12 seeds");
        }
    }

    /// Another arm's problems are the same environments with its own ends, written with its
    /// `robot` name, and read back by the scene reader as valid ends of that arm.
    fn other_arms_problems_read_back<const J: usize>(robot: &'static Robot<f32, J>) {
        let mut found = 0;
        for seed in 0..24u64 {
            let kind = [Kind::TaskOriented, Kind::NeutralStart, Kind::NeutralGoal][(seed % 3) as usize];
            let family = Family::ALL[(seed % 4) as usize];
            let Some(p) = problem_for(robot, family, kind, seed) else {
                continue;
            };
            found += 1;
            let panda_env = environment(family, &mut Rng::new(seed));
            assert_eq!(
                p.env.prims, panda_env.prims,
                "{family:?} seed {seed}: another environment"
            );
            let doc = p.json();
            assert_eq!(doc["robot"], robot.name);
            let text = serde_json::to_string(&doc).unwrap();
            let back = crate::formats::json::parse_problem_for(&text, std::path::Path::new("."), robot)
                .unwrap_or_else(|e| panic!("{} {family:?} seed {seed}: {e}", robot.name));
            assert_eq!(back.start, p.start);
        }
        assert!(found >= 6, "{}: {found} problems of 24 seeds", robot.name);
    }

    #[test]
    fn other_arms_draw_their_own_ends_in_the_same_environments() {
        other_arms_problems_read_back(&edmp_core::robot::arms::iiwa7::ROBOT);
        other_arms_problems_read_back(&edmp_core::robot::arms::xarm6::ROBOT);
        let panda = problem_for(&PANDA, Family::Tabletop, Kind::TaskOriented, 0).map(|p| p.json());
        assert!(
            panda.is_none_or(|d| d.get("robot").is_none()),
            "the Panda's scenes keep their bytes"
        );
    }
}
