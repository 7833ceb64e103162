//! MoveIt planning scenes and motion plan requests (YAML) as `edmp-scene/1`: the hand-written
//! files under `tests/moveit/`, the errors that name a YAML path, the command line, and a round
//! trip of every example through MoveIt's format that plans to the same bits.

use core::fmt::Write as _;
use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::planner::PlanConfig;
use edmp_core::robot::kinematics::forward;
use edmp_host::formats::json::{Goal, joint_goal, parse_problem};
use edmp_host::formats::moveit::{import, import_validated};
use edmp_host::planning::{chosen_guides, plan_problem};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde_json::{Value, json};
use std::process::Command;

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/moveit");

fn file(name: &str) -> String {
    std::fs::read_to_string(format!("{DIR}/{name}")).unwrap()
}

fn example(name: &str) -> Value {
    let path = format!("{}/../examples/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// Equal as the planner reads them (`f32`).
fn same_f32(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| *x as f32 == *y as f32)
}

/// Quaternions equal up to sign (q and -q are one rotation), to `tol` or (`tol` < 0) as f32.
fn same_rotation(a: &[f64], b: &[f64], tol: f64) -> bool {
    let neg: Vec<f64> = b.iter().map(|x| -x).collect();
    if tol < 0.0 {
        same_f32(a, b) || same_f32(a, &neg)
    } else {
        close(a, b, tol) || close(a, &neg, tol)
    }
}

/// The obstacles (or held objects) of two documents agree to `tol`; `tol` < 0: as f32.
fn assert_same_primitive(a: &Value, b: &Value, tol: f64, what: &str) {
    assert_eq!(a["type"], b["type"], "{what}");
    let same = |x: &[f64], y: &[f64]| if tol < 0.0 { same_f32(x, y) } else { close(x, y, tol) };
    for key in ["center", "dims"] {
        if a.get(key).is_some() {
            assert!(same(&floats(&a[key]), &floats(&b[key])), "{what}.{key}: {a} vs {b}");
        }
    }
    for key in ["radius", "height"] {
        if let Some(x) = a.get(key) {
            assert!(
                same(&[x.as_f64().unwrap()], &[b[key].as_f64().unwrap()]),
                "{what}.{key}"
            );
        }
    }
    if a.get("quaternion").is_some() {
        assert!(
            same_rotation(&floats(&a["quaternion"]), &floats(&b["quaternion"]), tol),
            "{what}.quaternion: {a} vs {b}"
        );
    }
}

#[test]
fn the_table_scene_with_a_joint_goal_is_the_wall_example() {
    let doc = import_validated(&file("table_box.scene.yaml"), Some(&file("joint_goal.request.yaml"))).unwrap();
    let problem = parse_problem(&doc.to_string()).unwrap();
    let wall = example("wall.json");
    let (got, want) = (
        doc["obstacles"].as_array().unwrap(),
        wall["obstacles"].as_array().unwrap(),
    );
    assert_eq!(got.len(), want.len());
    // The table is a 1.6 × 1.2 box yawed 90° (the wall example's 1.2 × 1.6 box, unrotated).
    assert_eq!(got[0]["type"], "cuboid");
    assert!(close(&floats(&got[0]["center"]), &[0.5, 0.0, -0.01], 1e-12));
    assert!(close(&floats(&got[0]["dims"]), &[1.6, 1.2, 0.02], 0.0));
    let h = core::f64::consts::FRAC_1_SQRT_2;
    assert!(close(&floats(&got[0]["quaternion"]), &[h, 0.0, 0.0, h], 1e-12));
    for i in 1..want.len() {
        assert_same_primitive(&got[i], &want[i], 1e-12, &format!("obstacles[{i}]"));
    }
    assert_eq!(doc["meta"]["object_ids"], json!(["table", "wall", "can", "ball"]));
    assert!(close(&floats(&doc["start"]), &floats(&wall["start"]), 0.0));
    assert!(close(
        &floats(&doc["goal"]["joints"]),
        &floats(&wall["goal"]["joints"]),
        0.0
    ));
    assert!(matches!(problem.goal, Goal::Joints(_)));

    let guides = chosen_guides(&[]).unwrap();
    let planned = plan_problem(edmp_core::prior::PANDA, &problem, &guides, &PlanConfig::DEFAULT, 0).unwrap();
    assert!(planned.plan.is_free());
    let report = check_trajectory(
        &edmp_core::robot::PANDA,
        &problem.scene(),
        &planned.plan.paths[planned.plan.best],
        &CheckConfig::default(),
        false,
    )
    .unwrap();
    assert!(report.is_free());
}

#[test]
fn a_hand_pose_goal_becomes_the_tcp_pose() {
    let doc = import_validated(&file("table_box.scene.yaml"), Some(&file("pose_goal.request.yaml"))).unwrap();
    let problem = parse_problem(&doc.to_string()).unwrap();
    let pose = &doc["goal"]["pose"];
    // FK of the wall example's goal: the hand points straight down, so the TCP is 0.105 m lower.
    assert!(
        close(
            &floats(&pose["position"]),
            &[0.48748365, -0.3335055, 0.36002734 - 0.105],
            1e-6
        ),
        "{pose}"
    );
    assert!(same_rotation(
        &floats(&pose["quaternion"]),
        &[0.0, 0.9553953, -0.29533, 0.0],
        1e-6
    ));
    let goal = joint_goal(&problem).unwrap();
    let tcp = *forward(&edmp_core::robot::PANDA, &goal).unwrap().tcp();
    let want = [0.48748365f32, -0.3335055, 0.25502735];
    for (x, y) in tcp.translation.iter().zip(want) {
        assert!((x - y).abs() < 1e-3, "IK's TCP {:?}", tcp.translation);
    }
}

fn error(scene: &str, request: Option<&str>, want: &str) -> String {
    match import(scene, request) {
        Ok(_) => panic!("expected {want:?}, but it imported"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_mesh_becomes_a_mesh_obstacle_placed_in_the_world() {
    let doc = import(&file("mesh.scene.yaml"), Some(&file("joint_goal.request.yaml"))).unwrap();
    let obstacles = doc["obstacles"].as_array().unwrap();
    let meshes: Vec<&serde_json::Value> = obstacles.iter().filter(|o| o["type"] == "mesh").collect();
    assert_eq!(meshes.len(), 1, "{obstacles:?}");
    let m = meshes[0];
    assert!(!m["vertices"].as_array().unwrap().is_empty() && !m["triangles"].as_array().unwrap().is_empty());
    // The imported scene reads back as a problem whose surface holds the mesh's triangles.
    let problem = parse_problem(&doc.to_string()).unwrap();
    assert_eq!(problem.surfaces.obstacles.len(), 1);
    assert!(problem.surfaces.pieces() > 0);
}

#[test]
fn unsupported_or_bad_entries_name_their_yaml_path() {
    let scene = file("table_box.scene.yaml");
    let request = file("pose_goal.request.yaml");
    let joint_request = file("joint_goal.request.yaml");
    let cases: Vec<(String, Option<String>, &str)> = vec![
        (
            scene.replace("header: {frame_id: world}", "header: {frame_id: camera}"),
            None,
            "scene: world.collision_objects[1].header.frame_id: frame \"camera\" is not supported",
        ),
        (
            scene.replace("{type: 2, dimensions: [0.06]}", "{type: 4, dimensions: [0.1, 0.05]}"),
            None,
            "scene: world.collision_objects[3].primitives[0].type: CONE (4) is not supported",
        ),
        (
            scene.replace("z: 0.7071067811865476\n", "z: 0.5\n"),
            None,
            "scene: world.collision_objects[0].pose.orientation: norm 0.8660, expected 1",
        ),
        (
            scene.replace("    id: can\n", "    id: can\n    colour: red\n"),
            None,
            "scene: world.collision_objects[2].colour: unknown field",
        ),
        (
            scene.replace("{type: 3, dimensions: [0.2, 0.05]}", "{type: 3, dimensions: [0.2]}"),
            None,
            "scene: world.collision_objects[2].primitives[0].dimensions: expected 2 dimensions",
        ),
        (
            scene.replace("    - 0.025\n    - 0.025\n", "    - 0.025\n    - 0.04\n"),
            None,
            "scene: robot_state.joint_state.name[8]: finger at 0.04 m, but robot_state.joint_state.name[7] is at 0.025 m",
        ),
        (
            scene.replace("  padding: 0.0", "  padding: 0.01"),
            None,
            "scene: link_padding[0].padding: 0.01: not supported",
        ),
        (
            scene.replace("data: []", "data: [1, 2, 3]"),
            None,
            "scene: world.octomap.octomap.data: not supported: octomaps",
        ),
        (
            scene.replace("operation: 0", "operation: 1"),
            None,
            "scene: world.collision_objects[0].operation: operation 1 is not supported",
        ),
        (
            scene.replace(
                "  attached_collision_objects: []",
                "  attached_collision_objects:\n  - link_name: panda_link7\n    object: {id: tool}",
            ),
            None,
            "scene: robot_state.attached_collision_objects[0].link_name: attached to \"panda_link7\"",
        ),
        (
            scene.clone(),
            Some(request.replace("link_name: panda_hand", "link_name: panda_link5")),
            "request: goal_constraints[0].position_constraints[0].link_name: link \"panda_link5\" is not supported",
        ),
        (
            scene.clone(),
            Some(request.replace("    orientation: {x: 0.9553953", "    orientation: {x: 0.5")),
            "request: goal_constraints[0].orientation_constraints[0].orientation: norm",
        ),
        (
            scene.clone(),
            Some(request.replace("orientation_constraints:\n  - header", "orientation_constraints: []\n  - header")),
            "request: not valid YAML",
        ),
        (
            scene.clone(),
            Some(joint_request.replace("joint_name: panda_joint7", "joint_name: panda_joint8")),
            "request: goal_constraints[0].joint_constraints[6].joint_name: unknown joint \"panda_joint8\"",
        ),
        (
            scene.clone(),
            Some(joint_request.replace(
                "  - {joint_name: panda_joint7, position: 0.785, tolerance_above: 0.0001, tolerance_below: 0.0001, weight: 1.0}\n",
                "",
            )),
            "request: goal_constraints[0].joint_constraints: panda_joint7 is missing",
        ),
        (
            scene.clone(),
            Some(joint_request.replace("group_name: panda_arm", "group_name: hand")),
            "request: group_name: \"hand\": panda's groups are panda_arm, panda_manipulator",
        ),
        (
            scene.clone(),
            Some(joint_request.replace(
                "  orientation_constraints: []\n  visibility_constraints: []\ntrajectory",
                "  orientation_constraints:\n  - {link_name: panda_hand}\n  visibility_constraints: []\ntrajectory",
            )),
            "request: path_constraints.orientation_constraints: not supported: path constraints",
        ),
    ];
    for (scene, request, want) in cases {
        let got = error(&scene, request.as_deref(), want);
        assert!(got.starts_with(want), "expected {want:?}, got {got:?}");
    }
}

/// The obstacles, start and goal of two imports are the same document parts, exactly.
fn assert_same_problem(got: &Value, want: &Value, what: &str) {
    for key in ["obstacles", "start", "goal", "gripper", "held_object"] {
        assert_eq!(got.get(key), want.get(key), "{what}: {key}");
    }
}

#[test]
fn scenes_as_moveit_and_motionbenchmaker_export_them_are_the_explicit_frame_scene() {
    // Empty or absent frames, the identity virtual joint, fixed transforms, a collision matrix,
    // neutral padding and scale, an empty octomap, byte operations; and robowflex's compact forms.
    let explicit = file("table_box.scene.yaml");
    for name in ["exported.scene.yaml", "robowflex.scene.yaml"] {
        let scene = file(name);
        for request in [
            None,
            Some(file("joint_goal.request.yaml")),
            Some(file("pose_goal.request.yaml")),
        ] {
            let got = import_validated(&scene, request.as_deref()).unwrap_or_else(|e| panic!("{name}: {e}"));
            let want = import_validated(&explicit, request.as_deref()).unwrap();
            assert_same_problem(&got, &want, name);
            assert_eq!(
                got["meta"]["object_ids"],
                json!(["table", "wall", "can", "ball"]),
                "{name}"
            );
        }
    }
    // A request as MotionBenchMaker stores it: the pose goal request's problem.
    let got = import_validated(&file("robowflex.scene.yaml"), Some(&file("robowflex.request.yaml"))).unwrap();
    let want = import_validated(&explicit, Some(&file("pose_goal.request.yaml"))).unwrap();
    assert_same_problem(&got, &want, "robowflex.request.yaml");
}

#[test]
fn an_object_may_name_a_frame_of_fixed_frame_transforms() {
    // The table's placement moved from its pose to a fixed frame it names.
    let scene = file("robowflex.scene.yaml")
        .replace(
            "allowed_collision_matrix:",
            "  - header: {frame_id: panda_link0}\n    child_frame_id: table_frame\n    transform:\n      \
             translation: [0.5, 0, 0]\n      rotation: [0, 0, 0.7071067811865476, 0.7071067811865476]\n\
             allowed_collision_matrix:",
        )
        .replace(
            "    - id: table\n      pose:\n        position: [0.5, 0, 0]\n        orientation: [0, 0, 0.7071067811865476, 0.7071067811865476]\n",
            "    - id: table\n      header: {frame_id: table_frame}\n",
        );
    assert!(scene.contains("table_frame}"), "{scene}");
    let got = import_validated(&scene, None).unwrap();
    let want = import_validated(&file("table_box.scene.yaml"), None).unwrap();
    let (a, b) = (
        got["obstacles"].as_array().unwrap(),
        want["obstacles"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_same_primitive(x, y, 1e-12, &format!("obstacles[{i}]"));
    }
}

/// `doc` with every obstacle and the pose goal placed by `base` (as a world whose
/// `panda_link0` is at `base` sees them).
fn seen_from_world(doc: &Value, base: &Isometry3<f64>) -> Value {
    let place = |center: &[f64], wxyz: &[f64]| {
        let q = UnitQuaternion::from_quaternion(Quaternion::new(wxyz[0], wxyz[1], wxyz[2], wxyz[3]));
        let p = base * Isometry3::from_parts(Translation3::new(center[0], center[1], center[2]), q);
        let q = p.rotation.quaternion();
        (
            json!([p.translation.x, p.translation.y, p.translation.z]),
            json!([q.w, q.i, q.j, q.k]),
        )
    };
    let mut out = doc.clone();
    for o in out["obstacles"].as_array_mut().unwrap() {
        let wxyz = o.get("quaternion").map_or(vec![1.0, 0.0, 0.0, 0.0], floats);
        let (c, q) = place(&floats(&o["center"]), &wxyz);
        o["center"] = c;
        if o["type"] != "sphere" {
            o["quaternion"] = q;
        }
    }
    if let Some(pose) = out["goal"].get_mut("pose") {
        let (c, q) = place(&floats(&pose["position"]), &floats(&pose["quaternion"]));
        pose["position"] = c;
        pose["quaternion"] = q;
    }
    out
}

#[test]
fn a_placed_virtual_joint_puts_the_world_in_the_base_frame() {
    // panda_link0 1 m forward, 0.5 m left, 0.2 m up and yawed 90° in `world`: obstacles and goals
    // written in `world` (or an empty frame) come back in panda_link0, where the examples have them.
    let h = core::f64::consts::FRAC_1_SQRT_2;
    let base = Isometry3::from_parts(
        Translation3::new(1.0, 0.5, 0.2),
        UnitQuaternion::from_quaternion(Quaternion::new(h, 0.0, 0.0, h)),
    );
    let joint = format!(
        "  multi_dof_joint_state:\n    header: {{frame_id: world}}\n    joint_names: [virtual_joint]\n    \
         transforms: [{{translation: {{x: 1.0, y: 0.5, z: 0.2}}, rotation: {{x: 0, y: 0, z: {h}, w: {h}}}}}]\n    \
         twist: [{{linear: {{x: 0.1, y: 0, z: 0}}, angular: {{x: 0, y: 0, z: 0}}}}]\n    wrench: []\n"
    );
    for name in ["wall.json", "tabletop-pose-held.json"] {
        let original = example(name);
        let (scene, request) = to_moveit(&seen_from_world(&original, &base));
        let scene = scene.replace("{frame_id: panda_link0}", "{frame_id: ''}");
        let request = request.replace("{frame_id: panda_link0}", "{frame_id: world}");
        // The virtual joint in the scene's robot state, or in the request's start state (which,
        // as MoveIt merges it, wins over the scene's).
        let in_scene = (
            scene.replace("robot_state:\n", &format!("robot_state:\n{joint}")),
            request.clone(),
        );
        let in_request = (
            scene.replace("robot_state:\n", "robot_state:\n  multi_dof_joint_state: {joint_names: [virtual_joint], transforms: [{translation: [5, 5, 5], rotation: [0, 0, 0, 1]}]}\n"),
            request.replace("start_state:\n", &format!("start_state:\n{joint}")),
        );
        for (scene, request) in [in_scene, in_request] {
            let back =
                import_validated(&scene, Some(&request)).unwrap_or_else(|e| panic!("{name}: {e}\n{scene}\n{request}"));
            let (a, b) = (
                original["obstacles"].as_array().unwrap(),
                back["obstacles"].as_array().unwrap(),
            );
            assert_eq!(a.len(), b.len(), "{name}");
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                // The examples' quaternions are f32s, normalised on the way: 1e-6, not 1e-12.
                assert_same_primitive(x, y, 1e-6, &format!("{name}: obstacles[{i}]"));
            }
            if let Some(held) = original.get("held_object") {
                assert_same_primitive(held, &back["held_object"], 1e-12, name);
            }
            if let Some(p) = original["goal"].get("pose") {
                let q = &back["goal"]["pose"];
                assert!(
                    close(&floats(&p["position"]), &floats(&q["position"]), 1e-6),
                    "{name}: {p} vs {q}"
                );
                assert!(
                    same_rotation(&floats(&p["quaternion"]), &floats(&q["quaternion"]), 1e-6),
                    "{name}"
                );
            }
        }
    }
}

#[test]
fn exported_scenes_refuse_what_they_cannot_express_by_yaml_path() {
    let exported = file("exported.scene.yaml");
    let compact = file("robowflex.scene.yaml");
    let mut cases: Vec<(String, &str)> = vec![
        (
            compact.replace(
                "    joint_names: [virtual_joint]\n    transforms: [{translation: [0, 0, 0], rotation: [0, 0, 0, 1]}]",
                "    joint_names: [virtual_joint, mobile_base]\n    transforms: [{translation: [0, 0, 0], rotation: [0, 0, 0, 1]}, {}]",
            ),
            "scene: robot_state.multi_dof_joint_state.joint_names[1]: a second multi-DOF joint",
        ),
        (
            exported.replacen("    joint_names:\n    - virtual_joint\n", "    joint_names:\n    - virtual_joint\n    - mobile_base\n", 1),
            "scene: robot_state.multi_dof_joint_state.transforms: 1 transforms for 2 joints",
        ),
        (
            exported.replacen("      frame_id: world\n    joint_names:", "      frame_id: panda_hand\n    joint_names:", 1),
            "scene: robot_state.multi_dof_joint_state.header.frame_id: frame \"panda_hand\" is not supported",
        ),
        (
            compact.replacen("      translation: [0, 0, 0]\n", "      translation: [0, 0, 0.5]\n", 1),
            "scene: fixed_frame_transforms[0].transform: places \"world\" at translation [0.000000, 0.000000, 0.500000]",
        ),
        (
            exported.replacen("  child_frame_id: panda_link0\n  transform:\n    translation:\n      x: 0.0", "  child_frame_id: panda_link0\n  transform:\n    translation:\n      x: 0.3", 1),
            "scene: fixed_frame_transforms[0].transform: places \"panda_link0\" at translation [0.300000",
        ),
        (
            compact.replace("child_frame_id: world", "child_frame_id: panda_hand"),
            "scene: fixed_frame_transforms[0].child_frame_id: \"panda_hand\" is a robot link",
        ),
        (
            compact.replace("  - child_frame_id: world", "  - header: {frame_id: map}\n    child_frame_id: odom"),
            "scene: fixed_frame_transforms[0].header.frame_id: frame \"map\" is not supported",
        ),
        (
            exported.replacen("  frame_id: ''\n    pose:", "  frame_id: camera\n    pose:", 1),
            "scene: world.collision_objects[0].header.frame_id: frame \"camera\" is not supported",
        ),
        (
            exported.replacen("  scale: 1.0", "  scale: 1.1", 1),
            "scene: link_scale[0].scale: 1.1: not supported",
        ),
        (
            exported.replacen("- link_name: panda_link7\n  padding: 0.0", "- link_name: panda_link7\n  padding: 0.02", 1),
            "scene: link_padding[1].padding: 0.02: not supported",
        ),
        (
            exported.replace("      data: []", "      data: [1, 2]"),
            "scene: world.octomap.octomap.data: not supported: octomaps",
        ),
        (
            compact.replace("world:\n", "world:\n  octomap:\n    octomap: {binary: true, id: OcTree, resolution: 0.1, data: 78DA0300}\n"),
            "scene: world.octomap.octomap.data: not supported: octomaps",
        ),
        (
            compact.replace("world:\n", "point_cloud: {}\nworld:\n"),
            "scene: point_cloud: unknown field",
        ),
        (
            exported.replacen("    meshes: []\n", "    meshes:\n    - {triangles: [[0, 1, 2]], vertices: [[0, 0, 0]]}\n", 1),
            "scene: world.collision_objects[0].mesh_poses: 0 poses for 1 meshes",
        ),
        (
            compact.replace(
                "    - id: wall\n",
                "    - id: bunny\n      meshes:\n        - resource: package://objects/bunny.dae\n          dimensions: [1, 1, 1]\n      \
                 mesh_poses:\n        - position: [0.4, 0, 0.3]\n          orientation: [0, 0, 0, 1]\n    - id: wall\n",
            ),
            "scene: world.collision_objects[1].meshes[0].resource: a mesh file",
        ),
        (
            compact.replace("type: sphere", "type: cone"),
            "scene: world.collision_objects[3].primitives[0].type: CONE (4) is not supported",
        ),
        (
            compact.replace("    - id: ball\n", "    - id: ball\n      operation: remove\n"),
            "scene: world.collision_objects[3].operation: operation \"remove\" is not supported",
        ),
    ];
    let held = |header: &str| {
        exported.replace(
            "  attached_collision_objects: []",
            &format!(
                "  attached_collision_objects:\n  - link_name: panda_hand\n    object:\n      {header}id: tool\n      \
                 primitives: [{{type: 2, dimensions: [0.02]}}]\n      primitive_poses: [{{position: {{x: 0, y: 0, z: 0.1}}}}]"
            ),
        )
    };
    // An empty frame is the link's, as MoveIt reads it; no header is ambiguous.
    let doc = import_validated(&held("header: {frame_id: ''}\n      "), None).unwrap();
    assert_eq!(doc["held_object"]["center"], json!([0.0, 0.0, 0.1]));
    cases.push((
        held(""),
        "scene: robot_state.attached_collision_objects[0].object: no header",
    ));
    for (scene, want) in cases {
        assert_ne!(scene, exported);
        assert_ne!(scene, compact, "{want}: the replacement did not apply");
        let got = error(&scene, None, want);
        assert!(got.starts_with(want), "expected {want:?}, got {got:?}");
    }
}

#[test]
fn open_fingers_become_the_gripper_field() {
    let scene = file("table_box.scene.yaml").replace("    - 0.025\n    - 0.025\n", "    - 0.035\n    - 0.035\n");
    let doc = import_validated(&scene, Some(&file("pose_goal.request.yaml"))).unwrap();
    let problem = parse_problem(&doc.to_string()).unwrap();
    assert_eq!(doc["gripper"], json!({"finger": 0.035}));
    assert_eq!(problem.scene().gripper(), 0.035);
    let doc = import_validated(&file("table_box.scene.yaml"), None).unwrap();
    assert!(doc.get("gripper").is_none(), "0.025 m is the format's default");
}

#[test]
fn without_a_request_the_start_comes_from_the_scene_and_the_goal_is_the_start() {
    let doc = import_validated(&file("table_box.scene.yaml"), None).unwrap();
    assert_eq!(doc["goal"]["joints"], doc["start"]);
    assert_eq!(doc["meta"]["goal_from"], "start (no request)");
}

#[test]
fn an_end_in_collision_is_refused_by_the_json_reader() {
    // The ball moved onto the start's hand: MoveIt's YAML is fine, the problem is not.
    let scene = file("table_box.scene.yaml").replace("{x: 0.35, y: -0.45, z: 0.6}", "{x: 0.4875, y: 0.3335, z: 0.36}");
    let e = import_validated(&scene, Some(&file("joint_goal.request.yaml"))).unwrap_err();
    assert!(e.contains("start: in collision"), "{e}");
}

#[test]
fn the_command_line_writes_a_scene_that_plans() {
    let out = std::env::temp_dir().join(format!("edmp-moveit-{}.json", std::process::id()));
    let run = Command::new(env!("CARGO_BIN_EXE_edmp-host"))
        .args(["import-moveit", "--scene", &format!("{DIR}/table_box.scene.yaml")])
        .args(["--request", &format!("{DIR}/joint_goal.request.yaml"), "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    std::fs::remove_file(&out).ok();
    parse_problem(&text).unwrap();
    let meshed = Command::new(env!("CARGO_BIN_EXE_edmp-host"))
        .args(["import-moveit", "--scene", &format!("{DIR}/mesh.scene.yaml")])
        .output()
        .unwrap();
    // No start in the scene and no request: refused by its YAML path.
    assert_eq!(meshed.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&meshed.stderr);
    assert!(
        stderr.contains("mesh.scene.yaml: robot_state.joint_state: no start"),
        "{stderr}"
    );
}

// ---- A tiny writer: edmp-scene/1 → MoveIt YAML, to round-trip the examples. ----

fn ros_pose(center: &[f64], wxyz: &[f64]) -> String {
    format!(
        "{{position: {{x: {}, y: {}, z: {}}}, orientation: {{x: {}, y: {}, z: {}, w: {}}}}}",
        center[0], center[1], center[2], wxyz[1], wxyz[2], wxyz[3], wxyz[0]
    )
}

/// The fields of a collision object of one primitive, one per line; even objects carry the
/// pose on the object, odd ones on the primitive (both are the object pose times the
/// primitive pose).
fn collision_object(id: &str, frame: &str, o: &Value, on_object: bool) -> Vec<String> {
    let center = floats(&o["center"]);
    let quaternion = o.get("quaternion").map_or(vec![1.0, 0.0, 0.0, 0.0], floats);
    let (kind, dims) = match o["type"].as_str().unwrap() {
        "cuboid" => (1, floats(&o["dims"])),
        "sphere" => (2, vec![o["radius"].as_f64().unwrap()]),
        "cylinder" => (3, vec![o["height"].as_f64().unwrap(), o["radius"].as_f64().unwrap()]),
        other => panic!("{other}"),
    };
    let identity = ros_pose(&[0.0; 3], &[1.0, 0.0, 0.0, 0.0]);
    let placed = ros_pose(&center, &quaternion);
    let (object_pose, primitive_pose) = if on_object {
        (&placed, &identity)
    } else {
        (&identity, &placed)
    };
    let dims: Vec<String> = dims.iter().map(f64::to_string).collect();
    vec![
        format!("header: {{frame_id: {frame}}}"),
        format!("id: {id}"),
        format!("pose: {object_pose}"),
        format!("primitives: [{{type: {kind}, dimensions: [{}]}}]", dims.join(", ")),
        format!("primitive_poses: [{primitive_pose}]"),
        "operation: 0".to_owned(),
    ]
}

fn joint_state(q: &Value) -> String {
    let names: Vec<String> = (1..=7).map(|j| format!("panda_joint{j}")).collect();
    let q: Vec<String> = floats(q).iter().map(f64::to_string).collect();
    format!("{{name: [{}], position: [{}]}}", names.join(", "), q.join(", "))
}

/// The scene as a `PlanningScene` and its problem as a `MotionPlanRequest`; a pose goal is
/// written on `panda_hand` (0.105 m behind the TCP along its z).
fn to_moveit(doc: &Value) -> (String, String) {
    let mut scene = String::from("robot_model_name: panda\nrobot_state:\n");
    match doc.get("held_object") {
        Some(held) => {
            scene.push_str("  attached_collision_objects:\n  - link_name: panda_hand\n    object:\n");
            for line in collision_object("held", "panda_hand", held, true) {
                writeln!(scene, "      {line}").unwrap();
            }
        }
        None => scene.push_str("  attached_collision_objects: []\n"),
    }
    scene.push_str("world:\n  collision_objects:\n");
    for (i, o) in doc["obstacles"].as_array().unwrap().iter().enumerate() {
        let lines = collision_object(&format!("obstacle{i}"), "panda_link0", o, i % 2 == 0);
        for (k, line) in lines.iter().enumerate() {
            writeln!(scene, "  {}{line}", if k == 0 { "- " } else { "  " }).unwrap();
        }
    }
    let mut request = format!(
        "group_name: panda_arm\nstart_state:\n  joint_state: {}\ngoal_constraints:\n- name: goal\n",
        joint_state(&doc["start"])
    );
    if let Some(q) = doc["goal"].get("joints") {
        request.push_str("  joint_constraints:\n");
        for (j, x) in floats(q).iter().enumerate() {
            writeln!(
                request,
                "  - {{joint_name: panda_joint{}, position: {x}, weight: 1.0}}",
                j + 1
            )
            .unwrap();
        }
    } else {
        let pose = &doc["goal"]["pose"];
        let (p, q) = (floats(&pose["position"]), floats(&pose["quaternion"]));
        // The hand's origin: the TCP minus 0.105 m along the TCP's z axis.
        let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
        let n = (w * w + x * x + y * y + z * z).sqrt();
        let (w, x, y, z) = (w / n, x / n, y / n, z / n);
        let axis = [
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ];
        let hand: Vec<f64> = (0..3).map(|k| p[k] - 0.105 * axis[k]).collect();
        writeln!(
            request,
            "  position_constraints:\n  - header: {{frame_id: panda_link0}}\n    link_name: panda_hand\n    \
             constraint_region:\n      primitives: [{{type: 2, dimensions: [0.001]}}]\n      primitive_poses: [{}]",
            ros_pose(&hand, &[1.0, 0.0, 0.0, 0.0])
        )
        .unwrap();
        writeln!(
            request,
            "  orientation_constraints:\n  - header: {{frame_id: panda_link0}}\n    link_name: panda_hand\n    \
             orientation: {{x: {}, y: {}, z: {}, w: {}}}",
            q[1], q[2], q[3], q[0]
        )
        .unwrap();
    }
    (scene, request)
}

#[test]
fn every_example_round_trips_through_moveit_yaml_and_plans_the_same() {
    let guides = chosen_guides(&[]).unwrap();
    for name in ["wall.json", "cubby.json", "dresser.json", "tabletop-pose-held.json"] {
        let original = example(name);
        let (scene, request) = to_moveit(&original);
        let back =
            import_validated(&scene, Some(&request)).unwrap_or_else(|e| panic!("{name}: {e}\n{scene}\n{request}"));
        let problem = parse_problem(&back.to_string()).unwrap();
        let (a, b) = (
            original["obstacles"].as_array().unwrap(),
            back["obstacles"].as_array().unwrap(),
        );
        assert_eq!(a.len(), b.len(), "{name}");
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert_same_primitive(x, y, -1.0, &format!("{name}: obstacles[{i}]"));
        }
        match original.get("held_object") {
            Some(held) => assert_same_primitive(held, &back["held_object"], -1.0, name),
            None => assert!(back.get("held_object").is_none()),
        }
        assert!(
            close(&floats(&original["start"]), &floats(&back["start"]), 0.0),
            "{name}"
        );
        if let Some(q) = original["goal"].get("joints") {
            assert!(close(&floats(q), &floats(&back["goal"]["joints"]), 0.0), "{name}");
        } else {
            let (p, q) = (&original["goal"]["pose"], &back["goal"]["pose"]);
            assert!(
                same_f32(&floats(&p["position"]), &floats(&q["position"])),
                "{name}: {p} vs {q}"
            );
            assert!(
                same_rotation(&floats(&p["quaternion"]), &floats(&q["quaternion"]), -1.0),
                "{name}"
            );
        }
        // Same problem, same seed: the same plan, and our checker's verdict on it.
        let direct = parse_problem(&original.to_string()).unwrap();
        let want = plan_problem(edmp_core::prior::PANDA, &direct, &guides, &PlanConfig::DEFAULT, 3).unwrap();
        let got = plan_problem(edmp_core::prior::PANDA, &problem, &guides, &PlanConfig::DEFAULT, 3).unwrap();
        assert_eq!(
            got.plan.paths[got.plan.best], want.plan.paths[want.plan.best],
            "{name}: the imported scene plans differently"
        );
        let report = check_trajectory(
            &edmp_core::robot::PANDA,
            &problem.scene(),
            &got.plan.paths[got.plan.best],
            &CheckConfig::default(),
            false,
        )
        .unwrap();
        assert_eq!(report.is_free(), got.plan.is_free(), "{name}");
    }
}

/// A MoveIt scene and joint-goal request for another arm (its joint names, its groups; the
/// model name optional), with a post behind the arm and a box held by its TCP link.
fn other_arm_files<const J: usize>(
    robot: &edmp_core::robot::Robot<f32, J>,
    model: Option<&str>,
    group: &str,
    goal: &[f32; J],
) -> (String, String) {
    let list = |q: &[f32]| q.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(", ");
    let names = robot.joint_names.join(", ");
    let tcp = robot.frame_names[robot.tcp_frame];
    let model = model.map_or(String::new(), |m| format!("robot_model_name: {m}\n"));
    let scene = format!(
        "{model}robot_state:
  joint_state:
    name: [{names}]
    position: [{start}]
  multi_dof_joint_state:
    header: {{frame_id: world}}
    joint_names: [virtual_joint]
    transforms: [{{translation: {{x: 0, y: 0, z: 0}}, rotation: {{x: 0, y: 0, z: 0, w: 1}}}}]
  attached_collision_objects:
  - link_name: {tcp}
    object:
      id: tool
      header: {{frame_id: {tcp}}}
      primitives: [{{type: box, dimensions: [0.02, 0.02, 0.02]}}]
      primitive_poses: [{{position: {{x: 0, y: 0, z: 0.05}}}}]
world:
  collision_objects:
  - id: post
    header: {{frame_id: world}}
    primitives: [{{type: box, dimensions: [0.1, 0.1, 0.4]}}]
    primitive_poses: [{{position: {{x: -0.8, y: 0.0, z: 0.2}}}}]
",
        start = list(&robot.neutral)
    );
    let constraints: String = robot
        .joint_names
        .iter()
        .zip(goal)
        .map(|(n, x)| format!("  - {{joint_name: {n}, position: {x}}}\n"))
        .collect();
    let request = format!("group_name: {group}\ngoal_constraints:\n- joint_constraints:\n{constraints}");
    (scene, request)
}

fn other_arm_is_read_by_its_names<const J: usize>(robot: &'static edmp_core::robot::Robot<f32, J>, group: &str) {
    let mut goal = robot.neutral;
    goal[0] += 0.5;
    for model in [None, Some(robot.name)] {
        let (scene, request) = other_arm_files(robot, model, group, &goal);
        let doc = import_validated(&scene, Some(&request)).unwrap_or_else(|e| panic!("{}: {e}\n{scene}", robot.name));
        assert_eq!(doc["robot"], json!(robot.name));
        let start: Vec<f64> = robot.neutral.iter().map(|&x| f64::from(x)).collect();
        assert!(close(&floats(&doc["start"]), &start, 1e-6));
        let want: Vec<f64> = goal.iter().map(|&x| f64::from(x)).collect();
        assert!(close(&floats(&doc["goal"]["joints"]), &want, 1e-6));
        assert_eq!(doc["held_object"]["type"], "cuboid");
        assert!(close(&floats(&doc["held_object"]["center"]), &[0.0, 0.0, 0.05], 1e-12));
        let problem =
            edmp_host::formats::json::parse_problem_for(&doc.to_string(), std::path::Path::new("."), robot).unwrap();
        assert_eq!(problem.start, robot.neutral);
    }

    // A pose goal on the TCP link is the TCP pose itself.
    let k = forward(robot, &goal).unwrap();
    let tcp = k.tcp();
    let [w, x, y, z] = tcp.quaternion_wxyz();
    let link = robot.frame_names[robot.tcp_frame];
    let (scene, _) = other_arm_files(robot, None, group, &goal);
    let pose_request = format!(
        "group_name: {group}
goal_constraints:
- position_constraints:
  - link_name: {link}
    constraint_region:
      primitive_poses: [{{position: {{x: {}, y: {}, z: {}}}}}]
  orientation_constraints:
  - link_name: {link}
    orientation: {{x: {x}, y: {y}, z: {z}, w: {w}}}
",
        tcp.translation.x, tcp.translation.y, tcp.translation.z
    );
    let doc = import_validated(&scene, Some(&pose_request)).unwrap();
    let p = &doc["goal"]["pose"];
    let want = [tcp.translation.x, tcp.translation.y, tcp.translation.z].map(f64::from);
    assert!(close(&floats(&p["position"]), &want, 1e-6), "{p}");
    assert!(
        same_rotation(&floats(&p["quaternion"]), &[w, x, y, z].map(f64::from), 1e-6),
        "{p}"
    );

    // What does not fit the arm is refused by path, naming the arm's own names.
    let (scene, request) = other_arm_files(robot, None, "panda_arm", &goal);
    let e = import_validated(&scene, Some(&request)).unwrap_err();
    assert!(e.contains("group_name") && e.contains(group), "{e}");
    let (scene, request) = other_arm_files(robot, None, group, &goal);
    let mixed = request.replacen(robot.joint_names[1], "panda_joint2", 1);
    let e = import_validated(&scene, Some(&mixed)).unwrap_err();
    assert!(
        e.contains("unknown joint \"panda_joint2\"") && e.contains(robot.joint_names[1]),
        "{e}"
    );
    let e = import_validated(&format!("robot_model_name: ur5\n{scene}"), Some(&request)).unwrap_err();
    assert!(e.contains("robot_model_name") && e.contains("ur5"), "{e}");
    let held_by_base = scene.replace(
        &format!("link_name: {link}"),
        &format!("link_name: {}", robot.frame_names[1]),
    );
    let e = import_validated(&held_by_base, Some(&request)).unwrap_err();
    assert!(
        e.contains("attached_collision_objects[0].link_name") && e.contains(link),
        "{e}"
    );
}

#[test]
fn another_arms_scene_is_read_by_its_joint_names() {
    other_arm_is_read_by_its_names(&edmp_core::robot::arms::iiwa7::ROBOT, "manipulator");
    other_arm_is_read_by_its_names(&edmp_core::robot::arms::xarm6::ROBOT, "xarm6");
}
