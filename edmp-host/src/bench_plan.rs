//! `edmp-host bench-plan`: EDMP over a problem folder (the committed suite by default), one row
//! per family: share of problems whose plan passed the project's exact checker, median and p95
//! planning time (IK + guided denoising + selection, one problem per core), as Markdown.

use crate::Failure;
use crate::json::parse_problem;
use crate::plan_cmd::{Tuning, chosen_guides, plan_problem};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;

/// Arguments of `edmp-host bench-plan`.
#[derive(Debug, clap::Args)]
pub(crate) struct Args {
    /// Folder with one sub-folder of `edmp-scene/1` files per family.
    #[arg(long, default_value = "benchmarks/problems")]
    problems: PathBuf,
    /// Problems per family (the first N of each).
    #[arg(long, default_value_t = 100)]
    per_family: usize,
    /// Random seed of every plan.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Plan on one thread (timings without a second planner on the other core).
    #[arg(long)]
    serial: bool,
    /// Use only these guides (the original's numbers); their count must divide 12.
    #[arg(long, value_delimiter = ',')]
    guides: Vec<u8>,
    #[command(flatten)]
    tuning: Tuning,
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Runs the benchmark and prints the table.
pub(crate) fn run(args: &Args) -> Result<(), Failure> {
    let guides = chosen_guides(&args.guides)?;
    let config = args.tuning.config()?;
    let input = |e: String| Failure::Input(e);
    let families = crate::suite::read_folder(&args.problems, args.per_family).map_err(input)?;
    let ids: Vec<String> = guides.iter().map(|g| g.id.to_string()).collect();
    println!(
        "EDMP, guides {} ({} rows), {}, seed {}\n",
        ids.join(","),
        crate::plan_cmd::ROWS,
        args.tuning.label(),
        args.seed
    );
    println!("| family | solved | median time (ms) | p95 time (ms) |");
    println!("|---|---|---|---|");
    let (mut all_ok, mut all_n, mut all_times) = (0, 0, Vec::new());
    for (name, files) in families {
        let bar = ProgressBar::new(files.len() as u64).with_message(name.clone());
        bar.set_style(
            ProgressStyle::with_template("{msg:>13} [{bar:40}] {pos}/{len}").map_err(|e| input(e.to_string()))?,
        );
        let one = |f: &PathBuf| -> Result<(bool, f64), Failure> {
            let text = std::fs::read_to_string(f).map_err(|e| input(format!("{}: {e}", f.display())))?;
            let problem = parse_problem(&text).map_err(|e| input(format!("{}: {e}", f.display())))?;
            let planned = plan_problem(&problem, &guides, &config, args.seed)?;
            bar.inc(1);
            Ok((
                planned.plan.is_free(),
                planned.ik_ms + planned.denoise_ms + planned.select_ms,
            ))
        };
        let outcomes: Vec<(bool, f64)> = if args.serial {
            files.iter().map(one).collect::<Result<_, _>>()?
        } else {
            files.par_iter().map(one).collect::<Result<_, _>>()?
        };
        bar.finish_and_clear();
        let ok = outcomes.iter().filter(|o| o.0).count();
        let mut times: Vec<f64> = outcomes.iter().map(|o| o.1).collect();
        times.sort_by(f64::total_cmp);
        println!(
            "| {name} | {ok}/{} ({:.0} %) | {:.1} | {:.1} |",
            outcomes.len(),
            100.0 * ok as f64 / outcomes.len().max(1) as f64,
            percentile(&times, 0.5),
            percentile(&times, 0.95)
        );
        all_ok += ok;
        all_n += outcomes.len();
        all_times.extend(times);
    }
    all_times.sort_by(f64::total_cmp);
    println!(
        "| all | {all_ok}/{all_n} ({:.0} %) | {:.1} | {:.1} |",
        100.0 * all_ok as f64 / all_n.max(1) as f64,
        percentile(&all_times, 0.5),
        percentile(&all_times, 0.95)
    );
    Ok(())
}
