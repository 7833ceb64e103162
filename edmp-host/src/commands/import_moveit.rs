//! `edmp-host import-moveit`: a MoveIt planning scene (and optionally a motion plan request)
//! as `edmp-scene/1` JSON, through the reader in [`crate::formats::moveit`], validated by the
//! scene reader before anything is written.

use crate::Failure;
use crate::formats::moveit::{Source, import, validate};
use std::path::PathBuf;

/// Arguments of `edmp-host import-moveit`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The MoveIt planning scene (`moveit_msgs/PlanningScene` as YAML).
    #[arg(long)]
    scene: PathBuf,
    /// The motion plan request (`moveit_msgs/MotionPlanRequest` as YAML): start and goal.
    #[arg(long)]
    request: Option<PathBuf>,
    /// Write the `edmp-scene/1` JSON here instead of standard output.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// Imports, validates and writes the scene.
pub fn run(args: &Args) -> Result<(), Failure> {
    let read = |p: &PathBuf| std::fs::read_to_string(p).map_err(|e| Failure::Input(format!("{}: {e}", p.display())));
    let scene = read(&args.scene)?;
    let request = args.request.as_ref().map(read).transpose()?;
    let doc = import(&scene, request.as_deref()).map_err(|e| {
        let file = match (e.source, &args.request) {
            (Source::Request, Some(r)) => r,
            _ => &args.scene,
        };
        if e.path.is_empty() {
            Failure::Input(format!("{}: {}", file.display(), e.message))
        } else {
            Failure::Input(format!("{}: {}: {}", file.display(), e.path, e.message))
        }
    })?;
    validate(&doc).map_err(Failure::Input)?;
    let text = serde_json::to_string_pretty(&doc).map_err(|e| Failure::Input(e.to_string()))? + "\n";
    crate::commands::write_document(args.output.as_deref(), &text).map_err(Failure::Input)
}
