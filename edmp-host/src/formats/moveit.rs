//! MoveIt's planning scenes as `edmp-scene/1`: a `moveit_msgs/PlanningScene` as YAML (from
//! `rostopic echo` / `ros2 topic echo`, MoveIt's scene export, or MotionBenchMaker's robowflex
//! files) and optionally a `moveit_msgs/MotionPlanRequest` (YAML) become one document,
//! validated through the host's JSON reader.
//!
//! The arm. `robot_model_name` names it (`panda`; `iiwa7` or its URDF's `lbr_iiwa`; `xarm6`);
//! without one, the first joint name of the robot states or the joint goal does
//! (`panda_joint1`, `lbr_iiwa_joint_1`, `joint1`); with neither, it is the Panda. Everything
//! below then uses that arm's names: its base link (`panda_link0`, `lbr_iiwa_link_0`,
//! `link_base`), its hand (`panda_hand`; the others' TCP link, `lbr_iiwa_link_7`, `link6`),
//! its joints and its planning groups (`panda_arm`, `panda_manipulator`; `manipulator`,
//! `iiwa7`; `xarm6`). A document for another arm carries `robot`.
//!
//! What is read: `world.collision_objects[]` (BOX, SPHERE, CYLINDER primitives, and meshes; the
//! pose of each is its frame's, times the object's `pose`, times the primitive's pose), one
//! object attached to the hand with one primitive (the held object), the start from the
//! request's `start_state.joint_state` (else the scene's `robot_state.joint_state`), and the
//! goal from `goal_constraints[0]`: joint constraints, or one position and one orientation
//! constraint on a link rigid with the TCP (the Panda's `panda_link8`, `panda_hand` or
//! `panda_grasptarget`; another arm's TCP link), converted to the TCP. ROS quaternions are
//! `{x, y, z, w}`; ours are `[w, x, y, z]`. Points and quaternions may also be flow sequences
//! (`[x, y, z]`, `[x, y, z, w]`) and primitive types names (`box`, `sphere`, `cylinder`), as
//! robowflex writes them; an operation is ADD as `0`, `"\x00"`, `b'\x00'`, `add`, or absent.
//!
//! Frames. Our world is the arm's base link. MoveIt's planning frame is `world`; an absent
//! header or an empty `frame_id` names it. Where it is relative to the base:
//! - `multi_dof_joint_state` (the scene's robot state, or the request's start state, which wins
//!   as MoveIt merges it): at most one joint, of any name (MoveIt's Panda: `virtual_joint`),
//!   its parent the planning frame; its transform places the base link in `world`, and
//!   everything given in `world` is brought into the base frame by its inverse. Within 1e-9 of
//!   the identity it is the identity. Its twist and wrench, and joint velocities and efforts,
//!   are ignored: a plan is positions. A second multi-DOF joint is an error.
//! - no such joint: `world` is the base link.
//! - `fixed_frame_transforms` (`geometry_msgs/TransformStamped`, parent the header's frame, empty
//!   the planning frame): each child is a frame that objects and goal constraints may name; one
//!   the importer already places (`world`, the base link) must agree with it to 1e-6 (an
//!   identity `world` → base does, with no or an identity virtual joint); a robot link other
//!   than the base is an error (the joint state places it).
//!
//! An attached object's frame is the hand, or empty (its link's, as MoveIt reads it); an
//! attached object without a header is refused (robowflex would read it as `world`).
//!
//! Everything that would change the problem and cannot be expressed is an error naming its YAML
//! path: planes, cones, mesh files by `resource`, octomap data, unknown frames and links,
//! padding ≠ 0 or scale ≠ 1, operations other than ADD, path constraints, a second goal.
//! Fields that do not change the geometry or the ends are read and ignored: names, stamps,
//! `is_diff`, colours, subframes, object types, planner settings, and the allowed collision
//! matrix (it only ever permits contacts; the checker checks every pair the spec names).
//! Unknown fields are errors, as in `edmp-scene/1`.

use crate::arm::{Arm, with_arm};
use crate::formats::json::{parse_problem_for, scene_arm};
use core::fmt;
use edmp_core::robot::Robot;
use edmp_core::robot::kinematics::forward;
use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use saphyr::{LoadableYamlNode, Scalar, Yaml};
use serde_json::{Map, Value, json};
use std::path::Path;

/// The finger opening `edmp-scene/1` holds when it has no `gripper` field (metres).
const FINGER_OPENING: f64 = 0.025;
/// How far two finger positions may differ and still be one opening (metres).
const FINGER_TOLERANCE: f64 = 1e-6;
/// How far a quaternion's norm may be from 1 (the scene format's own rule).
const NORM_TOLERANCE: f64 = 1e-3;
/// MoveIt's planning frame (the arm configuration's virtual joint's parent); an empty or
/// absent frame is this one.
const PLANNING_FRAME: &str = "world";
/// How far a virtual joint's transform may be from the identity and be read as it (m, rad).
const IDENTITY_TOLERANCE: f64 = 1e-9;
/// How far two placements of one frame may differ and still agree (m, rad).
const AGREEMENT_TOLERANCE: f64 = 1e-6;
/// What the importer needs to know of an arm: its names as its URDF and its MoveIt
/// configuration write them.
#[derive(Clone, Copy, Debug)]
struct ArmNames {
    arm: Arm,
    /// The arm's joints, joint 1 first.
    joints: &'static [&'static str],
    /// Every link frame of the generated tables.
    frames: &'static [&'static str],
    /// Our world: the base link, which a virtual joint places in the planning frame.
    base: &'static str,
    /// The link an attached object hangs from (the Panda's hand; another arm's TCP link).
    hand: &'static str,
    /// Finger joints: one opening for the whole plan (`gripper.finger`).
    fingers: &'static [&'static str],
    /// Links rigid with the TCP that a pose goal may name.
    rigid: &'static [&'static str],
    /// Planning groups a request may name (besides none).
    groups: &'static [&'static str],
    /// `robot_model_name`s that name this arm (the URDF's robot name, the scene format's name).
    models: &'static [&'static str],
}

impl ArmNames {
    fn of(arm: Arm) -> Self {
        let (joints, frames, hand) =
            with_arm!(arm, robot => (&robot.joint_names[..], robot.frame_names, robot.hand_frame));
        let (base, fingers, rigid, groups, models): (_, &[&str], &[&str], &[&str], &[&str]) = match arm {
            Arm::Panda => (
                "panda_link0",
                &["panda_finger_joint1", "panda_finger_joint2"],
                &["panda_link8", "panda_hand", "panda_grasptarget"],
                &["panda_arm", "panda_manipulator"],
                &["panda"],
            ),
            // The MoveIt configurations of ROS-Industrial's iiwa_stack and of UFACTORY's
            // xarm_ros name these groups.
            Arm::Iiwa7 => (
                "lbr_iiwa_link_0",
                &[],
                &["lbr_iiwa_link_7"],
                &["manipulator", "iiwa7"],
                &["iiwa7", "lbr_iiwa"],
            ),
            Arm::Xarm6 => ("link_base", &[], &["link6"], &["xarm6"], &["xarm6"]),
        };
        Self {
            arm,
            joints,
            frames,
            base,
            hand: frames[hand],
            fingers,
            rigid,
            groups,
            models,
        }
    }

