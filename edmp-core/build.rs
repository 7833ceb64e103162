//! Freezes the Panda kinematic chain from `weights/panda/panda.urdf` into `OUT_DIR/panda.rs`.

use std::path::Path;

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let out_dir = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let urdf = Path::new(&manifest).join("../weights/panda/panda.urdf");
    let generated = match edmp_codegen::generate_robot(&urdf, "weights/panda/panda.urdf") {
        Ok(generated) => generated,
        Err(e) => panic!("edmp-core build: cannot generate the robot tables: {e}"),
    };
    for input in &generated.inputs {
        println!("cargo::rerun-if-changed={}", input.display());
    }
    println!("cargo::rerun-if-changed=build.rs");
    std::fs::write(Path::new(&out_dir).join("panda.rs"), generated.source).expect("write OUT_DIR/panda.rs");
}
