//! The `edmp-host` command line as a user runs it: exit codes, outputs, error messages.

use std::process::Command;

fn edmp_host(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_edmp-host"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("edmp-host runs")
}

#[test]
fn fk_prints_every_frame() {
    let out = edmp_host(&["fk", "0", "-0.785", "0", "-2.356", "0", "1.571", "0.785", "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["frames"].as_array().unwrap().len(), 13);
    assert_eq!(v["collision_boxes"].as_array().unwrap().len(), 11);
    assert_eq!(v["within_soft_limits"], true);
}

/// A reader that has closed its end (`edmp-host fk | head -1` once `head` is done): the output
/// ends quietly with success, not with a panic.
#[test]
fn fk_into_a_closed_pipe_is_no_panic() {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    for json in [false, true] {
        let mut args = vec!["fk", "0", "-0.785", "0", "-2.356", "0", "1.571", "0.785"];
        if json {
            args.push("--json");
        }
        let out = Command::new(env!("CARGO_BIN_EXE_edmp-host"))
            .args(&args)
            .stdout(writer.try_clone().expect("a second writer"))
            .output()
            .expect("edmp-host runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "json {json}: {:?} {stderr}", out.status);
        assert!(stderr.is_empty(), "json {json}: {stderr}");
    }
}

#[test]
fn rrt_plans_the_example_and_writes_the_file() {
    let path = std::env::temp_dir().join(format!("edmp-rrt-{}.json", std::process::id()));
    let out = edmp_host(&["rrt", "examples/wall.json", "--seed", "1", "-o", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(plan["format"], "edmp-plan/1");
    assert_eq!(plan["status"], "success");
    let waypoints = plan["waypoints"].as_array().unwrap();
    assert_eq!(waypoints.len(), 50);
    assert_eq!(waypoints[0].as_array().unwrap()[0].as_f64().unwrap() as f32, 0.6);
}

/// `plan`, `rrt` and `render` read the arm from the scene: an xArm 6 problem is planned with 6
/// joints and drawn with its plan, a 7-joint start is refused by its path; a Panda-only command
/// names the arm it refuses.
#[test]
fn another_arms_scene_is_planned_with_its_joints_or_refused_by_name() {
    let scene = "benchmarks/xarm6/problems/cubby/000.json";
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{}/../{scene}", env!("CARGO_MANIFEST_DIR"))).unwrap())
            .unwrap();
    for command in ["plan", "rrt"] {
        let out = edmp_host(&[command, scene]);
        assert!(
            out.status.success(),
            "{command}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let waypoints = plan["waypoints"].as_array().unwrap();
        assert_eq!(waypoints.len(), 50, "{command}");
        assert!(waypoints.iter().all(|q| q.as_array().unwrap().len() == 6), "{command}");
        let first: Vec<f64> = waypoints[0]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let start: Vec<f64> = doc["start"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(
            first.iter().zip(&start).all(|(a, b)| (a - b).abs() < 1e-4),
            "{command}: {first:?}"
        );
    }
    let dir = std::env::temp_dir().join(format!("edmp-xarm6-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (plan, png) = (dir.join("plan.json"), dir.join("plan.png"));
    assert!(
        edmp_host(&["plan", scene, "-o", plan.to_str().unwrap()])
            .status
            .success()
    );
    let out = edmp_host(&["render", scene, plan.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert!(out.status.success(), "render: {}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // A Panda's plan (7 joints) drawn over the xArm's scene is refused by its path.
    let panda_plan = dir.join("panda.json");
    assert!(
        edmp_host(&["plan", "examples/wall.json", "-o", panda_plan.to_str().unwrap()])
            .status
            .success()
    );
    let out = edmp_host(&[
        "render",
        scene,
        panda_plan.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("waypoints[0]: expected 6 numbers, found 7"));
    let seven = dir.join("seven.json");
    let mut bad = doc.clone();
    bad["start"].as_array_mut().unwrap().push(serde_json::json!(0.0));
    std::fs::write(&seven, bad.to_string()).unwrap();
    let out = edmp_host(&["plan", seven.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("start: expected 6 numbers, found 7"));
    // The firmware's bytes carry the arm's 6 joints; one call embeds one arm's scenes.
    let embedded = dir.join("embedded");
    let out = edmp_host(&["embed", scene, "--out", embedded.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let bytes = std::fs::read(embedded.join("cubby-000.postcard")).unwrap();
    let mut surface = Box::new(edmp_core::wire::WireSurface::<320, 80>::new());
    let problem = edmp_core::wire::decode::<64, 320, 80, 6>(&bytes, &mut surface).unwrap();
    assert_eq!(problem.start.len(), 6);
    let out = edmp_host(&[
        "embed",
        scene,
        "examples/wall.json",
        "--out",
        embedded.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("one firmware plans one arm"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_names_the_field_exits_2_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("edmp-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.json");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/wall.json"))
        .unwrap()
        .replace(r#""radius": 0.06"#, r#""radius": 0.06, "colour": "red""#);
    std::fs::write(&scene, text).unwrap();
    let plan = dir.join("plan.json");
    let out = edmp_host(&["rrt", scene.to_str().unwrap(), "-o", plan.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("obstacles[3].colour: unknown field"), "{stderr}");
    assert!(!plan.exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn render_writes_a_png_of_the_scene_and_of_a_plan_with_its_candidates() {
    let dir = std::env::temp_dir().join(format!("edmp-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (png, plan) = (dir.join("scene.png"), dir.join("plan.json"));
    let size = |path: &std::path::Path| {
        let bytes = std::fs::read(path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        // IHDR: width, height.
        (
            u32::from_be_bytes([bytes[16], bytes[17], bytes[18], bytes[19]]),
            u32::from_be_bytes([bytes[20], bytes[21], bytes[22], bytes[23]]),
        )
    };
    let out = edmp_host(&["render", "examples/wall.json", "-o", png.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(size(&png), (1800, 600), "three 600 × 600 views");
    let bare = std::fs::read(&png).unwrap();
    // --candidates needs a plan written with them.
    let out = edmp_host(&["plan", "examples/wall.json", "-o", plan.to_str().unwrap()]);
    assert!(out.status.success());
    let out = edmp_host(&[
        "render",
        "examples/wall.json",
        plan.to_str().unwrap(),
        "--candidates",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--candidates"));
    let out = edmp_host(&[
        "plan",
        "examples/wall.json",
        "--candidates",
        "-o",
        plan.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let out = edmp_host(&[
        "render",
        "examples/wall.json",
        plan.to_str().unwrap(),
        "--candidates",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(size(&png), (1800, 600));
    assert_ne!(std::fs::read(&png).unwrap(), bare, "the plan is drawn");
    // A cloud (PLY) and a mesh (OBJ) read beside the scene (where they are drawn: the unit
    // tests of commands/render.rs).
    let out = edmp_host(&[
        "render",
        "edmp-host/tests/data/surfaces.json",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(size(&png), (1800, 600));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn plan_solves_the_example_deterministically_and_refuses_bad_input() {
    let dir = std::env::temp_dir().join(format!("edmp-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b) = (dir.join("a.json"), dir.join("b.json"));
    for path in [&a, &b] {
        let out = edmp_host(&[
            "plan",
            "examples/wall.json",
            "--seed",
            "1",
            "--candidates",
            "-o",
            path.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let read = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (pa, pb) = (read(&a), read(&b));
    assert_eq!(pa["format"], "edmp-plan/1");
    assert_eq!(pa["status"], "success");
    let w = pa["waypoints"].as_array().unwrap();
    assert_eq!(w.len(), 50);
    let row = |v: &serde_json::Value| {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect::<Vec<_>>()
    };
    assert_eq!(row(&w[0]), [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785]);
    assert_eq!(row(&w[49]), [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785]);
    assert_eq!(pa["candidates"].as_array().unwrap().len(), 12);
    // Same scene and seed: the same plan, bit for bit (timings aside).
    assert_eq!(pa["waypoints"], pb["waypoints"]);
    assert_eq!(pa["candidates"], pb["candidates"]);

    let bad = dir.join("bad.json");
    let text = std::fs::read_to_string("../examples/wall.json")
        .or_else(|_| std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/wall.json")))
        .unwrap()
        .replace("\"start\": [0.6,", "\"start\": [9.0,");
    std::fs::write(&bad, text).unwrap();
    let out_path = dir.join("never.json");
    let out = edmp_host(&["plan", bad.to_str().unwrap(), "-o", out_path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("start[0]"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!out_path.exists());
    let out = edmp_host(&["plan", "examples/wall.json", "--guides", "7"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--guides: no guide 7"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Each bad input: how the example is spoiled, and what standard error must say.
const BAD_PLAN_INPUTS: &[(&str, &str, &str)] = &[
    ("not JSON", "{", "not valid JSON"),
    (
        "wrong format",
        r#"{"format": "edmp-scene/2", "obstacles": [], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "format: expected \"edmp-scene/1\"",
    ),
    (
        "unknown field",
        r#"{"format": "edmp-scene/1", "obstacles": [], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0]}, "speed": 1}"#,
        "speed: unknown field",
    ),
    (
        "short start",
        r#"{"format": "edmp-scene/1", "obstacles": [], "start": [0,0,0,-2,0,2], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "start: expected 7 numbers, found 6",
    ),
    (
        "start outside the limits",
        r#"{"format": "edmp-scene/1", "obstacles": [], "start": [0,0,0,-2,0,2,3.5], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "start[6]",
    ),
    (
        "string in the goal",
        r#"{"format": "edmp-scene/1", "obstacles": [], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,"x",-2,0,2,0]}}"#,
        "goal.joints[2]",
    ),
    (
        "quaternion not unit",
        r#"{"format": "edmp-scene/1", "obstacles": [{"type": "cuboid", "center": [2,0,0], "dims": [0.1,0.1,0.1], "quaternion": [1,1,0,0]}], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "obstacles[0].quaternion",
    ),
    (
        "negative radius",
        r#"{"format": "edmp-scene/1", "obstacles": [{"type": "sphere", "center": [2,0,0], "radius": -0.1}], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "obstacles[0].radius",
    ),
    (
        "start in collision",
        r#"{"format": "edmp-scene/1", "obstacles": [{"type": "sphere", "center": [0,0,0.4], "radius": 0.2}], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "start: in collision",
    ),
    (
        "goal in collision",
        r#"{"format": "edmp-scene/1", "obstacles": [{"type": "sphere", "center": [0.554,0,0.3], "radius": 0.08}], "start": [0.8,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0]}}"#,
        "goal.joints: in collision",
    ),
    (
        "both goal kinds",
        r#"{"format": "edmp-scene/1", "obstacles": [], "start": [0,0,0,-2,0,2,0], "goal": {"joints": [0,0,0,-2,0,2,0], "pose": {"position": [0.5,0,0.5], "quaternion": [0,1,0,0]}}}"#,
        "goal: expected exactly one of",
    ),
    (
        "unreachable pose",
        r#"{"format": "edmp-scene/1", "obstacles": [], "start": [0,0,0,-2,0,2,0], "goal": {"pose": {"position": [3,0,0.5], "quaternion": [0,1,0,0]}}}"#,
        "goal.pose: unreachable",
    ),
];

#[test]
fn plan_refuses_every_bad_input_by_name_with_exit_2_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("edmp-plan-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let too_many = format!(
        r#"{{"format": "edmp-scene/1", "obstacles": [{}], "start": [0,0,0,-2,0,2,0], "goal": {{"joints": [0,0,0,-2,0,2,0]}}}}"#,
        vec![r#"{"type": "sphere", "center": [3,0,0], "radius": 0.1}"#; 65].join(",")
    );
    let mut cases: Vec<(&str, String, &str)> = BAD_PLAN_INPUTS
        .iter()
        .map(|(n, t, m)| (*n, t.to_string(), *m))
        .collect();
    cases.push((
        "too many obstacles",
        too_many,
        "obstacles: 65 primitive obstacles, at most 64",
    ));
    // Clouds and meshes by file, beside the scene: the error names the obstacle and the file.
    std::fs::write(dir.join("short.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n").unwrap();
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    let with = |obstacle: &str| {
        format!(
            r#"{{"format": "edmp-scene/1", "obstacles": [{obstacle}], "start": [0,0,0,-2,0,2,0], "goal": {{"joints": [0,0,0,-2,0,2,0]}}}}"#
        )
    };
    let surface_cases = [
        (
            "missing cloud file",
            with(r#"{"type": "points", "file": "absent.ply", "radius": 0.01}"#),
            "absent.ply: cannot read",
        ),
        (
            "truncated PLY",
            with(r#"{"type": "points", "file": "short.ply", "radius": 0.01}"#),
            "short.ply: line 9: element \"vertex\" row 2",
        ),
        (
            "OBJ index out of range",
            with(r#"{"type": "mesh", "file": "bad.obj"}"#),
            "obstacles[0].file: ",
        ),
        (
            "cloud radius",
            with(r#"{"type": "points", "points": [[3, 0, 0]], "radius": 0}"#),
            "obstacles[0].radius: must be positive",
        ),
        (
            "cloud point",
            with(r#"{"type": "points", "points": [[3, 0]], "radius": 0.01}"#),
            "obstacles[0].points[0]: expected 3 numbers",
        ),
        (
            "mesh index",
            with(r#"{"type": "mesh", "vertices": [[3, 0, 0], [3, 1, 0], [3, 0, 1]], "triangles": [[0, 1, 3]]}"#),
            "obstacles[0].triangles[0][2]: expected a vertex index below 3",
        ),
        (
            "mesh scale",
            with(
                r#"{"type": "mesh", "vertices": [[3, 0, 0], [3, 1, 0], [3, 0, 1]], "triangles": [[0, 1, 2]], "scale": -1}"#,
            ),
            "obstacles[0].scale: must be positive",
        ),
        (
            "cloud on the start",
            with(r#"{"type": "points", "points": [[0, 0, 0.5]], "radius": 0.05}"#),
            "start: in collision: ",
        ),
        // A closed 4 m cube around the whole arm: no body touches a triangle, all are inside.
        (
            "inside a closed mesh",
            with(
                r#"{"type": "mesh", "scale": 2, "vertices": [[-1,-1,-1],[1,-1,-1],[1,1,-1],[-1,1,-1],[-1,-1,1],[1,-1,1],[1,1,1],[-1,1,1]],
                   "triangles": [[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]]}"#,
            ),
            "start: in collision: panda_link1 inside the closed mesh obstacles[0]",
        ),
    ];
    for (name, text, message) in surface_cases {
        cases.push((name, text, message));
    }
    for (name, text, message) in cases {
        let scene = dir.join("scene.json");
        std::fs::write(&scene, text).unwrap();
        let plan = dir.join("plan.json");
        let out = edmp_host(&["plan", scene.to_str().unwrap(), "-o", plan.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(message), "{name}: expected `{message}` in: {stderr}");
        assert!(!plan.exists(), "{name}: a plan was written");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The scene of an `edmp-scene/1` document, rebuilt here from the JSON with the core's
/// constructors (independent of the host's parser). Clouds and meshes: inline vertices or an
/// ASCII PLY beside the examples, in the world frame (no placement), no robot filter.
fn scene_of(doc: &serde_json::Value) -> edmp_core::scene::Scene<'static> {
    use edmp_core::surface::bvh::{Key, Node, build, nodes_for};
    use edmp_core::surface::element::Element;
    let v3 = |v: &serde_json::Value| -> [f32; 3] { core::array::from_fn(|i| v[i].as_f64().unwrap() as f32) };
    let mut pieces = Vec::new();
    for (i, o) in doc["obstacles"].as_array().unwrap().iter().enumerate() {
        match o["type"].as_str().unwrap() {
            "points" => {
                let ply = std::fs::read_to_string(
                    std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples"))
                        .join(o["file"].as_str().unwrap()),
                )
                .unwrap();
                let body = ply.split("end_header\n").nth(1).unwrap();
                let r = o["radius"].as_f64().unwrap() as f32;
                for line in body.lines() {
                    let p: Vec<f32> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
                    pieces.push(Element::ball([p[0], p[1], p[2]], r, i as u16).unwrap());
                }
            }
            "mesh" => {
                let v: Vec<[f32; 3]> = o["vertices"].as_array().unwrap().iter().map(v3).collect();
                for t in o["triangles"].as_array().unwrap() {
                    let k = |j: usize| v[t[j].as_u64().unwrap() as usize];
                    pieces.extend(Element::triangle([k(0), k(1), k(2)], i as u16).unwrap());
                }
            }
            _ => {}
        }
    }
    let scene = primitive_scene_of(doc);
    if pieces.is_empty() {
        return scene;
    }
    let mut nodes = vec![Node::EMPTY; nodes_for(pieces.len())];
    let mut keys = vec![Key::EMPTY; pieces.len()];
    let used = build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys).unwrap();
    nodes.truncate(used);
    let (pieces, nodes): (&'static [Element], &'static [Node]) = (pieces.leak(), nodes.leak());
    let surface = edmp_core::surface::Surface::new(pieces, nodes).unwrap();
    scene.with_surface(surface, &[])
}

/// The primitives, held object and opening of an `edmp-scene/1` document.
fn primitive_scene_of(doc: &serde_json::Value) -> edmp_core::scene::Scene<'static> {
    use edmp_core::scene::{Obstacle, Scene};
    let v3 = |v: &serde_json::Value| -> [f32; 3] { core::array::from_fn(|i| v[i].as_f64().unwrap() as f32) };
    let v4 = |v: &serde_json::Value| -> [f32; 4] { core::array::from_fn(|i| v[i].as_f64().unwrap() as f32) };
    let primitive = |o: &serde_json::Value| -> Obstacle {
        let c = v3(&o["center"]);
        match o["type"].as_str().unwrap() {
            "cuboid" => Obstacle::cuboid(c, v3(&o["dims"]), v4(&o["quaternion"])).unwrap(),
            "cylinder" => Obstacle::cylinder(
                c,
                o["radius"].as_f64().unwrap() as f32,
                o["height"].as_f64().unwrap() as f32,
                v4(&o["quaternion"]),
            )
            .unwrap(),
            "sphere" => Obstacle::sphere(c, o["radius"].as_f64().unwrap() as f32).unwrap(),
            other => panic!("unknown type {other}"),
        }
    };
    let mut scene = Scene::new();
    for o in doc["obstacles"].as_array().unwrap() {
        if !matches!(o["type"].as_str(), Some("points" | "mesh")) {
            scene.push(primitive(o)).unwrap();
        }
    }
    if let Some(held) = doc.get("held_object") {
        scene.hold(primitive(held));
    }
    if let Some(w) = doc.get("gripper").map(|g| g["finger"].as_f64().unwrap() as f32) {
        scene = scene.with_gripper(w).unwrap();
    }
    scene
}

fn joints(v: &serde_json::Value) -> [f32; 7] {
    core::array::from_fn(|i| v[i].as_f64().unwrap() as f32)
}

#[test]
fn every_example_plans_a_collision_free_path_from_its_start_to_its_goal() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples");
    let mut examples: Vec<_> = std::fs::read_dir(root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    examples.sort();
    assert!(examples.len() >= 4, "{examples:?}");
    let mut pose_goals = 0;
    for path in examples {
        let name = path.display().to_string();
        let out = edmp_host(&["plan", path.to_str().unwrap()]);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(plan["status"], "success", "{name}");
        let waypoints: Vec<[f32; 7]> = plan["waypoints"].as_array().unwrap().iter().map(joints).collect();
        assert_eq!(waypoints.len(), 50, "{name}");
        assert_eq!(waypoints[0], joints(&doc["start"]), "{name}: start");
        let last = waypoints[49];
        if let Some(goal) = doc["goal"].get("joints") {
            assert_eq!(last, joints(goal), "{name}: goal");
        } else {
            pose_goals += 1;
            let pose = &doc["goal"]["pose"];
            let tcp = *edmp_core::robot::kinematics::forward(&edmp_core::robot::PANDA, &last)
                .unwrap()
                .tcp();
            let p = &pose["position"];
            let error: f32 = (0..3)
                .map(|i| (tcp.translation[i] - p[i].as_f64().unwrap() as f32).powi(2))
                .sum::<f32>()
                .sqrt();
            assert!(error < 1e-3, "{name}: TCP {error} m from the goal");
            let q = pose["quaternion"].as_array().unwrap();
            let want = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[0].as_f64().unwrap() as f32,
                q[1].as_f64().unwrap() as f32,
                q[2].as_f64().unwrap() as f32,
                q[3].as_f64().unwrap() as f32,
            ));
            let got = nalgebra::UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(
                tcp.rotation,
            ));
            assert!(
                got.angle_to(&want) < 1e-2,
                "{name}: TCP {} rad off",
                got.angle_to(&want)
            );
        }
        assert!(
            waypoints
                .iter()
                .all(|q| edmp_core::robot::PANDA.within_soft_limits(q, 0.0)),
            "{name}: outside the limits"
        );
        let trajectory: [[f32; 7]; 50] = core::array::from_fn(|i| waypoints[i]);
        let report = edmp_core::collision::checker::check_trajectory(
            &edmp_core::robot::PANDA,
            &scene_of(&doc),
            &trajectory,
            &edmp_core::collision::checker::CheckConfig::DEFAULT,
            false,
        )
        .unwrap();
        assert!(report.is_free(), "{name}: {report:?}");
    }
    assert!(pose_goals >= 1, "one example has a pose goal");
}

#[test]
fn plan_exits_1_and_still_writes_the_least_colliding_plan_when_no_candidate_is_free() {
    // Two unguided denoising steps and no global stage: the prior's paths run through the wall.
    let dir = std::env::temp_dir().join(format!("edmp-plan-1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("plan.json");
    let out = edmp_host(&[
        "plan",
        "examples/wall.json",
        "--steps",
        "2",
        "--gradient-steps",
        "0",
        "--refine-steps",
        "0",
        "--no-global",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no collision-free candidate"));
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(plan["status"], "collision");
    assert_eq!(plan["waypoints"].as_array().unwrap().len(), 50);
    assert_eq!(plan["stage"], "none");
    // With the global stage, the same first stage is rescued: a search path, reshaped by the prior.
    let out = edmp_host(&[
        "plan",
        "examples/wall.json",
        "--steps",
        "2",
        "--gradient-steps",
        "0",
        "--refine-steps",
        "0",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert!(
        plan["stage"] == "reseeded" || plan["stage"] == "search",
        "{}",
        plan["stage"]
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bench_writes_results_summary_and_charts_and_bench_report_compares_runs() {
    let dir = std::env::temp_dir().join(format!("edmp-bench-{}", std::process::id()));
    let (edmp, single, rrt, report) = (
        dir.join("edmp"),
        dir.join("single"),
        dir.join("rrt"),
        dir.join("report"),
    );
    for (out, extra) in [
        (&edmp, vec!["--serial"]),
        (&single, vec!["--guides", "1"]),
        (&rrt, vec!["--planner", "rrt-connect"]),
    ] {
        let mut args = vec!["bench", "--per-family", "1", "-o", out.to_str().unwrap()];
        args.extend(extra);
        let run = edmp_host(&args);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        for file in ["results.jsonl", "summary.md", "success.png", "time.png"] {
            assert!(out.join(file).exists(), "{}: no {file}", out.display());
        }
        let text = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
        let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        assert_eq!(lines.len(), 4, "one problem per family");
        for line in &lines {
            assert!(["success", "collision", "failure"].contains(&line["status"].as_str().unwrap()));
            assert!(line["time_ms"].as_f64().unwrap() > 0.0);
            assert!(line["problem"].as_str().unwrap().ends_with(".json"));
            if line["status"] == "success" {
                assert_eq!(line["waypoints"].as_array().unwrap().len(), 50);
            }
        }
    }
    let first: serde_json::Value = serde_json::from_str(
        std::fs::read_to_string(edmp.join("results.jsonl"))
            .unwrap()
            .lines()
            .next()
            .unwrap(),
    )
    .unwrap();
    // The waves that ran (three guides each, the default): their candidates alone.
    let made = first["candidates"].as_array().unwrap().len();
    assert!([3, 6, 9, 12].contains(&made), "{made} candidates");
    // The waves that ran, and the summary's table of how the plans ended.
    let waves = first["waves"].as_u64().unwrap();
    assert!((1..=4).contains(&waves), "{waves} waves");
    if first["stage"] == "diffusion" {
        assert_eq!(made as u64, 3 * waves);
    }
    let summary = std::fs::read_to_string(edmp.join("summary.md")).unwrap();
    assert!(
        summary.contains("Where the time goes") && summary.contains("| wave "),
        "{summary}"
    );
    assert_eq!(first["guides"].as_array().unwrap().len(), 12);
    let run = edmp_host(&[
        "bench-report",
        edmp.to_str().unwrap(),
        single.to_str().unwrap(),
        rrt.to_str().unwrap(),
        "-o",
        report.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    assert!(
        md.contains("Table III") && md.contains("Figure 6") && md.contains("Figure 7"),
        "{md}"
    );
    for file in ["success.png", "time.png", "guides.png", "winners.png"] {
        assert!(report.join(file).exists(), "no {file}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `--threads`: the same plan, bit for bit, on 1, 2 and 3 threads, for a plan the first stage
/// solves and one that needs the global stage (bookshelf/039: its search path wins); 0 threads
/// is bad input.
#[test]
fn plans_are_the_same_on_any_number_of_threads() {
    for scene in ["examples/wall.json", "benchmarks/unseen/bookshelf/039.json"] {
        let plan = |threads: &str| {
            let out = edmp_host(&["plan", scene, "--candidates", "--threads", threads]);
            assert!(
                out.status.code().is_some_and(|c| c <= 1),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let mut doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            doc.as_object_mut().unwrap().remove("timing_ms");
            doc
        };
        let one = plan("1");
        assert_eq!(plan("2"), one, "{scene}: 2 threads");
        assert_eq!(plan("3"), one, "{scene}: 3 threads");
        if scene.contains("bookshelf") {
            assert_ne!(one["stage"], "diffusion", "the global stage ran");
        }
    }
    let out = edmp_host(&["plan", "examples/wall.json", "--threads", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--threads"));
    assert!(out.stdout.is_empty());
}

#[test]
fn filter_robot_drops_the_robots_own_points_and_the_plan_counts_them() {
    use edmp_core::robot::HAND_FRAME;
    use edmp_core::robot::kinematics::forward_with;
    let wall: serde_json::Value = serde_json::from_str(include_str!("../../examples/wall.json")).unwrap();
    let start: Vec<f32> = wall["start"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect();
    let k = forward_with(&edmp_core::robot::PANDA, &<[f32; 7]>::try_from(start).unwrap(), 0.025).unwrap();
    let hand = k.frames[HAND_FRAME].translation;
    // Two points on the hand (a camera saw the robot) and one far away.
    let cloud = serde_json::json!({"type": "points", "radius": 0.005,
        "points": [[hand.x, hand.y, hand.z], [hand.x, hand.y, hand.z + 0.01], [1.5, 0.0, 0.0]]});
    let dir = std::env::temp_dir().join(format!("edmp-filter-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.json");
    let mut doc = wall.clone();
    doc["obstacles"].as_array_mut().unwrap().push(cloud.clone());
    std::fs::write(&scene, doc.to_string()).unwrap();
    let out = edmp_host(&["plan", scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("start: in collision: "));
    let mut filtered = cloud;
    filtered["filter_robot"] = serde_json::json!(0.02);
    doc["obstacles"].as_array_mut().unwrap().pop();
    doc["obstacles"].as_array_mut().unwrap().push(filtered);
    std::fs::write(&scene, doc.to_string()).unwrap();
    let out = edmp_host(&["plan", scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(plan["points_filtered"], 2);
    std::fs::remove_dir_all(&dir).ok();
}