    /// The arm of a scene and request: the one `robot_model_name` names, else the one whose
    /// joints the first joint name (robot states, joint goals) belongs to, else the Panda.
    /// The reader then refuses whatever does not fit it, by path.
    fn detect(scene: &Value, request: Option<&Value>) -> Self {
        let arms = Arm::ALL.map(Self::of);
        if let Some(model) = scene.get("robot_model_name").and_then(Value::as_str)
            && let Some(a) = arms.iter().find(|a| a.models.contains(&model))
        {
            return *a;
        }
        let state_names = |state: Option<&Value>| {
            state
                .and_then(|s| s.get("joint_state"))
                .and_then(|j| j.get("name"))
                .and_then(Value::as_array)
                .cloned()
                .unwrap_or_default()
        };
        let mut names = state_names(scene.get("robot_state"));
        if let Some(r) = request {
            names.extend(state_names(r.get("start_state")));
            for g in r
                .get("goal_constraints")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                for c in g
                    .get("joint_constraints")
                    .and_then(Value::as_array)
                    .into_iter()
                    .flatten()
                {
                    names.extend(c.get("joint_name").cloned());
                }
            }
        }
        names
            .iter()
            .filter_map(Value::as_str)
            .find_map(|n| arms.iter().find(|a| a.joints.contains(&n) || a.fingers.contains(&n)))
            .copied()
            .unwrap_or(arms[0])
    }
}

/// Which of the two input files an error is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// The `PlanningScene` YAML.
    Scene,
    /// The `MotionPlanRequest` YAML.
    Request,
}

/// A field of the MoveIt input that is wrong or unsupported, by its YAML path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImportError {
    /// The file it is in.
    pub source: Source,
    /// The YAML path, e.g. `world.collision_objects[2].meshes`.
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = match self.source {
            Source::Scene => "scene",
            Source::Request => "request",
        };
        if self.path.is_empty() {
            write!(f, "{file}: {}", self.message)
        } else {
            write!(f, "{file}: {}: {}", self.path, self.message)
        }
    }
}

impl core::error::Error for ImportError {}

/// Errors of one file, before the file is known.
#[derive(Debug)]
struct At {
    path: String,
    message: String,
}

type R<T> = Result<T, At>;

fn at(path: &str, message: impl Into<String>) -> At {
    At {
        path: path.to_owned(),
        message: message.into(),
    }
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_owned()
    } else {
        format!("{path}.{key}")
    }
}

/// Parses one YAML document into a JSON value (string keys, finite numbers), naming the path of
/// anything JSON cannot hold.
fn load(text: &str) -> R<Value> {
    let docs = Yaml::load_from_str(text).map_err(|e| at("", format!("not valid YAML: {e}")))?;
    match docs.as_slice() {
        [] => Ok(Value::Object(Map::new())),
        [doc] => to_json(doc, ""),
        _ => Err(at("", format!("{} YAML documents, expected one", docs.len()))),
    }
}

fn to_json(node: &Yaml<'_>, path: &str) -> R<Value> {
    match node {
        Yaml::Value(Scalar::Null) => Ok(Value::Null),
        Yaml::Value(Scalar::Boolean(b)) => Ok(Value::Bool(*b)),
        Yaml::Value(Scalar::Integer(i)) => Ok(json!(i)),
        Yaml::Value(Scalar::FloatingPoint(x)) => {
            let x = x.into_inner();
            serde_json::Number::from_f64(x)
                .map(Value::Number)
                .ok_or_else(|| at(path, format!("{x} is not a finite number")))
        }
        Yaml::Value(Scalar::String(s)) => Ok(Value::String(s.to_string())),
        Yaml::Sequence(items) => items
            .iter()
            .enumerate()
            .map(|(i, item)| to_json(item, &format!("{path}[{i}]")))
            .collect::<R<Vec<_>>>()
            .map(Value::Array),
        Yaml::Mapping(map) => {
            let mut out = Map::new();
            for (k, v) in map {
                let key = match k {
                    Yaml::Value(Scalar::String(s)) => s.to_string(),
                    Yaml::Value(Scalar::Integer(i)) => i.to_string(),
                    other => return Err(at(path, format!("mapping key {other:?} is not a string"))),
                };
                let value = to_json(v, &join(path, &key))?;
                if out.insert(key.clone(), value).is_some() {
                    return Err(at(&join(path, &key), "duplicate key"));
                }
            }
            Ok(Value::Object(out))
        }
        // Core-schema tags (`!!map`, `!!seq`) on collections are harmless; others are not ours.
        Yaml::Tagged(tag, inner) if tag.is_yaml_core_schema() => to_json(inner, path),
        Yaml::Tagged(tag, _) => Err(at(path, format!("YAML tag {tag} is not supported"))),
        Yaml::Alias(_) => Err(at(path, "unresolved YAML alias")),
        Yaml::Representation(text, ..) => Err(at(path, format!("unparsed YAML scalar {text:?}"))),
        Yaml::BadValue => Err(at(path, "invalid YAML value")),
    }
}

/// The mapping at `path` with only `allowed` keys (`null` reads as an empty mapping, as
/// `rostopic echo` writes empty messages).
fn mapping<'a>(v: &'a Value, path: &str, allowed: &[&str]) -> R<Option<&'a Map<String, Value>>> {
    let map = match v {
        Value::Null => return Ok(None),
        Value::Object(map) => map,
        _ => return Err(at(path, "expected a mapping")),
    };
    for key in map.keys() {
        if !allowed.contains(&key.as_str()) {
            return Err(at(
                &join(path, key),
                format!("unknown field (expected one of: {})", allowed.join(", ")),
            ));
        }
    }
    Ok(Some(map))
}

/// A sequence field (absent or `null`: empty).
fn sequence<'a>(map: Option<&'a Map<String, Value>>, path: &str, key: &str) -> R<(&'a [Value], String)> {
    let p = join(path, key);
    match map.and_then(|m| m.get(key)) {
        None | Some(Value::Null) => Ok((&[], p)),
        Some(Value::Array(items)) => Ok((items.as_slice(), p)),
        Some(_) => Err(at(&p, "expected a sequence")),
    }
}

/// Refuses a non-empty sequence the importer cannot express.
fn unsupported_if_any(map: Option<&Map<String, Value>>, path: &str, key: &str, why: &str) -> R<()> {
    let (items, p) = sequence(map, path, key)?;
    if items.is_empty() {
        Ok(())
    } else {
        Err(at(&p, format!("not supported: {why}")))
    }
}

fn number(v: &Value, path: &str) -> R<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| at(path, format!("expected a finite number, found {v}")))
}

/// A number field; ROS fills absent fields with 0.
fn number_or_zero(map: Option<&Map<String, Value>>, path: &str, key: &str) -> R<f64> {
    match map.and_then(|m| m.get(key)) {
        None | Some(Value::Null) => Ok(0.0),
        Some(v) => number(v, &join(path, key)),
    }
}

fn string<'a>(map: Option<&'a Map<String, Value>>, path: &str, key: &str) -> R<&'a str> {
    match map.and_then(|m| m.get(key)) {
        None | Some(Value::Null) => Ok(""),
        Some(Value::String(s)) => Ok(s),
        Some(v) => Err(at(&join(path, key), format!("expected a string, found {v}"))),
    }
}

/// `N` numbers written as a flow sequence (`[x, y, z]`, as MotionBenchMaker's robowflex writes
/// points and quaternions).
fn numbers<const N: usize>(items: &[Value], path: &str) -> R<[f64; N]> {
    if items.len() != N {
        return Err(at(path, format!("expected {N} numbers, found {}", items.len())));
    }
    let mut out = [0.0; N];
    for (i, (slot, x)) in out.iter_mut().zip(items).enumerate() {
        *slot = number(x, &format!("{path}[{i}]"))?;
    }
    Ok(out)
}

