//! The `edmp-scene/1` scene and `edmp-plan/1` plan formats (docs/formats.md): reading with
//! errors that name the offending field by its JSON path, e.g. `obstacles[3].quaternion: norm
//! 0.71, expected 1`, and writing a primitive back.

pub use super::fields::InputError;
use super::fields::{field, number, numbers, object, quaternion};
use super::surface::{Surfaces, build_surfaces, inside_closed_mesh, is_surface, read_obstacle};
use crate::arm::Arm;
use edmp_core::collision::checker::{CheckConfig, Contact, check_end};
use edmp_core::robot::ik::{IkConfig, solve};
use edmp_core::robot::kinematics::{Joints, Pose};
use edmp_core::robot::{FINGER_OPENING_MAX, FINGER_OPENING_MIN, JOINTS, PANDA, Robot};
use edmp_core::scene::{MAX_OBSTACLES, Primitive, Scene, SceneError, rotation_from_wxyz};
use serde_json::{Value, json};
use std::path::Path;

/// The goal of a problem for an arm of `J` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Goal<const J: usize = JOINTS> {
    /// A joint configuration.
    Joints(Joints<f32, J>),
    /// A TCP pose: position and quaternion `[w, x, y, z]`.
    Pose {
        /// TCP position in the world, metres.
        position: [f32; 3],
        /// TCP orientation, `[w, x, y, z]`.
        quaternion: [f32; 4],
    },
}

/// A parsed, validated problem for an arm of `J` joints (the Panda's by default).
#[derive(Clone, Debug)]
pub struct Problem<const J: usize = JOINTS> {
    /// The arm the scene names (`robot`).
    pub robot: &'static Robot<f32, J>,
    /// The primitive obstacles, the held object and the finger opening (`gripper.finger`);
    /// [`Problem::scene`] adds the clouds and meshes.
    primitive_scene: Scene<'static, MAX_OBSTACLES>,
    /// The clouds and meshes, and the pieces the planner holds of them.
    pub surfaces: Surfaces,
    /// The primitive obstacles' parameters as the file gives them, in the scene's order (what
    /// the wire to firmware carries).
    pub primitives: Vec<Primitive>,
    /// Each primitive's index in the file's `obstacles` (clouds and meshes may stand between).
    pub primitive_index: Vec<usize>,
    /// The held object's parameters, if any.
    pub held: Option<Primitive>,
    /// The start configuration.
    pub start: Joints<f32, J>,
    /// The goal: joints or a TCP pose.
    pub goal: Goal<J>,
}

/// An `edmp-scene/1` primitive (an obstacle or the held object) at `path`: its parameters as
/// the file gives them, validated as an obstacle ([`Primitive::to_obstacle`]).
pub fn primitive(v: &Value, path: &str) -> Result<Primitive, InputError> {
    let kind = v
        .get("type")
        .and_then(Value::as_str)
        .ok_or_else(|| InputError::at(&format!("{path}.type"), "missing (cuboid, cylinder or sphere)"))?;
    let (primitive, size_field) = match kind {
        "cuboid" => {
            let map = object(v, path, &["type", "center", "dims", "quaternion"])?;
            let (c, cp) = field(map, path, "center")?;
            let (d, dp) = field(map, path, "dims")?;
            let (q, qp) = field(map, path, "quaternion")?;
            let primitive = Primitive::Cuboid {
                center: numbers::<3>(c, &cp)?,
                dims: numbers::<3>(d, &dp)?,
                quaternion: quaternion(q, &qp)?,
            };
            (primitive, "dims")
        }
        "cylinder" => {
            let map = object(v, path, &["type", "center", "radius", "height", "quaternion"])?;
            let (c, cp) = field(map, path, "center")?;
            let (r, rp) = field(map, path, "radius")?;
            let (h, hp) = field(map, path, "height")?;
            let (q, qp) = field(map, path, "quaternion")?;
            let (center, radius, height, quaternion) = (
                numbers::<3>(c, &cp)?,
                number(r, &rp)?,
                number(h, &hp)?,
                quaternion(q, &qp)?,
            );
            let size = if radius > 0.0 { "height" } else { "radius" };
            let primitive = Primitive::Cylinder {
                center,
                radius,
                height,
                quaternion,
            };
            (primitive, size)
        }
        "sphere" => {
            let map = object(v, path, &["type", "center", "radius"])?;
            let (c, cp) = field(map, path, "center")?;
            let (r, rp) = field(map, path, "radius")?;
            let primitive = Primitive::Sphere {
                center: numbers::<3>(c, &cp)?,
                radius: number(r, &rp)?,
            };
            (primitive, "radius")
        }
        other => {
            return Err(InputError::at(
                &format!("{path}.type"),
                format!("unknown type {other:?} (cuboid, cylinder or sphere)"),
            ));
        }
    };
    primitive.to_obstacle().map_err(|e| scene_error(e, path, size_field))?;
    Ok(primitive)
}

