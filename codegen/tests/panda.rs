//! The generator on the committed Panda URDF: boxes hold their meshes, and the URDF drives
//! the output (a changed origin changes the generated tables).

use edmp_codegen::arms::ArmSpec;
use edmp_codegen::math;
use edmp_codegen::mesh::read_obj_vertices;
use edmp_codegen::urdf::read_chain;
use std::path::{Path, PathBuf};

fn panda() -> &'static ArmSpec {
    edmp_codegen::arms::arm("panda").unwrap()
}

fn panda_urdf() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../weights/panda/panda.urdf")
}

#[test]
fn every_box_holds_every_vertex_and_beats_the_aabb() {
    let chain = read_chain(&panda_urdf(), panda()).expect("the committed URDF reads");
    assert_eq!(chain.joints.len(), 7);
    assert_eq!(chain.bodies.len(), 11, "link0-7, hand and two fingers");
    for body in &chain.bodies {
        assert!(
            body.tight.volume() <= body.aabb.volume() * (1.0 + 1e-12),
            "{}",
            body.name
        );
        assert!(math::det(&body.tight.rotation) > 0.999_999, "{}", body.name);
    }
    // Containment, re-derived from the mesh files. The right finger's mesh is turned by its
    // collision origin (rpy 0 0 π), so only the bodies with an identity collision origin are
    // re-read here; the right finger's box must match the left one's volume instead.
    for body in chain.bodies.iter().filter(|b| b.name != "panda_rightfinger") {
        let mesh = panda_urdf().parent().unwrap().join(&body.mesh);
        let rt = math::transpose(&body.tight.rotation);
        for v in read_obj_vertices(&mesh).unwrap() {
            let d = [
                v[0] - body.tight.center[0],
                v[1] - body.tight.center[1],
                v[2] - body.tight.center[2],
            ];
            let local = math::mul_vec(&rt, &d);
            for (l, h) in local.iter().zip(body.tight.half_extents) {
                assert!(l.abs() <= h + 1e-9, "{}: vertex {v:?} outside", body.name);
            }
        }
    }
}

#[test]
fn mirrored_fingers_get_equal_boxes() {
    let chain = read_chain(&panda_urdf(), panda()).unwrap();
    let volume = |name: &str| chain.bodies.iter().find(|b| b.name == name).unwrap().tight.volume();
    let (left, right) = (volume("panda_leftfinger"), volume("panda_rightfinger"));
    assert!((left - right).abs() < 1e-3 * left, "{left} vs {right}");
}

#[test]
fn changing_the_urdf_changes_the_tables() {
    let original = std::fs::read_to_string(panda_urdf()).unwrap();
    let dir = std::env::temp_dir().join(format!("edmp-codegen-test-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("meshes/collision")).unwrap();
    for entry in std::fs::read_dir(panda_urdf().parent().unwrap().join("meshes/collision")).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), dir.join("meshes/collision").join(entry.file_name())).unwrap();
    }
    let edited = original.replacen(r#"xyz="0 0 0.333""#, r#"xyz="0 0 0.343""#, 1);
    assert_ne!(edited, original, "the test's edit must apply");
    std::fs::write(dir.join("panda.urdf"), &edited).unwrap();
    let before = edmp_codegen::generate_robot(&panda_urdf(), panda())
        .unwrap()
        .generated
        .source;
    let after = edmp_codegen::generate_robot(&dir.join("panda.urdf"), panda())
        .unwrap()
        .generated
        .source;
    std::fs::remove_dir_all(&dir).ok();
    assert_ne!(before, after);
    assert!(after.contains("Vector3::new(0.0, 0.0, 0.343)"));
}

#[test]
fn malformed_urdf_is_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("edmp-codegen-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("bad.urdf"),
        "<robot name=\"x\"><link name=\"a\"/><link name=\"b\"/></robot>",
    )
    .unwrap();
    let err = edmp_codegen::generate_robot(&dir.join("bad.urdf"), panda()).unwrap_err();
    std::fs::remove_dir_all(&dir).ok();
    assert!(err.contains("root link"), "{err}");
}

#[test]
fn the_time_law_limits_are_written_and_checked() {
    let source = edmp_codegen::generate_robot(&panda_urdf(), panda())
        .expect("the committed URDF reads")
        .generated
        .source;
    // Franka's datasheet numbers, as the trajectory module had them.
    assert!(source.contains("max_velocity: [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61],"));
    assert!(source.contains("max_acceleration: [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0],"));
    assert!(source.contains("max_jerk: [7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0],"));
    let mut short = *panda();
    short.dynamics.jerk = &[1.0; 6];
    let err = edmp_codegen::generate_robot(&panda_urdf(), &short).unwrap_err();
    assert!(err.contains("dynamics.jerk has 6 values"), "{err}");
    let mut zero = *panda();
    zero.dynamics.acceleration = &[15.0, 7.5, 10.0, 0.0, 15.0, 20.0, 20.0];
    let err = edmp_codegen::generate_robot(&panda_urdf(), &zero).unwrap_err();
    assert!(err.contains("dynamics.acceleration[3] = 0"), "{err}");
}