/// A `geometry_msgs/Vector3` or `Point`: `{x, y, z}` (absent fields 0) or `[x, y, z]`.
fn vector(v: Option<&Value>, path: &str) -> R<Vector3<f64>> {
    if let Some(Value::Array(items)) = v {
        return numbers::<3>(items, path).map(Vector3::from);
    }
    let map = mapping(v.unwrap_or(&Value::Null), path, &["x", "y", "z"])?;
    Ok(Vector3::new(
        number_or_zero(map, path, "x")?,
        number_or_zero(map, path, "y")?,
        number_or_zero(map, path, "z")?,
    ))
}

/// A ROS quaternion `{x, y, z, w}` or `[x, y, z, w]`. All zeros is the identity (MoveIt's own
/// reading of an unset orientation); otherwise the norm must be within 1e-3 of 1.
fn orientation(v: Option<&Value>, path: &str) -> R<UnitQuaternion<f64>> {
    let q = if let Some(Value::Array(items)) = v {
        let [x, y, z, w] = numbers::<4>(items, path)?;
        Quaternion::new(w, x, y, z)
    } else {
        let map = mapping(v.unwrap_or(&Value::Null), path, &["x", "y", "z", "w"])?;
        Quaternion::new(
            number_or_zero(map, path, "w")?,
            number_or_zero(map, path, "x")?,
            number_or_zero(map, path, "y")?,
            number_or_zero(map, path, "z")?,
        )
    };
    let norm = q.norm();
    if norm == 0.0 {
        return Ok(UnitQuaternion::identity());
    }
    if (norm - 1.0).abs() > NORM_TOLERANCE {
        return Err(at(path, format!("norm {norm:.4}, expected 1")));
    }
    Ok(UnitQuaternion::from_quaternion(q))
}

/// A `geometry_msgs/Pose` (absent: the identity).
fn pose(v: Option<&Value>, path: &str) -> R<Isometry3<f64>> {
    let map = mapping(v.unwrap_or(&Value::Null), path, &["position", "orientation"])?;
    let position = vector(map.and_then(|m| m.get("position")), &join(path, "position"))?;
    let rotation = orientation(map.and_then(|m| m.get("orientation")), &join(path, "orientation"))?;
    Ok(Isometry3::from_parts(Translation3::from(position), rotation))
}

/// The frame of a `std_msgs/Header` (leading `/` dropped); absent or empty: `""`, the planning
/// frame.
fn frame_id(map: Option<&Map<String, Value>>, path: &str) -> R<String> {
    let hp = join(path, "header");
    let header = mapping(
        map.and_then(|m| m.get("header")).unwrap_or(&Value::Null),
        &hp,
        &["seq", "stamp", "frame_id"],
    )?;
    let id = string(header, &hp, "frame_id")?;
    Ok(id.strip_prefix('/').unwrap_or(id).to_owned())
}

/// Whether `p` is the identity to [`IDENTITY_TOLERANCE`].
fn is_identity(p: &Isometry3<f64>) -> bool {
    p.translation.vector.norm() <= IDENTITY_TOLERANCE && p.rotation.angle() <= IDENTITY_TOLERANCE
}

/// Whether `a` and `b` agree to [`AGREEMENT_TOLERANCE`].
fn agree(a: &Isometry3<f64>, b: &Isometry3<f64>) -> bool {
    let d = a.inverse() * b;
    d.translation.vector.norm() <= AGREEMENT_TOLERANCE && d.rotation.angle() <= AGREEMENT_TOLERANCE
}

fn describe(p: &Isometry3<f64>) -> String {
    let t = p.translation.vector;
    let (axis, angle) = p
        .rotation
        .axis_angle()
        .map_or((Vector3::z(), 0.0), |(a, angle)| (a.into_inner(), angle));
    format!(
        "translation [{:.6}, {:.6}, {:.6}], rotation {:.6} rad about [{:.4}, {:.4}, {:.4}]",
        t.x, t.y, t.z, angle, axis.x, axis.y, axis.z
    )
}

/// The frames objects and goals may name, each with its pose in our world (the arm's base
/// link, `panda_link0` for the Panda): the planning frame (`world`, or an empty frame), the
/// base, and the children of `fixed_frame_transforms`.
#[derive(Debug)]
struct Frames {
    known: Vec<(String, Isometry3<f64>)>,
    arm: ArmNames,
}

impl Frames {
    /// `base`: where the virtual joint places the arm's base link in the planning frame.
    fn new(base: &Isometry3<f64>, arm: ArmNames) -> Self {
        Self {
            known: vec![
                (arm.base.to_owned(), Isometry3::identity()),
                (PLANNING_FRAME.to_owned(), base.inverse()),
            ],
            arm,
        }
    }

    fn get(&self, id: &str) -> Option<&Isometry3<f64>> {
        let id = if id.is_empty() { PLANNING_FRAME } else { id };
        self.known.iter().find(|(n, _)| n == id).map(|(_, p)| p)
    }

    /// The pose in our world of frame `id`, named at `path`.
    fn pose(&self, id: &str, path: &str) -> R<Isometry3<f64>> {
        self.get(id).copied().ok_or_else(|| {
            let names: Vec<&str> = self.known.iter().map(|(n, _)| n.as_str()).collect();
            at(
                path,
                format!(
                    "frame {id:?} is not supported (known: {}; empty is world, the planning frame)",
                    names.join(", ")
                ),
            )
        })
    }

    /// Reads `fixed_frame_transforms` (`geometry_msgs/TransformStamped`s): each child becomes a
    /// frame objects may name; one the importer already knows (the planning frame, the base)
    /// must agree with it; a robot link other than the base is refused (the joint state
    /// places it).
    fn read_fixed(&mut self, items: &[Value], path: &str) -> R<()> {
        for (i, item) in items.iter().enumerate() {
            let ip = format!("{path}[{i}]");
            let m = mapping(item, &ip, &["header", "child_frame_id", "transform"])?;
            let parent_id = frame_id(m, &ip)?;
            let parent = self.pose(&parent_id, &join(&ip, "header.frame_id"))?;
            let tp = join(&ip, "transform");
            let t = mapping(
                m.and_then(|m| m.get("transform")).unwrap_or(&Value::Null),
                &tp,
                &["translation", "rotation"],
            )?;
            let translation = vector(t.and_then(|t| t.get("translation")), &join(&tp, "translation"))?;
            let rotation = orientation(t.and_then(|t| t.get("rotation")), &join(&tp, "rotation"))?;
            let placed = parent * Isometry3::from_parts(Translation3::from(translation), rotation);
            let child = string(m, &ip, "child_frame_id")?;
            let child = child.strip_prefix('/').unwrap_or(child);
            let cp = join(&ip, "child_frame_id");
            if let Some(known) = self.get(child) {
                if !agree(known, &placed) {
                    return Err(at(
                        &tp,
                        format!(
                            "places {:?} at {} in {}, but it is at {} (the robot state's virtual joint places the base; the planning frame is world)",
                            if child.is_empty() { PLANNING_FRAME } else { child },
                            describe(&placed),
                            self.arm.base,
                            describe(known),
                        ),
                    ));
                }
            } else if self.arm.frames.contains(&child) {
                return Err(at(
                    &cp,
                    format!("{child:?} is a robot link: the joint state places it, not a fixed transform"),
                ));
            } else {
                self.known.push((child.to_owned(), placed));
            }
        }
        Ok(())
    }
}

fn round(x: f64) -> f64 {
    // Keep the JSON short and free of f64 dust (1e-12 is far below f32's resolution).
    (x * 1e12).round() / 1e12
}

fn center_and_quaternion(p: &Isometry3<f64>) -> (Vec<f64>, Vec<f64>) {
    let t = p.translation.vector;
    let mut q = *p.rotation.quaternion();
    if q.w < 0.0 {
        q = -q;
    }
    (
        vec![round(t.x), round(t.y), round(t.z)],
        vec![round(q.w), round(q.i), round(q.j), round(q.k)],
    )
}