/// A primitive as `edmp-scene/1` writes it (the inverse of [`primitive`]).
pub fn primitive_json(primitive: &Primitive) -> Value {
    match *primitive {
        Primitive::Cuboid {
            center,
            dims,
            quaternion,
        } => json!({"type": "cuboid", "center": center, "dims": dims, "quaternion": quaternion}),
        Primitive::Cylinder {
            center,
            radius,
            height,
            quaternion,
        } => {
            json!({"type": "cylinder", "center": center, "radius": radius, "height": height, "quaternion": quaternion})
        }
        Primitive::Sphere { center, radius } => json!({"type": "sphere", "center": center, "radius": radius}),
    }
}

fn scene_error(e: SceneError, path: &str, size_field: &str) -> InputError {
    match e {
        SceneError::NonPositiveSize => InputError::at(&format!("{path}.{size_field}"), "must be positive"),
        other => InputError::at(path, other.to_string()),
    }
}

fn joints<const J: usize>(robot: &Robot<f32, J>, v: &Value, path: &str) -> Result<Joints<f32, J>, InputError> {
    let q = numbers::<J>(v, path)?;
    for (j, &x) in q.iter().enumerate() {
        let (lo, hi) = (robot.soft_lower[j], robot.soft_upper[j]);
        if x < lo - 1e-5 || x > hi + 1e-5 {
            return Err(InputError::at(
                &format!("{path}[{j}]"),
                format!("{x} outside {}'s limits [{lo}, {hi}]", robot.joint_names[j]),
            ));
        }
    }
    Ok(q)
}

impl<const J: usize> Problem<J> {
    /// The scene to plan in: the primitives, and the clouds and meshes with their boxes.
    pub fn scene(&self) -> Scene<'_, MAX_OBSTACLES> {
        with_surfaces(&self.primitive_scene, &self.surfaces)
    }
}

fn with_surfaces<'a>(primitives: &Scene<'static, MAX_OBSTACLES>, surfaces: &'a Surfaces) -> Scene<'a, MAX_OBSTACLES> {
    if surfaces.pieces() == 0 {
        return primitives.clone();
    }
    primitives.clone().with_surface(surfaces.surface(), &surfaces.boxes)
}

/// A contact of `robot`'s bodies in words, obstacles named by their index in the file
/// (`primitive_index` maps the scene's primitives to it).
pub fn describe<const J: usize>(robot: &Robot<f32, J>, contact: Contact, primitive_index: &[usize]) -> String {
    let body = |b: u8| robot.body_names.get(usize::from(b)).copied().unwrap_or("held_object");
    match contact {
        Contact::Obstacle { body: b, obstacle } => {
            let i = primitive_index
                .get(usize::from(obstacle))
                .copied()
                .unwrap_or(usize::from(obstacle));
            format!("{} touches obstacles[{i}]", body(b))
        }
        Contact::Surface { body: b, obstacle } => format!("{} touches obstacles[{obstacle}]", body(b)),
        Contact::SelfContact { first, second } => format!("{} touches {}", body(first), body(second)),
    }
}

/// The problem's goal as joints: itself for a joint goal, the core IK's collision-free solution
/// nearest the start for a pose goal. The error names the field.
pub fn joint_goal<const J: usize>(problem: &Problem<J>) -> Result<Joints<f32, J>, String> {
    match problem.goal {
        Goal::Joints(q) => Ok(q),
        Goal::Pose { position, quaternion } => {
            let rotation = rotation_from_wxyz(quaternion).map_err(|e| format!("goal.pose.quaternion: {e}"))?;
            let target = Pose {
                rotation,
                translation: position.into(),
            };
            solve(
                problem.robot,
                &target,
                &problem.start,
                &problem.scene(),
                &IkConfig::default(),
            )
            .map(|s| s.joints)
            .map_err(|e| format!("goal.pose: unreachable: {e}"))
        }
    }
}

