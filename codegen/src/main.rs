//! Prints the Rust tables that `edmp-core`'s build script generates, for review.
//!
//! Usage: `edmp-codegen [URDF]` (default: `weights/panda/panda.urdf`).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let urdf = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("weights/panda/panda.urdf"), PathBuf::from);
    match edmp_codegen::generate_robot(&urdf, &urdf.display().to_string()) {
        Ok(generated) => {
            print!("{}", generated.source);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("edmp-codegen: {e}");
            ExitCode::from(2)
        }
    }
}
