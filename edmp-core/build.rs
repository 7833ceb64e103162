//! Freezes each arm compiled in (cargo features `panda`, `iiwa7`, `xarm6`) from its URDF into
//! `OUT_DIR/robot_NAME.rs`, their largest sizes into `OUT_DIR/arms.rs`, and each arm's trained
//! prior (the Panda's from `weights/prior/` into `OUT_DIR/prior.rs` + `OUT_DIR/prior.bin`, int8;
//! another arm's from its `ArmSpec::prior` folder into `OUT_DIR/prior_NAME.rs` + `.bin`).

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

    // Each arm's prior: the Panda's as `prior.rs` + `prior.bin`, another arm's as
    // `prior_NAME.rs` (+ `.bin`), which ends in its `NETWORK` (`None` while it has no prior).
    for arm in &edmp_codegen::arms::ARMS {
        let feature = format!("CARGO_FEATURE_{}", arm.name.to_uppercase());
        if std::env::var_os(&feature).is_none() {
            continue;
        }
        let panda = arm.name == "panda";
        let stem = if panda {
            "prior".to_owned()
        } else {
            format!("prior_{}", arm.name)
        };
        let Some(folder) = arm.prior else {
            let none = format!(
                "/// `{}` has no trained prior yet.\npub static NETWORK: Option<&Network<{}>> = None;\n",
                arm.name,
                arm.neutral.len()
            );
            std::fs::write(out_dir.join(format!("{stem}.rs")), none).expect("write OUT_DIR/prior_NAME.rs");
            continue;
        };
        let blob = format!("{stem}.bin");
        let prior = match edmp_codegen::prior::generate_prior(&root.join(folder), folder, &blob) {
            Ok(generated) => generated,
            Err(e) => panic!("edmp-core build: cannot generate the prior of `{}`: {e}", arm.name),
        };
        for input in &prior.inputs {
            println!("cargo::rerun-if-changed={}", input.display());
        }
        let mut source = prior.source;
        if !panda {
            let _ = write!(
                source,
                "\nstatic TRAINED: Network<JOINTS> = Network {{ name: {:?}, net: &NET, blob: WEIGHT_BLOB, fnv1a: WEIGHTS_FNV1A, wave_budget: None }};\n\
                 /// The network trained on this arm's data (`{folder}`).\n\
                 pub static NETWORK: Option<&Network<JOINTS>> = Some(&TRAINED);\n\
                 const _: () = assert!(\n    LEVELS == weights::LEVELS && same(&DIMS, &weights::DIMS) && same(&LENGTHS, &weights::LENGTHS)\n    \
                 && KERNEL == weights::KERNEL && GROUPS == weights::GROUPS && TIME_DIM == weights::TIME_DIM\n    \
                 && TIME_HIDDEN == weights::TIME_HIDDEN && TOP_SKIP == weights::TOP_SKIP && STEPS == weights::STEPS\n    \
                 && BETA[STEPS - 1].to_bits() == weights::BETA[STEPS - 1].to_bits() && JOINTS <= weights::JOINTS,\n    \
                 \"an arm's prior must have the Panda's network shape and schedule\"\n);\n",
                arm.name
            );
        }
        std::fs::write(out_dir.join(format!("{stem}.rs")), source).expect("write OUT_DIR/prior_NAME.rs");
        std::fs::write(out_dir.join(blob), prior.blob).expect("write OUT_DIR/prior_NAME.bin");
    }
    println!("cargo::rerun-if-changed=build.rs");
}