/// Parses and validates a Panda's `edmp-scene/1` document whose files (clouds, meshes) lie
/// relative to the current directory.
pub fn parse_problem(text: &str) -> Result<Problem, InputError> {
    parse_problem_in(text, Path::new("."))
}

/// Reads and validates the Panda's `edmp-scene/1` file at `path`: files it names lie relative
/// to its folder. The error names the file.
pub fn read_problem(path: &Path) -> Result<Problem, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_problem_in(&text, dir).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses and validates a Panda's `edmp-scene/1` document; files it names lie relative to
/// `dir`. A scene for another arm is refused by name (commands that take every arm read
/// [`scene_arm`] first, then [`parse_problem_for`]).
pub fn parse_problem_in(text: &str, dir: &Path) -> Result<Problem, InputError> {
    parse_problem_for(text, dir, &PANDA)
}

/// The arm an `edmp-scene/1` document names in `robot` (absent: the Panda).
pub fn scene_arm(text: &str) -> Result<Arm, InputError> {
    read_arm(&parse_json(text)?)
}

fn parse_json(text: &str) -> Result<Value, InputError> {
    serde_json::from_str(text).map_err(|e| InputError::at("", format!("not valid JSON: {e}")))
}

fn read_arm(root: &Value) -> Result<Arm, InputError> {
    let Some(value) = root.get("robot") else {
        return Ok(Arm::Panda);
    };
    let known = || Arm::ALL.map(Arm::name).join(", ");
    let name = value
        .as_str()
        .ok_or_else(|| InputError::at("robot", format!("expected a string, one of: {}", known())))?;
    Arm::from_name(name)
        .ok_or_else(|| InputError::at("robot", format!("unknown arm {value}, expected one of: {}", known())))
}

