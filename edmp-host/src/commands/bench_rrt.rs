//! `edmp-host bench-rrt`: RRT-Connect on a problem folder (the committed suite by default),
//! one row per family: success within the budget, median and p95 planning time, mean path
//! length (joint space, radians), as a Markdown table on standard output.

use crate::formats::json::{Goal, read_problem};
use crate::rrt::{RrtConfig, path_length, plan};
use core::time::Duration;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Arguments of `edmp-host bench-rrt`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder with one sub-folder of `edmp-scene/1` files per family.
    #[arg(long, default_value = "benchmarks/problems")]
    problems: PathBuf,
    /// Planning budget per problem, milliseconds.
    #[arg(long, default_value_t = 1000)]
    budget_ms: u64,
    /// Random seed of every run.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Plan on one thread (timings without a second planner on the other core).
    #[arg(long)]
    serial: bool,
}

struct Outcome {
    ms: f64,
    length: Option<f32>,
}

fn run_one(path: &Path, budget: Duration, seed: u64) -> Result<Outcome, String> {
    let p = read_problem(path)?;
    let Goal::Joints(goal) = p.goal else {
        return Err(format!("{}: suite problems have joint goals", path.display()));
    };
    let config = RrtConfig {
        budget,
        ..RrtConfig::default()
    };
    let began = std::time::Instant::now();
    let planned = plan::<50, { edmp_core::robot::JOINTS }, { edmp_core::scene::MAX_OBSTACLES }>(
        &edmp_core::robot::PANDA,
        &p.scene(),
        &p.start,
        &goal,
        &config,
        seed,
    );
    Ok(Outcome {
        ms: began.elapsed().as_secs_f64() * 1e3,
        length: planned.ok().map(|r| path_length(&r.waypoints)),
    })
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Runs the benchmark and prints the table.
pub fn run(args: &Args) -> Result<(), String> {
    let families = crate::commands::gen_suite::read_folder(&args.problems, usize::MAX)?;
    let budget = Duration::from_millis(args.budget_ms);
    crate::commands::print_stdout(&format!(
        "| family | solved (≤ {} ms) | median time (ms) | p95 time (ms) | mean path length (rad) |\n|---|---|---|---|---|\n",
        args.budget_ms
    ))?;
    for (name, files) in families {
        let bar = ProgressBar::new(files.len() as u64).with_message(name.clone());
        bar.set_style(ProgressStyle::with_template("{msg:>13} [{bar:40}] {pos}/{len}").map_err(|e| e.to_string())?);
        let one = |f: &PathBuf| {
            let r = run_one(f, budget, args.seed);
            bar.inc(1);
            r
        };
        let outcomes: Vec<Outcome> = if args.serial {
            files.iter().map(one).collect::<Result<_, _>>()?
        } else {
            files.par_iter().map(one).collect::<Result<_, _>>()?
        };
        bar.finish_and_clear();
        let solved: Vec<&Outcome> = outcomes.iter().filter(|o| o.length.is_some()).collect();
        let mut times: Vec<f64> = solved.iter().map(|o| o.ms).collect();
        times.sort_by(f64::total_cmp);
        let mean_length =
            solved.iter().filter_map(|o| o.length).map(f64::from).sum::<f64>() / solved.len().max(1) as f64;
        crate::commands::print_stdout(&format!(
            "| {name} | {}/{} ({:.0} %) | {:.1} | {:.1} | {:.2} |\n",
            solved.len(),
            outcomes.len(),
            100.0 * solved.len() as f64 / outcomes.len().max(1) as f64,
            percentile(&times, 0.5),
            percentile(&times, 0.95),
            mean_length
        ))?;
    }
    Ok(())
}
