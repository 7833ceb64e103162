//! `edmp-host rrt`: the RRT-Connect baseline on one `edmp-scene/1` file, written as an
//! `edmp-plan/1` plan (status "success" only: without a path nothing is written, exit 1).

use crate::Failure;
use crate::formats::json::{joint_goal, parse_problem_for, scene_arm};
use crate::rrt::{RrtConfig, RrtError, path_length, plan};
use crate::with_arm;
use core::time::Duration;
use edmp_core::robot::Robot;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `edmp-host rrt`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene and problem (`edmp-scene/1` JSON).
    scene: PathBuf,
    /// Write the plan here instead of standard output.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Planning time budget in milliseconds.
    #[arg(long, default_value_t = 1000)]
    budget_ms: u64,
}

/// Plans for the arm the scene names (`robot`) and writes the plan.
pub fn run(args: &Args) -> Result<(), Failure> {
    let began = Instant::now();
    let text =
        std::fs::read_to_string(&args.scene).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    let arm = scene_arm(&text).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    with_arm!(arm, robot => plan_for(args, began, &text, robot))
}

fn plan_for<const J: usize>(
    args: &Args,
    began: Instant,
    text: &str,
    robot: &'static Robot<f32, J>,
) -> Result<(), Failure> {
    let dir = args.scene.parent().unwrap_or(std::path::Path::new("."));
    let problem =
        parse_problem_for(text, dir, robot).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    let goal = joint_goal(&problem).map_err(Failure::Input)?;
    let config = RrtConfig {
        budget: Duration::from_millis(args.budget_ms),
        ..RrtConfig::default()
    };
    let planned = plan::<50, J, { edmp_core::scene::MAX_OBSTACLES }>(
        robot,
        &problem.scene(),
        &problem.start,
        &goal,
        &config,
        args.seed,
    )
    .map_err(|e| match e {
        RrtError::Timeout => Failure::NoPath(format!("no path within {} ms", args.budget_ms)),
        RrtError::Resample => Failure::NoPath("the resampled path cut into an obstacle".into()),
        RrtError::InvalidStart => Failure::Input("start: in collision or outside the limits".into()),
        RrtError::InvalidGoal => Failure::Input("goal: in collision or outside the limits".into()),
        RrtError::Checker(e) => Failure::Input(format!("checker: {e}")),
    })?;
    let total_ms = began.elapsed().as_secs_f64() * 1e3;
    let plan = json!({
        "format": "edmp-plan/1",
        "status": "success",
        "planner": "rrt-connect",
        "waypoints": planned.waypoints.iter().map(|q| q.to_vec()).collect::<Vec<_>>(),
        "seed": args.seed,
        "path_length": path_length(&planned.waypoints),
        "tree_nodes": planned.nodes,
        "timing_ms": {"total": total_ms, "search": planned.elapsed.as_secs_f64() * 1e3},
    });
    let text = serde_json::to_string_pretty(&plan).map_err(|e| Failure::Input(e.to_string()))? + "\n";
    crate::commands::write_document(args.output.as_deref(), &text).map_err(Failure::Input)
}