/// Parses and validates an `edmp-scene/1` document for `robot`; files it names lie relative
/// to `dir`. A document naming another arm is refused by name, never read as if it were
/// `robot`'s.
pub fn parse_problem_for<const J: usize>(
    text: &str,
    dir: &Path,
    robot: &'static Robot<f32, J>,
) -> Result<Problem<J>, InputError> {
    let root = parse_json(text)?;
    // `meta` (optional, free-form provenance such as the family, seed and the TCP pose of a
    // joint goal) is an extension of the format; the planner ignores it.
    let map = object(
        &root,
        "",
        &[
            "format",
            "robot",
            "obstacles",
            "start",
            "goal",
            "held_object",
            "gripper",
            "meta",
        ],
    )?;
    if let Some(meta) = map.get("meta") {
        meta.as_object()
            .ok_or_else(|| InputError::at("meta", "expected an object"))?;
    }
    let (format, fp) = field(map, "", "format")?;
    if format.as_str() != Some("edmp-scene/1") {
        return Err(InputError::at(
            &fp,
            format!("expected \"edmp-scene/1\", found {format}"),
        ));
    }
    let arm = read_arm(&root)?;
    if arm.name() != robot.name {
        return Err(InputError::at(
            "robot",
            format!(
                "\"{arm}\": this command runs the {} only (`edmp-host plan`, `rrt`, `render` and `fk --robot` take every arm)",
                robot.name
            ),
        ));
    }
    let (obstacles, op) = field(map, "", "obstacles")?;
    let list = obstacles
        .as_array()
        .ok_or_else(|| InputError::at(&op, "expected an array"))?;
    let primitive_count = list.iter().filter(|o| !is_surface(o)).count();
    if primitive_count > MAX_OBSTACLES {
        return Err(InputError::at(
            &op,
            format!("{primitive_count} primitive obstacles, at most {MAX_OBSTACLES}"),
        ));
    }
    let mut scene = Scene::<MAX_OBSTACLES>::new();
    let mut primitives = Vec::with_capacity(list.len());
    let mut primitive_index = Vec::with_capacity(list.len());
    let mut surface_obstacles = Vec::new();
    for (i, o) in list.iter().enumerate() {
        if is_surface(o) {
            surface_obstacles.push(read_obstacle(o, &format!("obstacles[{i}]"), i, dir)?);
            continue;
        }
        primitive_index.push(i);
        let p = primitive(o, &format!("obstacles[{i}]"))?;
        let built = p.to_obstacle().map_err(|e| InputError::at(&op, e.to_string()))?;
        scene.push(built).map_err(|e| InputError::at(&op, e.to_string()))?;
        primitives.push(p);
    }
    let held = map
        .get("held_object")
        .map(|h| primitive(h, "held_object"))
        .transpose()?;
    if let Some(h) = &held {
        scene.hold(
            h.to_obstacle()
                .map_err(|e| InputError::at("held_object", e.to_string()))?,
        );
    }
    // Before the ends are checked: the fingers sit at this opening for the whole problem.
    if let Some(gripper) = map.get("gripper") {
        let gm = object(gripper, "gripper", &["finger"])?;
        let (f, fp) = field(gm, "gripper", "finger")?;
        let finger = number(f, &fp)?;
        scene.set_gripper(finger).map_err(|e| match e {
            SceneError::FingerOutOfRange => InputError::at(
                &fp,
                format!("{finger} outside [{FINGER_OPENING_MIN}, {FINGER_OPENING_MAX}]"),
            ),
            other => InputError::at(&fp, other.to_string()),
        })?;
    }
    let (start, sp) = field(map, "", "start")?;
    let start = joints(robot, start, &sp)?;
    // After the start is known: `filter_robot` drops the points the robot has there.
    let surfaces = build_surfaces(surface_obstacles, robot, &start, scene.gripper())?;
    let primitive_scene = scene;
    let scene = with_surfaces(&primitive_scene, &surfaces);
    if let Some((body, i)) = inside_closed_mesh(robot, &surfaces, &start, scene.gripper()) {
        return Err(InputError::at(
            &sp,
            format!("in collision: {body} inside the closed mesh obstacles[{i}]"),
        ));
    }
    if let Some(c) =
        check_end(robot, &scene, &start, &CheckConfig::default()).map_err(|e| InputError::at(&sp, e.to_string()))?
    {
        return Err(InputError::at(
            &sp,
            format!("in collision: {}", describe(robot, c, &primitive_index)),
        ));
    }
    let (goal, gp) = field(map, "", "goal")?;
    let goal_map = object(goal, &gp, &["joints", "pose"])?;
    let goal = match (goal_map.get("joints"), goal_map.get("pose")) {
        (Some(q), None) => {
            let path = format!("{gp}.joints");
            let q = joints(robot, q, &path)?;
            if let Some((body, i)) = inside_closed_mesh(robot, &surfaces, &q, scene.gripper()) {
                return Err(InputError::at(
                    &path,
                    format!("in collision: {body} inside the closed mesh obstacles[{i}]"),
                ));
            }
            if let Some(c) = check_end(robot, &scene, &q, &CheckConfig::default())
                .map_err(|e| InputError::at(&path, e.to_string()))?
            {
                return Err(InputError::at(
                    &path,
                    format!("in collision: {}", describe(robot, c, &primitive_index)),
                ));
            }
            Goal::Joints(q)
        }
        (None, Some(pose)) => {
            let path = format!("{gp}.pose");
            let pm = object(pose, &path, &["position", "quaternion"])?;
            let (p, pp) = field(pm, &path, "position")?;
            let (q, qp) = field(pm, &path, "quaternion")?;
            Goal::Pose {
                position: numbers::<3>(p, &pp)?,
                quaternion: quaternion(q, &qp)?,
            }
        }
        _ => return Err(InputError::at(&gp, "expected exactly one of \"joints\" or \"pose\"")),
    };
    drop(scene);
    Ok(Problem {
        robot,
        primitive_scene,
        surfaces,
        primitives,
        primitive_index,
        held,
        start,
        goal,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"{
      "format": "edmp-scene/1",
      "obstacles": [
        {"type": "cuboid", "center": [0.6, 0.0, 0.2], "dims": [0.4, 0.8, 0.02], "quaternion": [1, 0, 0, 0]},
        {"type": "cylinder", "center": [0.5, 0.4, 0.3], "radius": 0.04, "height": 0.2, "quaternion": [1, 0, 0, 0]},
        {"type": "sphere", "center": [0.4, -0.4, 0.6], "radius": 0.05}
      ],
      "start": [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785],
      "goal": {"joints": [0.3, -0.5, 0.1, -2.0, 0.0, 1.6, 0.9]},
      "held_object": {"type": "cuboid", "center": [0, 0, 0.16], "dims": [0.03, 0.03, 0.06], "quaternion": [1, 0, 0, 0]}
    }"#;

    fn error_of(text: &str) -> String {
        parse_problem(text).unwrap_err().to_string()
    }

    #[test]
    fn parses_the_spec_example() {
        let p = parse_problem(GOOD).unwrap();
        assert_eq!(p.scene().obstacles().len(), 3);
        assert!(p.scene().held().is_some());
        assert!(matches!(p.goal, Goal::Joints(_)));
    }

    #[test]
    fn the_robot_field_names_the_arm_and_the_panda_reader_refuses_another() {
        let with = |robot: &str| {
            GOOD.replace(
                r#""format": "edmp-scene/1","#,
                &format!(r#""format": "edmp-scene/1", "robot": {robot},"#),
            )
        };
        assert!(parse_problem(&with(r#""panda""#)).is_ok());
        assert_eq!(scene_arm(&with(r#""iiwa7""#)).ok(), Some(Arm::Iiwa7));
        assert_eq!(scene_arm(GOOD).ok(), Some(Arm::Panda));
        assert!(error_of(&with(r#""iiwa7""#)).starts_with("robot: \"iiwa7\": this command runs the panda only"));
        assert_eq!(
            error_of(&with(r#""ur5""#)),
            "robot: unknown arm \"ur5\", expected one of: panda, iiwa7, xarm6"
        );
        assert!(error_of(&with("7")).starts_with("robot: expected a string"));
    }

    #[test]
    fn another_arms_scene_has_its_joint_count_and_limits() {
        let xarm = &edmp_core::robot::arms::xarm6::ROBOT;
        let scene = |start: &str| {
            format!(
                r#"{{"format": "edmp-scene/1", "robot": "xarm6", "obstacles": [],
                    "start": {start}, "goal": {{"joints": [0.5, -0.5, -0.8, 0, 1.3, 0]}}}}"#
            )
        };
        let error = |text: &str| parse_problem_for(text, Path::new("."), xarm).unwrap_err().to_string();
        let p = parse_problem_for(&scene("[0, -0.5, -0.8, 0, 1.3, 0]"), Path::new("."), xarm).unwrap();
        assert_eq!(p.robot.name, "xarm6");
        assert_eq!(p.start, [0.0, -0.5, -0.8, 0.0, 1.3, 0.0]);
        assert_eq!(
            error(&scene("[0, -0.5, -0.8, 0, 1.3, 0, 0]")),
            "start: expected 6 numbers, found 7"
        );
        assert!(error(&scene("[0, -0.5, -0.8, 0, 9, 0]")).starts_with("start[4]: 9 outside joint5's limits"));
        // A 6-joint scene is no Panda's: refused by name, not by its joint count.
        assert!(
            error_of(&scene("[0, -0.5, -0.8, 0, 1.3, 0]"))
                .starts_with("robot: \"xarm6\": this command runs the panda only")
        );
    }

    #[test]
    fn errors_name_the_field() {
        let bad_quat = GOOD.replace(
            r#""dims": [0.4, 0.8, 0.02], "quaternion": [1, 0, 0, 0]"#,
            r#""dims": [0.4, 0.8, 0.02], "quaternion": [0.71, 0, 0, 0]"#,
        );
        assert_eq!(error_of(&bad_quat), "obstacles[0].quaternion: norm 0.71, expected 1");
        let short = GOOD.replace("[0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]", "[0.0, -0.785]");
        assert_eq!(error_of(&short), "start: expected 7 numbers, found 2");
        let typo = GOOD.replace(r#""radius": 0.05}"#, r#""radius": 0.05, "colour": 1}"#);
        assert!(error_of(&typo).starts_with("obstacles[2].colour: unknown field"));
        let negative = GOOD.replace(r#""radius": 0.04"#, r#""radius": -0.04"#);
        assert_eq!(error_of(&negative), "obstacles[1].radius: must be positive");
        let limits = GOOD.replace(
            "[0.3, -0.5, 0.1, -2.0, 0.0, 1.6, 0.9]",
            "[0.3, -0.5, 0.1, 0.5, 0.0, 1.6, 0.9]",
        );
        assert!(error_of(&limits).starts_with("goal.joints[3]: 0.5 outside panda_joint4's limits"));
        let nan = GOOD.replace("\"radius\": 0.05", "\"radius\": \"x\"");
        assert!(error_of(&nan).starts_with("obstacles[2].radius: expected a number"));
        let collide = GOOD.replace(
            r#""center": [0.4, -0.4, 0.6], "radius": 0.05"#,
            r#""center": [0.3, 0.0, 0.6], "radius": 0.1"#,
        );
        assert!(
            error_of(&collide).starts_with("start: in collision:"),
            "{}",
            error_of(&collide)
        );
        assert!(error_of("{").starts_with("not valid JSON"));
    }

    fn with_gripper(gripper: &str) -> String {
        GOOD.replacen("\"format\"", &format!("\"gripper\": {gripper}, \"format\""), 1)
    }

    #[test]
    fn the_gripper_field_sets_the_finger_opening() {
        assert_eq!(parse_problem(GOOD).unwrap().scene().gripper(), 0.025);
        for (text, w) in [("0.04", 0.04), ("0", 0.0), ("0.0125", 0.0125)] {
            let p = parse_problem(&with_gripper(&format!(r#"{{"finger": {text}}}"#))).unwrap();
            assert_eq!(p.scene().gripper(), w);
        }
        let cases = [
            (r#"{"finger": 0.05}"#, "gripper.finger: 0.05 outside [0, 0.04]"),
            (r#"{"finger": -0.001}"#, "gripper.finger: -0.001 outside [0, 0.04]"),
            (
                r#"{"finger": "wide"}"#,
                "gripper.finger: expected a number, found \"wide\"",
            ),
            (r#"{}"#, "gripper.finger: missing"),
            (r#"0.04"#, "gripper: expected an object"),
        ];
        for (gripper, message) in cases {
            assert_eq!(error_of(&with_gripper(gripper)), message, "{gripper}");
        }
        let huge = error_of(&with_gripper(r#"{"finger": 1e300}"#));
        assert!(
            huge.starts_with("gripper.finger: 1") && huge.ends_with("is not a finite f32"),
            "{huge}"
        );
        let typo = error_of(&with_gripper(r#"{"finger": 0.04, "fingers": 0.04}"#));
        assert!(
            typo.starts_with("gripper.fingers: unknown field (expected one of: finger)"),
            "{typo}"
        );
    }

    #[test]
    fn the_ends_are_checked_at_the_scenes_opening() {
        // A plate between the fingers at the start: free with the fingers open, in contact closed.
        let ready = [0.0f32, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        let k = edmp_core::robot::kinematics::forward(&edmp_core::robot::PANDA, &ready).unwrap();
        let hand = &k.frames[edmp_core::robot::HAND_FRAME];
        let c = hand.transform_point(&nalgebra::Vector3::new(0.0, 0.0, 0.095));
        let q = hand.quaternion_wxyz();
        let doc = |finger: f32| {
            serde_json::json!({
                "format": "edmp-scene/1",
                "obstacles": [{"type": "cuboid", "center": [c.x, c.y, c.z], "dims": [0.01, 0.02, 0.02], "quaternion": q}],
                "start": ready,
                "goal": {"joints": [0.3, -0.5, 0.1, -2.0, 0.0, 1.6, 0.9]},
                "gripper": {"finger": finger},
            })
            .to_string()
        };
        assert!(parse_problem(&doc(0.04)).is_ok());
        let closed = parse_problem(&doc(0.0)).unwrap_err().to_string();
        assert!(closed.starts_with("start: in collision: panda_"), "{closed}");
        assert!(closed.contains("finger touches obstacles[0]"), "{closed}");
    }
}
