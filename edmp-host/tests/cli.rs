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
fn render_writes_a_png() {
    let path = std::env::temp_dir().join(format!("edmp-render-{}.png", std::process::id()));
    let out = edmp_host(&["render", "examples/wall.json", "-o", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width 1200, height 600.
    assert_eq!(u32::from_be_bytes([bytes[16], bytes[17], bytes[18], bytes[19]]), 1200);
    assert_eq!(u32::from_be_bytes([bytes[20], bytes[21], bytes[22], bytes[23]]), 600);
}
