//! Freezes the Panda kinematic chain from `weights/panda/panda.urdf` into `OUT_DIR/panda.rs`, and
//! the trained prior from `weights/prior/` into `OUT_DIR/prior.rs` + `OUT_DIR/prior.bin` (int8).

use std::path::Path;

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let out_dir = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let out_dir = Path::new(&out_dir);
    let urdf = Path::new(&manifest).join("../weights/panda/panda.urdf");
    let robot = match edmp_codegen::generate_robot(&urdf, "weights/panda/panda.urdf") {
        Ok(generated) => generated,
        Err(e) => panic!("edmp-core build: cannot generate the robot tables: {e}"),
    };
    for input in &robot.inputs {
        println!("cargo::rerun-if-changed={}", input.display());
    }
    std::fs::write(out_dir.join("panda.rs"), robot.source).expect("write OUT_DIR/panda.rs");

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
