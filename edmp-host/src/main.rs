//! `edmp-host`: the command line of edmp-rs. The commands live in the `edmp_host` library;
//! this binary parses the arguments, runs one and maps its outcome to the exit status.

use clap::{Parser, Subcommand};
use edmp_host::Failure;
use edmp_host::commands::{
    bench, bench_report, bench_rrt, embed, fk, gen_data, gen_suite, import_moveit, plan, render, rrt, sample, view,
};
use std::process::ExitCode;

/// EDMP motion planning for the Franka Panda.
#[derive(Debug, Parser)]
#[command(name = "edmp-host", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Plan with EDMP (exit 0: collision-free plan, 1: only a colliding plan, 2: bad input).
    Plan(plan::Args),
    /// Forward kinematics: world pose of every link frame, collision box and the TCP.
    Fk(fk::Args),
    /// Plan with the RRT-Connect baseline (exit 0: planned, 1: no path, 2: bad input).
    Rrt(rrt::Args),
    /// Generate the benchmark suite: MpiNets-style scenes and solvable problems.
    GenSuite(gen_suite::Args),
    /// Run a planner over a problem folder: per-problem JSONL, a summary per family, charts.
    Bench(bench::Args),
    /// Compare `bench` runs: the paper's ablation tables and charts.
    BenchReport(bench_report::Args),
    /// Run RRT-Connect over a problem folder and print a table per family.
    BenchRrt(bench_rrt::Args),
    /// Generate training trajectories (RRT-Connect in generated scenes) as a `.npy` file.
    GenData(gen_data::Args),
    /// Draw a scene (and optionally a plan) as a PNG: top, side and front views.
    Render(render::Args),
    /// Measure the unguided diffusion prior: roughness, joint limits, self-collision, time.
    Sample(sample::Args),
    /// Scenes as postcard bytes for the QEMU firmware, with the host's plan of each.
    Embed(embed::Args),
    /// Convert a MoveIt planning scene (and motion plan request) YAML to `edmp-scene/1` JSON.
    ImportMoveit(import_moveit::Args),
    /// Write an interactive 3-D viewer of a scene (and a plan) as one self-contained HTML page.
    View(view::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Plan(args) => plan::run(&args),
        Command::Fk(args) => fk::run(&args).map_err(Failure::Input),
        Command::Rrt(args) => rrt::run(&args),
        Command::GenSuite(args) => gen_suite::run(&args).map_err(Failure::Input),
        Command::Bench(args) => bench::run(&args),
        Command::BenchReport(args) => bench_report::run(&args).map_err(Failure::Input),
        Command::BenchRrt(args) => bench_rrt::run(&args).map_err(Failure::Input),
        Command::GenData(args) => gen_data::run(&args).map_err(Failure::Input),
        Command::Render(args) => render::run(&args).map_err(Failure::Input),
        Command::Sample(args) => sample::run(&args).map_err(Failure::Input),
        Command::Embed(args) => embed::run(&args),
        Command::ImportMoveit(args) => import_moveit::run(&args),
        Command::View(args) => view::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::NoPath(message)) => {
            eprintln!("edmp-host: {message}");
            ExitCode::from(1)
        }
        Err(Failure::Input(message)) => {
            eprintln!("edmp-host: {message}");
            ExitCode::from(2)
        }
    }
}
