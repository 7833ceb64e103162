//! The near-surface table (`benchmarks/near_surface/`, recorded by `benchmarks/near_surface.py`
//! with PyBullet): starts and goals 0.05-2 mm from a table, a shelf board and a drawer front
//! by PyBullet's own measure are valid ends (docs/formats.md) and must plan.

use std::process::Command;

#[test]
fn every_near_surface_end_is_accepted_and_planned() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../benchmarks/near_surface");
    let mut files: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .flat_map(|d| std::fs::read_dir(d.unwrap().path()).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 36, "three settings × six distances × two ends");
    let mut failed = Vec::new();
    for file in &files {
        let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        let d = doc["meta"]["pybullet_distance"].as_f64().unwrap();
        assert!(d > 0.0 && d <= 0.002 + 1e-6, "{}: {d}", file.display());
        let out = Command::new(env!("CARGO_BIN_EXE_edmp-host"))
            .arg("plan")
            .arg(file)
            .output()
            .unwrap();
        if out.status.code() != Some(0) {
            failed.push(format!(
                "{} ({:.2} mm): exit {:?}: {}",
                file.display(),
                d * 1000.0,
                out.status.code(),
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
    }
    assert!(
        failed.is_empty(),
        "near-surface problems not planned:\n{}",
        failed.join("\n")
    );
}