/// One `shape_msgs/SolidPrimitive` placed at `placed`, as an `edmp-scene/1` primitive.
fn primitive(v: &Value, path: &str, placed: &Isometry3<f64>) -> R<Value> {
    let map = mapping(v, path, &["type", "dimensions"])?;
    let tp = join(path, "type");
    // ROS writes the type's number; robowflex (MotionBenchMaker) its name.
    let kind = match map.and_then(|m| m.get("type")) {
        Some(Value::Number(n)) => n.as_u64(),
        Some(Value::String(name)) => ["box", "sphere", "cylinder", "cone"]
            .iter()
            .position(|k| k.eq_ignore_ascii_case(name))
            .map(|k| k as u64 + 1),
        _ => None,
    }
    .ok_or_else(|| at(&tp, "expected the primitive type (1 BOX, 2 SPHERE, 3 CYLINDER)"))?;
    let (dims, dp) = sequence(map, path, "dimensions")?;
    let dims = dims
        .iter()
        .enumerate()
        .map(|(i, d)| number(d, &format!("{dp}[{i}]")))
        .collect::<R<Vec<f64>>>()?;
    let expect = |n: usize, what: &str| {
        if dims.len() == n {
            Ok(())
        } else {
            Err(at(
                &dp,
                format!("expected {n} dimensions ({what}), found {}", dims.len()),
            ))
        }
    };
    let (center, quaternion) = center_and_quaternion(placed);
    match kind {
        1 => {
            expect(3, "x, y, z")?;
            Ok(json!({"type": "cuboid", "center": center, "dims": dims, "quaternion": quaternion}))
        }
        2 => {
            expect(1, "radius")?;
            Ok(json!({"type": "sphere", "center": center, "radius": dims[0]}))
        }
        3 => {
            expect(2, "height, radius")?;
            Ok(json!({
                "type": "cylinder", "center": center, "radius": dims[1], "height": dims[0], "quaternion": quaternion,
            }))
        }
        4 => Err(at(&tp, "CONE (4) is not supported (cuboid, sphere, cylinder)")),
        other => Err(at(&tp, format!("unknown primitive type {other}"))),
    }
}

/// One `shape_msgs/Mesh` placed at `placed`, as an `edmp-scene/1` mesh obstacle: `vertices`
/// (`{x, y, z}` or `[x, y, z]`, in the mesh's frame) and `triangles` (`{vertex_indices: [i, j,
/// k]}` or `[i, j, k]`). The scene reader does not accept mesh obstacles yet, so
/// [`collision_object`] checks meshes with this and then refuses them.
fn mesh(v: &Value, path: &str, placed: &Isometry3<f64>) -> R<Value> {
    let map = mapping(v, path, &["vertices", "triangles", "resource", "dimensions"])?;
    if map.is_some_and(|m| m.contains_key("resource")) {
        return Err(at(
            &join(path, "resource"),
            "a mesh file: the vertices and triangles must be in the YAML",
        ));
    }
    let (vertices, vp) = sequence(map, path, "vertices")?;
    let (triangles, tp) = sequence(map, path, "triangles")?;
    if vertices.is_empty() {
        return Err(at(&vp, "missing: a mesh has vertices"));
    }
    if triangles.is_empty() {
        return Err(at(&tp, "missing: a mesh has triangles"));
    }
    let vertices = vertices
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let p = vector(Some(x), &format!("{vp}[{i}]"))?;
            Ok(json!([round(p.x), round(p.y), round(p.z)]))
        })
        .collect::<R<Vec<Value>>>()?;
    let triangles = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let ip = format!("{tp}[{i}]");
            let (indices, ip) = match t {
                Value::Array(items) => (items.as_slice(), ip),
                _ => sequence(mapping(t, &ip, &["vertex_indices"])?, &ip, "vertex_indices")?,
            };
            if indices.len() != 3 {
                return Err(at(&ip, format!("expected 3 vertex indices, found {}", indices.len())));
            }
            indices
                .iter()
                .enumerate()
                .map(|(k, x)| match x.as_u64() {
                    Some(n) if (n as usize) < vertices.len() => Ok(json!(n)),
                    _ => Err(at(
                        &format!("{ip}[{k}]"),
                        format!("{x} is not a vertex index (0..{})", vertices.len()),
                    )),
                })
                .collect::<R<Vec<Value>>>()
                .map(Value::Array)
        })
        .collect::<R<Vec<Value>>>()?;
    let (center, quaternion) = center_and_quaternion(placed);
    Ok(json!({
        "type": "mesh", "vertices": vertices, "triangles": triangles, "center": center,
        "quaternion": quaternion, "scale": 1,
    }))
}

const COLLISION_OBJECT: [&str; 13] = [
    "header",
    "pose",
    "id",
    "type",
    "primitives",
    "primitive_poses",
    "meshes",
    "mesh_poses",
    "planes",
    "plane_poses",
    "subframe_names",
    "subframe_poses",
    "operation",
];

