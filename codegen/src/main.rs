//! Prints the Rust tables that `edmp-core`'s build script generates, for review.
//!
//! Usage: `edmp-codegen [ARM]` (default `panda`; see `arms::ARMS`), run from the repository root.

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let name = std::env::args().nth(1).unwrap_or_else(|| "panda".to_owned());
    let Some(arm) = edmp_codegen::arms::arm(&name) else {
        let known: Vec<_> = edmp_codegen::arms::ARMS.iter().map(|a| a.name).collect();
        eprintln!("edmp-codegen: no arm `{name}` (known: {})", known.join(", "));
        return ExitCode::from(2);
    };
    match edmp_codegen::generate_robot(Path::new(arm.urdf), arm) {
        Ok(generated) => {
            print!("{}", generated.generated.source);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("edmp-codegen: {e}");
            ExitCode::from(2)
        }
    }
}
