//! The grasp table (`benchmarks/grasp/`, written by `benchmarks/grasp/generate.py`) and
//! `examples/grasp-can.json`: a can on a table, the goal a horizontal grasp pose around it with
//! the fingers open to 0.04 m (`"gripper": {"finger": 0.04}`). Every problem must plan; with the
//! default opening (0.025 m) the same goal cuts the fingers into the can and is refused.

use std::path::{Path, PathBuf};
use std::process::Command;

fn problems() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files: Vec<_> = std::fs::read_dir(root.join("benchmarks/grasp"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 10, "the grasp table has ten problems");
    files.push(root.join("examples/grasp-can.json"));
    files
}

fn plan(file: &Path) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_edmp-host"))
        .arg("plan")
        .arg(file)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).trim().to_owned(),
    )
}

#[test]
fn grasps_with_open_fingers_plan_and_closed_ones_are_refused() {
    let scratch = std::env::temp_dir().join(format!("edmp-grasp-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).unwrap();
    let mut failed = Vec::new();
    for file in problems() {
        let text = std::fs::read_to_string(&file).unwrap();
        let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(doc["gripper"]["finger"].as_f64(), Some(0.04), "{}", file.display());
        let (code, stdout, stderr) = plan(&file);
        let status = serde_json::from_str::<serde_json::Value>(&stdout)
            .ok()
            .and_then(|p| p["status"].as_str().map(str::to_owned));
        if code != Some(0) || status.as_deref() != Some("success") {
            failed.push(format!(
                "{}: exit {code:?}, status {status:?}: {stderr}",
                file.display()
            ));
        }
        // The same problem at the default opening: the goal's fingers cut into the can.
        doc.as_object_mut().unwrap().remove("gripper");
        let closed = scratch.join(file.file_name().unwrap());
        std::fs::write(&closed, doc.to_string()).unwrap();
        let (code, _, stderr) = plan(&closed);
        assert_eq!(code, Some(2), "{}: at 0.025 m: {stderr}", file.display());
        assert!(
            stderr.contains("goal.pose: unreachable"),
            "{}: {stderr}",
            file.display()
        );
    }
    let _ = std::fs::remove_dir_all(&scratch);
    assert!(failed.is_empty(), "grasp problems not planned:\n{}", failed.join("\n"));
}

#[test]
fn the_opening_travels_in_the_firmwares_postcard_bytes() {
    use edmp_core::scene::MAX_OBSTACLES;
    use edmp_core::wire::Problem;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("examples/grasp-can.json")).unwrap();
    let problem = edmp_host::commands::embed::wire_problem(&text, 5).unwrap();
    assert_eq!(problem.finger, 0.04);
    let bytes = postcard::to_stdvec(&problem).unwrap();
    let back: Problem<MAX_OBSTACLES> = postcard::from_bytes(&bytes).unwrap();
    assert_eq!(back, problem);
    let scene = back.to_scene().unwrap();
    assert_eq!(scene.gripper(), 0.04);
    assert_eq!(
        scene.obstacles(),
        edmp_host::formats::json::parse_problem(&text)
            .unwrap()
            .scene()
            .obstacles()
    );
    // A scene without the field travels at the default opening.
    let wall = std::fs::read_to_string(root.join("examples/wall.json")).unwrap();
    assert_eq!(
        edmp_host::commands::embed::wire_problem(&wall, 0).unwrap().finger,
        0.025
    );
}
