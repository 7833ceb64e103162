//! Freezes each arm compiled in (cargo features `panda`, `iiwa7`, `xarm6`) from its URDF into
//! `OUT_DIR/robot_NAME.rs`, their largest sizes into `OUT_DIR/arms.rs`, and the trained prior
//! from `weights/prior/` into `OUT_DIR/prior.rs` + `OUT_DIR/prior.bin` (int8).

use core::fmt::Write;
use std::path::Path;

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let out_dir = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let out_dir = Path::new(&out_dir);
    let root = Path::new(&manifest).join("..");
    let (mut max_frames, mut max_bodies) = (0, 0);
    for arm in &edmp_codegen::arms::ARMS {
        let feature = format!("CARGO_FEATURE_{}", arm.name.to_uppercase());
        if std::env::var_os(&feature).is_none() {
            continue;
        }
        let robot = match edmp_codegen::generate_robot(&root.join(arm.urdf), arm) {
            Ok(generated) => generated,
            Err(e) => panic!("edmp-core build: cannot generate the tables of `{}`: {e}", arm.name),
        };
        for input in &robot.generated.inputs {
            println!("cargo::rerun-if-changed={}", input.display());
        }
        max_frames = max_frames.max(robot.frames);
        max_bodies = max_bodies.max(robot.bodies);
        let file = out_dir.join(format!("robot_{}.rs", arm.name));
        std::fs::write(file, robot.generated.source).expect("write OUT_DIR/robot_NAME.rs");
    }
    let mut sizes = String::new();
    let _ = writeln!(sizes, "/// The most link frames of any arm compiled in.");
    let _ = writeln!(sizes, "pub const MAX_FRAMES: usize = {max_frames};");
    let _ = writeln!(sizes, "/// The most collision bodies of any arm compiled in.");
    let _ = writeln!(sizes, "pub const MAX_BODIES: usize = {max_bodies};");
    std::fs::write(out_dir.join("arms.rs"), sizes).expect("write OUT_DIR/arms.rs");

    let prior_dir = Path::new(&manifest).join("../weights/prior");
    let prior = match edmp_codegen::prior::generate_prior(&prior_dir, "weights/prior") {
        Ok(generated) => generated,
        Err(e) => panic!("edmp-core build: cannot generate the prior tables: {e}"),
    };
    for input in &prior.inputs {
        println!("cargo::rerun-if-changed={}", input.display());
    }
    std::fs::write(out_dir.join("prior.rs"), prior.source).expect("write OUT_DIR/prior.rs");
    std::fs::write(out_dir.join("prior.bin"), prior.blob).expect("write OUT_DIR/prior.bin");
    println!("cargo::rerun-if-changed=build.rs");
}