/// Where a collision object's frame is: our world's `frames`, or (attached objects) the hand
/// (the Panda's; another arm's TCP link).
#[derive(Clone, Copy)]
enum ObjectFrames<'a> {
    World(&'a Frames),
    Hand(&'static str),
}

/// A `moveit_msgs/CollisionObject`: its primitives, placed in our world (or, for an attached
/// object, in the hand frame), as `edmp-scene/1` primitives.
fn collision_object(v: &Value, path: &str, frames: ObjectFrames<'_>) -> R<(String, Vec<Value>)> {
    let map = mapping(v, path, &COLLISION_OBJECT)?;
    let id = string(map, path, "id")?.to_owned();
    let fid = frame_id(map, path)?;
    let frame = match frames {
        ObjectFrames::World(frames) => frames.pose(&fid, &join(path, "header.frame_id"))?,
        // No header at all: ROS reads an empty frame (for an attached object, its link's),
        // robowflex `world`. Not guessed.
        ObjectFrames::Hand(hand) if map.is_none_or(|m| !m.contains_key("header")) => {
            return Err(at(
                path,
                format!(
                    "no header: an attached object's frame is ambiguous without one (ROS reads its link's, MotionBenchMaker's robowflex world); give header.frame_id {hand}"
                ),
            ));
        }
        // MoveIt reads an attached object's empty frame as its link's.
        ObjectFrames::Hand(hand) if fid.is_empty() || fid == hand => Isometry3::identity(),
        ObjectFrames::Hand(hand) => {
            return Err(at(
                &join(path, "header.frame_id"),
                format!("frame {fid:?} is not supported (only {hand}, or empty)"),
            ));
        }
    };
    match map.and_then(|m| m.get("operation")) {
        None | Some(Value::Null) => {}
        Some(Value::Number(n)) if n.as_u64() == Some(0) => {}
        // Byte 0 as YAML writes it ("\x00", b'\x00'), or robowflex's name.
        Some(Value::String(s)) if s == "\0" || s == "b'\\x00'" || s.eq_ignore_ascii_case("add") => {}
        Some(other) => {
            return Err(at(
                &join(path, "operation"),
                format!("operation {other} is not supported (only ADD, 0: a full scene)"),
            ));
        }
    }
    unsupported_if_any(map, path, "planes", "planes (cuboid, sphere, cylinder primitives only)")?;
    let object_pose = frame * pose(map.and_then(|m| m.get("pose")), &join(path, "pose"))?;
    let (meshes, mp) = sequence(map, path, "meshes")?;
    let (mesh_poses, mpp) = sequence(map, path, "mesh_poses")?;
    if meshes.len() != mesh_poses.len() {
        return Err(at(
            &mpp,
            format!("{} poses for {} meshes", mesh_poses.len(), meshes.len()),
        ));
    }
    let mut out = Vec::new();
    for (i, (m, p)) in meshes.iter().zip(mesh_poses).enumerate() {
        let placed = object_pose * pose(Some(p), &format!("{mpp}[{i}]"))?;
        out.push(mesh(m, &format!("{mp}[{i}]"), &placed)?);
    }
    let (primitives, pp) = sequence(map, path, "primitives")?;
    let (poses, posep) = sequence(map, path, "primitive_poses")?;
    if primitives.len() != poses.len() {
        return Err(at(
            &posep,
            format!("{} poses for {} primitives", poses.len(), primitives.len()),
        ));
    }
    for (i, (prim, p)) in primitives.iter().zip(poses).enumerate() {
        let placed = object_pose * pose(Some(p), &format!("{posep}[{i}]"))?;
        out.push(primitive(prim, &format!("{pp}[{i}]"), &placed)?);
    }
    Ok((id, out))
}

/// `moveit_msgs/AttachedCollisionObject`s: at most one, on the arm's hand (`panda_hand`; another
/// arm's TCP link), with one primitive (the held object, in that frame).
fn attached(items: &[Value], path: &str, arm: &ArmNames) -> R<Option<(String, Value)>> {
    let mut held = None;
    for (i, item) in items.iter().enumerate() {
        let ip = format!("{path}[{i}]");
        let map = mapping(
            item,
            &ip,
            &["link_name", "object", "touch_links", "detach_posture", "weight"],
        )?;
        let link = string(map, &ip, "link_name")?;
        if link != arm.hand {
            return Err(at(
                &join(&ip, "link_name"),
                format!("attached to {link:?}: only objects held by {} are supported", arm.hand),
            ));
        }
        if held.is_some() {
            return Err(at(&ip, "a second attached object: edmp-scene/1 holds one"));
        }
        let op = join(&ip, "object");
        let (id, mut prims) = collision_object(
            map.and_then(|m| m.get("object")).unwrap_or(&Value::Null),
            &op,
            ObjectFrames::Hand(arm.hand),
        )?;
        if prims.len() != 1 {
            return Err(at(
                &join(&op, "primitives"),
                format!("{} primitives: a held object is one primitive", prims.len()),
            ));
        }
        held = prims.pop().map(|p| (id, p));
    }
    Ok(held)
}

const ROBOT_STATE: [&str; 4] = [
    "joint_state",
    "multi_dof_joint_state",
    "attached_collision_objects",
    "is_diff",
];

/// Finger openings read from joint states, each with its YAML path.
type Fingers = Vec<(f64, String)>;

/// What a `moveit_msgs/RobotState` holds for us.
#[derive(Debug, Default)]
struct State {
    joints: Option<Vec<f64>>,
    held: Option<(String, Value)>,
    fingers: Fingers,
    /// Where the virtual joint places the base link in the planning frame, if it is given.
    base: Option<Isometry3<f64>>,
}

fn robot_state(v: &Value, path: &str, arm: &ArmNames) -> R<State> {
    let map = mapping(v, path, &ROBOT_STATE)?;
    let base = base_placement(
        map.and_then(|m| m.get("multi_dof_joint_state")).unwrap_or(&Value::Null),
        &join(path, "multi_dof_joint_state"),
    )?;
    let (items, ap) = sequence(map, path, "attached_collision_objects")?;
    let held = attached(items, &ap, arm)?;
    let jp = join(path, "joint_state");
    let js = mapping(
        map.and_then(|m| m.get("joint_state")).unwrap_or(&Value::Null),
        &jp,
        &["header", "name", "position", "velocity", "effort"],
    )?;
    let (names, np) = sequence(js, &jp, "name")?;
    let (positions, pp) = sequence(js, &jp, "position")?;
    if names.is_empty() && positions.is_empty() {
        return Ok(State {
            held,
            base,
            ..State::default()
        });
    }
    if names.len() != positions.len() {
        return Err(at(
            &pp,
            format!("{} positions for {} names", positions.len(), names.len()),
        ));
    }
    let mut joints = vec![None; arm.joints.len()];
    let mut fingers = Vec::new();
    for (i, (name, value)) in names.iter().zip(positions).enumerate() {
        let name = name
            .as_str()
            .ok_or_else(|| at(&format!("{np}[{i}]"), "expected a joint name"))?;
        let x = number(value, &format!("{pp}[{i}]"))?;
        assign(arm, &mut joints, &mut fingers, name, x, &format!("{np}[{i}]"))?;
    }
    Ok(State {
        joints: Some(complete(arm, joints, &np)?),
        held,
        fingers,
        base,
    })
}

/// A `sensor_msgs/MultiDOFJointState`: at most one joint (any name; MoveIt's Panda calls it
/// `virtual_joint`), whose transform places the arm's base link in the planning frame. Its twist and
/// wrench are ignored (a plan is positions; MoveIt's planners ignore start velocities too).
fn base_placement(v: &Value, path: &str) -> R<Option<Isometry3<f64>>> {
    let map = mapping(v, path, &["header", "joint_names", "transforms", "twist", "wrench"])?;
    let (names, np) = sequence(map, path, "joint_names")?;
    let (transforms, tp) = sequence(map, path, "transforms")?;
    if names.len() != transforms.len() {
        return Err(at(
            &tp,
            format!("{} transforms for {} joints", transforms.len(), names.len()),
        ));
    }
    match names.len() {
        0 => return Ok(None),
        1 => {}
        _ => {
            return Err(at(
                &format!("{np}[1]"),
                "a second multi-DOF joint: an arm has one, the virtual joint that places its base",
            ));
        }
    }
    if !names[0].is_string() {
        return Err(at(&format!("{np}[0]"), "expected a joint name"));
    }
    let parent = frame_id(map, path)?;
    if !(parent.is_empty() || parent == PLANNING_FRAME) {
        return Err(at(
            &join(path, "header.frame_id"),
            format!(
                "frame {parent:?} is not supported (the virtual joint's parent is the planning frame: world, or empty)"
            ),
        ));
    }
    let t0 = format!("{tp}[0]");
    let t = mapping(&transforms[0], &t0, &["translation", "rotation"])?;
    let translation = vector(t.and_then(|t| t.get("translation")), &join(&t0, "translation"))?;
    let rotation = orientation(t.and_then(|t| t.get("rotation")), &join(&t0, "rotation"))?;
    let placed = Isometry3::from_parts(Translation3::from(translation), rotation);
    Ok(Some(if is_identity(&placed) {
        Isometry3::identity()
    } else {
        placed
    }))
}

/// Records joint `name` = `x` (a finger's opening goes to `fingers`, with its path).
fn assign(arm: &ArmNames, joints: &mut [Option<f64>], fingers: &mut Fingers, name: &str, x: f64, path: &str) -> R<()> {
    if let Some(slot) = arm
        .joints
        .iter()
        .position(|n| *n == name)
        .and_then(|j| joints.get_mut(j))
    {
        if slot.replace(x).is_some() {
            return Err(at(path, format!("{name} given twice")));
        }
        Ok(())
    } else if arm.fingers.contains(&name) {
        fingers.push((x, path.to_owned()));
        Ok(())
    } else {
        let fingers = if arm.fingers.is_empty() { "" } else { " and the fingers" };
        Err(at(
            path,
            format!(
                "unknown joint {name:?} ({}'s joints are {}{fingers})",
                arm.arm,
                arm.joints.join(", ")
            ),
        ))
    }
}

fn complete(arm: &ArmNames, joints: Vec<Option<f64>>, path: &str) -> R<Vec<f64>> {
    joints
        .into_iter()
        .zip(arm.joints)
        .map(|(q, name)| q.ok_or_else(|| at(path, format!("{name} is missing"))))
        .collect()
}

/// Links rigidly attached to the TCP that a pose goal may name, and their TCP offset.
fn tcp_offset(arm: &ArmNames, link: &str, path: &str) -> R<Isometry3<f64>> {
    // After the last joint nothing moves (the Panda's fingers are held): these frames are
    // rigid with the TCP.
    let frame = arm
        .rigid
        .contains(&link)
        .then(|| arm.frames.iter().position(|n| *n == link))
        .flatten()
        .ok_or_else(|| {
            at(
                path,
                format!(
                    "link {link:?} is not supported for a pose goal (one of {})",
                    arm.rigid.join(", ")
                ),
            )
        })?;
    let offset = match arm.arm {
        Arm::Panda => frame_to_tcp(&edmp_core::robot::arms::panda::ROBOT_F64, frame),
        Arm::Iiwa7 => frame_to_tcp(&edmp_core::robot::arms::iiwa7::ROBOT_F64, frame),
        Arm::Xarm6 => frame_to_tcp(&edmp_core::robot::arms::xarm6::ROBOT_F64, frame),
    };
    offset.ok_or_else(|| at(path, format!("link {link:?}: no forward kinematics at zero")))
}

/// Frame `frame`'s pose to the TCP's, at the zero configuration (they are rigid).
fn frame_to_tcp<const J: usize>(robot: &'static Robot<f64, J>, frame: usize) -> Option<Isometry3<f64>> {
    let k = forward(robot, &[0.0; J]).ok()?;
    let iso = |p: &edmp_core::robot::kinematics::Pose<f64>| {
        let r = Rotation3::from_matrix_unchecked(Matrix3::from(p.rotation));
        Isometry3::from_parts(
            Translation3::from(p.translation),
            UnitQuaternion::from_rotation_matrix(&r),
        )
    };
    Some(iso(k.frames.get(frame)?).inverse() * iso(k.frames.get(robot.tcp_frame)?))
}

/// The fields of `moveit_msgs/Constraints` (a goal, or the path constraints).
const CONSTRAINTS: [&str; 5] = [
    "name",
    "joint_constraints",
    "position_constraints",
    "orientation_constraints",
    "visibility_constraints",
];

/// The goal of `moveit_msgs/Constraints`: joints (and finger openings), or the TCP pose.
fn goal(v: &Value, path: &str, frames: &Frames) -> R<(Value, Fingers)> {
    let arm = &frames.arm;
    let map = mapping(v, path, &CONSTRAINTS)?;
    unsupported_if_any(map, path, "visibility_constraints", "visibility constraints")?;
    let (jc, jcp) = sequence(map, path, "joint_constraints")?;
    let (pc, pcp) = sequence(map, path, "position_constraints")?;
    let (oc, ocp) = sequence(map, path, "orientation_constraints")?;
    if !jc.is_empty() {
        if !pc.is_empty() || !oc.is_empty() {
            return Err(at(path, "joint and pose constraints together: give one kind"));
        }
        let mut joints = vec![None; arm.joints.len()];
        let mut fingers = Vec::new();
        for (i, c) in jc.iter().enumerate() {
            let cp = format!("{jcp}[{i}]");
            let m = mapping(
                c,
                &cp,
                &["joint_name", "position", "tolerance_above", "tolerance_below", "weight"],
            )?;
            let name = string(m, &cp, "joint_name")?;
            let x = number(
                m.and_then(|m| m.get("position")).unwrap_or(&Value::Null),
                &join(&cp, "position"),
            )?;
            assign(arm, &mut joints, &mut fingers, name, x, &join(&cp, "joint_name"))?;
        }
        return Ok((json!({"joints": complete(arm, joints, &jcp)?}), fingers));
    }
    match (pc.len(), oc.len()) {
        (1, 1) => {}
        (0, 0) => return Err(at(path, "no joint, position or orientation constraint")),
        (1, 0) => return Err(at(path, "a position constraint without an orientation constraint")),
        (0, 1) => return Err(at(path, "an orientation constraint without a position constraint")),
        _ => return Err(at(path, "more than one position or orientation constraint")),
    }
    let (pp, op) = (format!("{pcp}[0]"), format!("{ocp}[0]"));
    let pm = mapping(
        &pc[0],
        &pp,
        &[
            "header",
            "link_name",
            "target_point_offset",
            "constraint_region",
            "weight",
        ],
    )?;
    let om = mapping(
        &oc[0],
        &op,
        &[
            "header",
            "orientation",
            "link_name",
            "absolute_x_axis_tolerance",
            "absolute_y_axis_tolerance",
            "absolute_z_axis_tolerance",
            "parameterization",
            "weight",
        ],
    )?;
    let pframe = frames.pose(&frame_id(pm, &pp)?, &join(&pp, "header.frame_id"))?;
    let oframe = frames.pose(&frame_id(om, &op)?, &join(&op, "header.frame_id"))?;
    let link = string(pm, &pp, "link_name")?;
    let olink = string(om, &op, "link_name")?;
    if link != olink {
        return Err(at(
            &join(&op, "link_name"),
            format!("{olink:?}, but the position constraint is on {link:?}"),
        ));
    }
    let offset = tcp_offset(arm, link, &join(&pp, "link_name"))?;
    let point_offset = vector(
        pm.and_then(|m| m.get("target_point_offset")),
        &join(&pp, "target_point_offset"),
    )?;
    let rp = join(&pp, "constraint_region");
    let region = mapping(
        pm.and_then(|m| m.get("constraint_region")).unwrap_or(&Value::Null),
        &rp,
        &["primitives", "primitive_poses", "meshes", "mesh_poses"],
    )?;
    unsupported_if_any(
        region,
        &rp,
        "meshes",
        "mesh regions (the region's first primitive pose is the target)",
    )?;
    let (poses, posep) = sequence(region, &rp, "primitive_poses")?;
    let target = match poses {
        [] => {
            return Err(at(
                &posep,
                "missing: the target position is the region's primitive pose",
            ));
        }
        [p] => (pframe * pose(Some(p), &format!("{posep}[0]"))?).translation.vector,
        _ => return Err(at(&posep, "more than one region: the target must be one point")),
    };
    let rotation = oframe.rotation * orientation(om.and_then(|m| m.get("orientation")), &join(&op, "orientation"))?;
    // The constrained point is `link · point_offset`; place the link so it lands on the target.
    let link_pose = Isometry3::from_parts(Translation3::from(target - rotation * point_offset), rotation);
    let (position, quaternion) = center_and_quaternion(&(link_pose * offset));
    Ok((
        json!({"pose": {"position": position, "quaternion": quaternion}}),
        Vec::new(),
    ))
}

const PLANNING_SCENE: [&str; 10] = [
    "name",
    "robot_state",
    "robot_model_name",
    "fixed_frame_transforms",
    "allowed_collision_matrix",
    "link_padding",
    "link_scale",
    "object_colors",
    "world",
    "is_diff",
];

/// Padding must be 0 and scale 1 (`moveit_msgs/LinkPadding` / `LinkScale`): the checker's robot
/// is the URDF's.
fn link_adjustments(map: Option<&Map<String, Value>>, key: &str, neutral: f64) -> R<()> {
    let (items, p) = sequence(map, "", key)?;
    for (i, item) in items.iter().enumerate() {
        let ip = format!("{p}[{i}]");
        let m = mapping(item, &ip, &["link_name", key.strip_prefix("link_").unwrap_or(key)])?;
        let field = key.strip_prefix("link_").unwrap_or(key);
        let x = number_or_zero(m, &ip, field)?;
        if (x - neutral).abs() > 1e-12 {
            return Err(at(
                &join(&ip, field),
                format!("{x}: not supported (the robot is checked as its URDF, {field} {neutral})"),
            ));
        }
    }
    Ok(())
}

/// The scene's obstacles (with their ids), its robot state, and its frames. `request_base`:
/// the request's start state's virtual joint, which (as MoveIt merges a start state into the
/// scene's) places the base instead of the scene's own.
fn scene_part(
    v: &Value,
    request_base: Option<Isometry3<f64>>,
    arm: ArmNames,
) -> R<(Vec<Value>, Vec<String>, State, Frames)> {
    let map = mapping(v, "", &PLANNING_SCENE)?;
    let model = string(map, "", "robot_model_name")?;
    if !model.is_empty() && !arm.models.contains(&model) {
        let known: Vec<&str> = Arm::ALL.iter().flat_map(|a| ArmNames::of(*a).models).copied().collect();
        return Err(at(
            "robot_model_name",
            format!("{model:?}: not an arm edmp-rs knows (one of {})", known.join(", ")),
        ));
    }
    link_adjustments(map, "link_padding", 0.0)?;
    link_adjustments(map, "link_scale", 1.0)?;
    let state = match map.and_then(|m| m.get("robot_state")) {
        Some(rs) => robot_state(rs, "robot_state", &arm)?,
        None => State::default(),
    };
    let base = request_base.or(state.base).unwrap_or_else(Isometry3::identity);
    let mut frames = Frames::new(&base, arm);
    let (fixed, fp) = sequence(map, "", "fixed_frame_transforms")?;
    frames.read_fixed(fixed, &fp)?;
    let world = mapping(
        map.and_then(|m| m.get("world")).unwrap_or(&Value::Null),
        "world",
        &["collision_objects", "octomap"],
    )?;
    if let Some(octo) = world.and_then(|w| w.get("octomap")) {
        let om = mapping(octo, "world.octomap", &["header", "origin", "octomap"])?;
        let inner = mapping(
            om.and_then(|m| m.get("octomap")).unwrap_or(&Value::Null),
            "world.octomap.octomap",
            &["header", "binary", "id", "resolution", "data"],
        )?;
        // A sequence of bytes (ROS), or robowflex's compressed hex string.
        match inner.and_then(|m| m.get("data")) {
            None | Some(Value::Null) => {}
            Some(Value::Array(a)) if a.is_empty() => {}
            Some(Value::String(h)) if h.is_empty() => {}
            Some(_) => {
                return Err(at(
                    "world.octomap.octomap.data",
                    "not supported: octomaps (primitives only)",
                ));
            }
        }
    }
    let (objects, op) = sequence(world, "world", "collision_objects")?;
    let mut obstacles = Vec::new();
    let mut ids = Vec::new();
    for (i, o) in objects.iter().enumerate() {
        let (id, prims) = collision_object(o, &format!("{op}[{i}]"), ObjectFrames::World(&frames))?;
        for p in prims {
            obstacles.push(p);
            ids.push(id.clone());
        }
    }
    Ok((obstacles, ids, state, frames))
}

const MOTION_PLAN_REQUEST: [&str; 16] = [
    "workspace_parameters",
    "start_state",
    "goal_constraints",
    "path_constraints",
    "trajectory_constraints",
    "reference_trajectories",
    "pipeline_id",
    "planner_id",
    "group_name",
    "num_planning_attempts",
    "allowed_planning_time",
    "max_velocity_scaling_factor",
    "max_acceleration_scaling_factor",
    "cartesian_speed_end_effector_link",
    "cartesian_speed_limited_link",
    "max_cartesian_speed",
];

/// The request's start state, after its checks (group, path and trajectory constraints).
fn request_start(v: &Value, arm: &ArmNames) -> R<State> {
    let map = mapping(v, "", &MOTION_PLAN_REQUEST)?;
    let group = string(map, "", "group_name")?;
    if !group.is_empty() && !arm.groups.contains(&group) {
        return Err(at(
            "group_name",
            format!("{group:?}: {}'s groups are {}", arm.arm, arm.groups.join(", ")),
        ));
    }
    if let Some(pc) = map.and_then(|m| m.get("path_constraints")) {
        let pm = mapping(pc, "path_constraints", &CONSTRAINTS)?;
        for key in [
            "joint_constraints",
            "position_constraints",
            "orientation_constraints",
            "visibility_constraints",
        ] {
            unsupported_if_any(pm, "path_constraints", key, "path constraints")?;
        }
    }
    if let Some(tc) = map.and_then(|m| m.get("trajectory_constraints")) {
        let tm = mapping(tc, "trajectory_constraints", &["constraints"])?;
        unsupported_if_any(tm, "trajectory_constraints", "constraints", "trajectory constraints")?;
    }
    unsupported_if_any(map, "", "reference_trajectories", "reference trajectories")?;
    match map.and_then(|m| m.get("start_state")) {
        Some(s) => robot_state(s, "start_state", arm),
        None => Ok(State::default()),
    }
}

/// The request's goal, its frames resolved through the scene's.
fn request_goal(v: &Value, frames: &Frames) -> R<(Value, Fingers)> {
    let map = mapping(v, "", &MOTION_PLAN_REQUEST)?;
    let (goals, gp) = sequence(map, "", "goal_constraints")?;
    match goals {
        [] => Err(at(&gp, "missing: the request has no goal")),
        [g] => goal(g, &format!("{gp}[0]"), frames),
        _ => Err(at(&format!("{gp}[1]"), "a second goal: edmp-scene/1 has one")),
    }
}

/// Reads a MoveIt `PlanningScene` (and optionally a `MotionPlanRequest`) into an
/// `edmp-scene/1` document. The start is the request's start state, else the scene's robot
/// state; without a request the goal is the start (edit it before planning). The result is not
/// yet validated: see [`import_validated`].
pub fn import(scene_yaml: &str, request_yaml: Option<&str>) -> Result<Value, ImportError> {
    let in_scene = |e: At| ImportError {
        source: Source::Scene,
        path: e.path,
        message: e.message,
    };
    let in_request = |e: At| ImportError {
        source: Source::Request,
        path: e.path,
        message: e.message,
    };
    let scene_doc = load(scene_yaml).map_err(in_scene)?;
    let request_doc = request_yaml.map(load).transpose().map_err(in_request)?;
    let arm = ArmNames::detect(&scene_doc, request_doc.as_ref());
    let request_state = match &request_doc {
        Some(v) => Some(request_start(v, &arm).map_err(in_request)?),
        None => None,
    };
    let (obstacles, ids, scene_state, frames) =
        scene_part(&scene_doc, request_state.as_ref().and_then(|s| s.base), arm).map_err(in_scene)?;
    let request = match (request_state, &request_doc) {
        (Some(state), Some(v)) => Some((state, request_goal(v, &frames).map_err(in_request)?)),
        _ => None,
    };
    let tag = |fingers: Fingers, source: Source| {
        fingers
            .into_iter()
            .map(move |(x, path)| (x, path, source))
            .collect::<Vec<_>>()
    };
    let (start, goal, held, fingers) = match request {
        Some((state, (goal, goal_fingers))) => {
            // As MoveIt merges a start state into the scene's: fingers the request does not
            // name stay where the scene's robot state has them.
            let scene_fingers = tag(scene_state.fingers, Source::Scene);
            let (start, mut fingers) = match state.joints {
                Some(q) if !state.fingers.is_empty() => (q, tag(state.fingers, Source::Request)),
                Some(q) => (q, scene_fingers),
                None => (
                    scene_state.joints.ok_or_else(|| ImportError {
                        source: Source::Request,
                        path: "start_state.joint_state".into(),
                        message: "no start: neither the request nor the scene's robot_state has a joint state".into(),
                    })?,
                    scene_fingers,
                ),
            };
            fingers.extend(tag(goal_fingers, Source::Request));
            let held = match (state.held, scene_state.held) {
                (Some(_), Some(_)) => {
                    return Err(ImportError {
                        source: Source::Request,
                        path: "start_state.attached_collision_objects".into(),
                        message: "the scene's robot_state holds an object too: edmp-scene/1 holds one".into(),
                    });
                }
                (a, b) => a.or(b),
            };
            (start, goal, held, fingers)
        }
        None => {
            let start = scene_state.joints.ok_or_else(|| ImportError {
                source: Source::Scene,
                path: "robot_state.joint_state".into(),
                message: "no start: give a request with a start_state, or a joint state here".into(),
            })?;
            let fingers = tag(scene_state.fingers, Source::Scene);
            let goal = json!({ "joints": start });
            (start, goal, scene_state.held, fingers)
        }
    };
    // Both fingers, at the start and the goal: one opening for the whole plan.
    let opening = fingers.first().map(|f| f.0);
    if let (Some(w), Some((_, first, _))) = (opening, fingers.first())
        && let Some((x, path, source)) = fingers.iter().find(|f| (f.0 - w).abs() > FINGER_TOLERANCE)
    {
        return Err(ImportError {
            source: *source,
            path: path.clone(),
            message: format!(
                "finger at {x} m, but {first} is at {w} m: the fingers hold one opening for the whole plan"
            ),
        });
    }
    let mut doc = json!({
        "format": "edmp-scene/1",
        "obstacles": obstacles,
        "start": start,
        "goal": goal,
        "meta": {
            "source": "moveit",
            "object_ids": ids,
            "goal_from": if request_yaml.is_some() { "request" } else { "start (no request)" },
        },
    });
    // Absent is the Panda: its documents stay as they were before other arms.
    if arm.arm != Arm::Panda {
        doc["robot"] = json!(arm.arm.name());
    }
    if let Some(w) = opening.filter(|w| (w - FINGER_OPENING).abs() > FINGER_TOLERANCE) {
        doc["gripper"] = json!({ "finger": w });
    }
    if let Some((id, object)) = held {
        doc["held_object"] = object;
        doc["meta"]["held_object_id"] = json!(id);
    }
    Ok(doc)
}

/// Checks an imported document with the host's `edmp-scene/1` reader for the arm it names
/// (the same checks as `edmp-host plan`: limits, valid ends, quaternions).
pub fn validate(doc: &Value) -> Result<(), String> {
    let text = doc.to_string();
    let invalid = |e: String| format!("the imported edmp-scene/1 is not valid: {e}");
    let arm = scene_arm(&text).map_err(|e| invalid(e.to_string()))?;
    with_arm!(arm, robot => parse_problem_for(&text, Path::new("."), robot).map(|_| ()))
        .map_err(|e| invalid(e.to_string()))
}

/// [`import`], then [`validate`].
pub fn import_validated(scene_yaml: &str, request_yaml: Option<&str>) -> Result<Value, String> {
    let doc = import(scene_yaml, request_yaml).map_err(|e| e.to_string())?;
    validate(&doc)?;
    Ok(doc)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn yaml(text: &str) -> Value {
        load(text).unwrap()
    }

    #[test]
    fn a_mesh_becomes_the_scene_formats_mesh_obstacle() {
        // shape_msgs/Mesh as ROS writes it, placed 1 m up and yawed 90°.
        let v = yaml(
            "triangles:\n- vertex_indices: [0, 1, 2]\n- vertex_indices: [0, 2, 3]\nvertices:\n\
             - {x: 0.0, y: 0.0, z: 0.0}\n- {x: 0.1, y: 0.0, z: 0.0}\n- {x: 0.1, y: 0.1, z: 0.0}\n- {x: 0, y: 0.1, z: 0}\n",
        );
        let placed = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 1.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), core::f64::consts::FRAC_PI_2),
        );
        let h = core::f64::consts::FRAC_1_SQRT_2;
        let want = json!({
            "type": "mesh",
            "vertices": [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0]],
            "triangles": [[0, 1, 2], [0, 2, 3]],
            "center": [0.0, 0.0, 1.0],
            "quaternion": [round(h), 0.0, 0.0, round(h)],
            "scale": 1,
        });
        assert_eq!(mesh(&v, "m", &placed).unwrap(), want);
        // robowflex's compact form: the same mesh.
        let compact =
            yaml("triangles: [[0, 1, 2], [0, 2, 3]]\nvertices: [[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]]\n");
        assert_eq!(mesh(&compact, "m", &placed).unwrap(), want);
    }

    #[test]
    fn a_bad_mesh_names_its_path() {
        let id = Isometry3::identity();
        let cases = [
            (
                "triangles: [[0, 1, 3]]\nvertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]]",
                "m.triangles[0][2]",
                "3 is not a vertex index (0..3)",
            ),
            (
                "triangles: [{vertex_indices: [0, 1]}]\nvertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]]",
                "m.triangles[0].vertex_indices",
                "expected 3 vertex indices, found 2",
            ),
            (
                "triangles: []\nvertices: [[0, 0, 0]]",
                "m.triangles",
                "missing: a mesh has triangles",
            ),
            ("vertices: []", "m.vertices", "missing: a mesh has vertices"),
            (
                "resource: package://x/bunny.dae\ndimensions: [1, 1, 1]",
                "m.resource",
                "a mesh file",
            ),
            (
                "triangles: [[0, 1, 2]]\nvertices: [[0, 0], [1, 0, 0], [0, 1, 0]]",
                "m.vertices[0]",
                "expected 3 numbers, found 2",
            ),
        ];
        for (text, path, message) in cases {
            let e = mesh(&yaml(text), "m", &id).unwrap_err();
            assert_eq!(e.path, path, "{text}");
            assert!(e.message.starts_with(message), "{text}: {}", e.message);
        }
    }

    #[test]
    fn the_virtual_joint_places_the_base() {
        let none = base_placement(&yaml("joint_names: []\ntransforms: []"), "s").unwrap();
        assert!(none.is_none());
        // Near the identity reads as the identity exactly.
        let near =
            yaml("joint_names: [virtual_joint]\ntransforms: [{translation: [1e-12, 0, 0], rotation: [0, 0, 0, 1]}]");
        assert_eq!(base_placement(&near, "s").unwrap(), Some(Isometry3::identity()));
        let moved = yaml(
            "joint_names: [base]\ntransforms: [{translation: {x: 1, y: 2, z: 0}, rotation: {x: 0, y: 0, z: 0, w: 1}}]",
        );
        let p = base_placement(&moved, "s").unwrap().unwrap();
        assert_eq!(p.translation.vector, Vector3::new(1.0, 2.0, 0.0));
        let two = yaml("joint_names: [a, b]\ntransforms: [{}, {}]");
        assert_eq!(base_placement(&two, "s").unwrap_err().path, "s.joint_names[1]");
        let short = yaml("joint_names: [a]\ntransforms: []");
        assert_eq!(base_placement(&short, "s").unwrap_err().path, "s.transforms");
        let frame = yaml("header: {frame_id: panda_link0}\njoint_names: [a]\ntransforms: [{}]");
        assert_eq!(base_placement(&frame, "s").unwrap_err().path, "s.header.frame_id");
    }
}
