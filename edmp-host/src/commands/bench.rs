//! `edmp-host bench`: one planner (EDMP in any of its variants, or RRT-Connect) over a problem
//! folder (the committed suite by default), with a progress bar. Writes, into `--out`:
//! - `results.jsonl`: one line per problem (status, time, path length, roughness, the
//!   project's checker's verdict, the winning guide, every candidate's verdict, the ensemble's
//!   ACSM diversity, the waypoints), which `benchmarks/judge.py` and `bench-report` read;
//! - `summary.md`: a table per family;
//! - `success.png` (success per family) and `time.png` (distribution of planning times).
//!
//! `--robot NAME` runs another arm's suite (`benchmarks/NAME/problems` by default); every scene
//! must name that arm.

use crate::Failure;
use crate::arm::Arm;
use crate::commands::gen_suite::Suite;
use crate::commands::plan::Tuning;
use crate::formats::json::{Goal, parse_problem_for};
use crate::metrics::{Roughness, acsm, path_length, roughness};
use crate::planning::{chosen_guides, plan_problem_on};
use crate::plots;
use crate::with_arm;
use core::sync::atomic::{AtomicUsize, Ordering};
use core::time::Duration;
use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::planner::Stage;
use edmp_core::prior::Network;
use edmp_core::robot::Robot;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Which planner runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Planner {
    /// EDMP (the core planner; `--guides` and the tuning flags select the variant).
    Edmp,
    /// The RRT-Connect baseline with shortcutting and smoothing.
    RrtConnect,
}

/// Arguments of `edmp-host bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder with one sub-folder of `edmp-scene/1` files per family (default: the arm's
    /// in-distribution suite, `benchmarks/problems` for the Panda).
    #[arg(long)]
    problems: Option<PathBuf>,
    /// The arm whose problems these are (docs/formats.md, "Other arms").
    #[arg(long, value_enum, default_value_t = Arm::Panda)]
    robot: Arm,
    /// Problems per family (the first N of each).
    #[arg(long, default_value_t = 100)]
    per_family: usize,
    /// The planner.
    #[arg(long, value_enum, default_value_t = Planner::Edmp)]
    planner: Planner,
    /// EDMP: use only these guides (the original's numbers); their count must divide 12.
    #[arg(long, value_delimiter = ',')]
    guides: Vec<u8>,
    #[command(flatten)]
    tuning: Tuning,
    /// RRT-Connect: planning budget per problem, milliseconds.
    #[arg(long, default_value_t = 1000)]
    budget_ms: u64,
    /// Random seed of every plan.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Plan on one thread (timings without a second planner on the other core).
    #[arg(long)]
    serial: bool,
    /// Output folder (created).
    #[arg(short, long)]
    out: PathBuf,
    /// Name of this run in tables (default: the planner and its settings).
    #[arg(long)]
    label: Option<String>,
}

/// One candidate of the ensemble.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Candidate {
    /// The guide it followed (the original's number).
    pub guide: u8,
    /// Passed the project's exact checker; `None`: not judged (the planner judges only as
    /// many candidates as the winner needs unless `--judge-every`).
    pub free: Option<bool>,
    /// Swept volume against the uninflated obstacles.
    pub swept: f32,
}

/// One problem's result: a line of `results.jsonl`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Record {
    /// Problem path relative to the problem folder, e.g. `cubby/003.json`.
    pub problem: String,
    /// Scene family (the sub-folder).
    pub family: String,
    /// The run's label.
    pub planner: String,
    /// Guides of the EDMP run (empty for RRT-Connect).
    pub guides: Vec<u8>,
    /// The EDMP settings besides the guides (sampler, steps, limits, boxes; empty for
    /// RRT-Connect): runs compare in ablations only when these agree.
    #[serde(default)]
    pub config: String,
    /// Random seed.
    pub seed: u64,
    /// Planned one problem at a time (`--serial`): only then do times compare across runs.
    #[serde(default)]
    pub serial: bool,
    /// `success` (passed the project's checker), `collision` (EDMP's least colliding
    /// candidate) or `failure` (RRT-Connect found nothing within its budget).
    pub status: String,
    /// Planning time, milliseconds (IK + denoising + selection, or the whole RRT search).
    pub time_ms: f64,
    /// Reading the problem, milliseconds: the scene's JSON and the cloud and mesh files it
    /// names, parsed, filtered, reduced and built into the planner's hierarchy.
    #[serde(default)]
    pub read_ms: f64,
    /// Joint-space length of the returned path (radians; absent without a path).
    pub path_length: Option<f64>,
    /// Roughness of the returned path.
    pub(crate) roughness: Option<Roughness>,
    /// The guide whose candidate was returned (EDMP).
    pub guide: Option<u8>,
    /// The stage that produced the returned path (EDMP: `diffusion`, `reseeded`, `search` or
    /// `none`).
    #[serde(default)]
    pub stage: Option<String>,
    /// Milliseconds in the global stage (EDMP; next to nothing when a first-stage candidate
    /// was free or no global stage was asked for).
    #[serde(default)]
    pub global_ms: Option<f64>,
    /// Milliseconds in each phase of the core's pipeline (EDMP; absent in older runs).
    #[serde(default)]
    pub phases: Option<PhaseMs>,
    /// First-stage waves that ran (EDMP): up to the one whose row won for a `diffusion` plan,
    /// all of them for the others (the global stage runs only after the last).
    #[serde(default)]
    pub waves: Option<u8>,
    /// Every candidate's verdict (EDMP).
    pub candidates: Vec<Candidate>,
    /// Mean pairwise cosine similarity of the ensemble's candidates (EDMP; lower: more diverse).
    pub acsm: Option<f64>,
    /// The returned path (50 × the arm's joints; empty without a path).
    pub waypoints: Vec<Vec<f32>>,
}

/// Where one EDMP plan's time went, milliseconds per phase of the pipeline, in its order.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct PhaseMs {
    /// IK for a pose goal.
    pub ik: f64,
    /// The first stage: the waves of guided denoising with their refinement and checks.
    pub first_stage: f64,
    /// The judge's verdicts and the winner.
    pub judge: f64,
    /// The global stage (next to nothing when a first-stage row was free).
    pub global: f64,
    /// Shortening the free winner.
    pub shortcut: f64,
}

impl PhaseMs {
    /// The phases' names and times, in the pipeline's order.
    fn named(&self) -> [(&'static str, f64); 5] {
        [
            ("IK", self.ik),
            ("first stage", self.first_stage),
            ("judge", self.judge),
            ("global stage", self.global),
            ("shortcut", self.shortcut),
        ]
    }
}

impl Record {
    /// Whether the planner called the problem solved.
    pub fn solved(&self) -> bool {
        self.status == "success"
    }
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn label(args: &Args, guides: &[u8]) -> String {
    if let Some(l) = &args.label {
        return l.clone();
    }
    match args.planner {
        Planner::RrtConnect => format!("RRT-Connect, {} ms budget", args.budget_ms),
        Planner::Edmp if guides.len() == 12 => format!("EDMP, 12 guides, {}", args.tuning.label()),
        Planner::Edmp => {
            let ids: Vec<String> = guides.iter().map(u8::to_string).collect();
            format!("EDMP, guides {}, {}", ids.join(","), args.tuning.label())
        }
    }
}

/// One problem's text, where its files lie, and its name in tables.
struct Job<'a> {
    text: &'a str,
    dir: &'a Path,
    problem: &'a str,
}

fn run_edmp(args: &Args, job: &Job<'_>) -> Result<Record, Failure> {
    with_arm!(args.robot, robot, network => run_edmp_for(robot, network, args, job)).map_err(Failure::Input)?
}

fn run_edmp_for<const J: usize>(
    robot: &'static Robot<f32, J>,
    network: &'static Network<J>,
    args: &Args,
    &Job { text, dir, problem }: &Job<'_>,
) -> Result<Record, Failure> {
    let reading = std::time::Instant::now();
    let parsed = parse_problem_for(text, dir, robot).map_err(|e| Failure::Input(format!("{problem}: {e}")))?;
    let read_ms = reading.elapsed().as_secs_f64() * 1e3;
    let guides = args.tuning.guides(&args.guides)?;
    let config = args.tuning.config()?;
    let planned = plan_problem_on(network, &parsed, &guides, &config, args.seed, args.tuning.threads()?)?;
    let plan = &planned.plan;
    let per_guide = plan.paths.len() / guides.len();
    // A wave's rows are made together and a later wave runs only after an earlier one found
    // nothing, so a first-stage winner's wave is the count of rows made over a wave's rows.
    let waves = config
        .waves_for(guides.len())
        .map_err(|e| Failure::Input(format!("{problem}: {e}")))?;
    let made = plan.verdicts.iter().filter(|v| v.made).count();
    let waves_run = match plan.stage {
        Stage::Diffusion => made.div_ceil((plan.paths.len() / waves).max(1)),
        _ => waves,
    };
    let best = &plan.paths[plan.best];
    let candidates = plan
        .verdicts
        .iter()
        .enumerate()
        .filter(|(_, v)| v.made)
        .map(|(row, v)| Candidate {
            guide: guides[row / per_guide].id,
            free: v.checked.then_some(v.free),
            swept: v.swept,
        })
        .collect();
    // The candidates made (the first waves' alone when a later one did not run).
    let batch: Vec<&[[f32; J]]> = plan
        .paths
        .iter()
        .zip(&plan.verdicts)
        .filter(|(_, v)| v.made)
        .map(|(p, _)| &p[..])
        .collect();
    Ok(Record {
        problem: problem.to_owned(),
        family: String::new(),
        planner: String::new(),
        guides: guides.iter().map(|g| g.id).collect(),
        config: args.tuning.label(),
        seed: args.seed,
        serial: args.serial,
        status: if plan.is_free() { "success" } else { "collision" }.to_owned(),
        time_ms: planned.total_ms(),
        read_ms,
        path_length: Some(path_length(best)),
        roughness: Some(roughness(best)),
        guide: Some(guides[plan.best / per_guide].id),
        stage: Some(plan.stage.name().to_owned()),
        global_ms: Some(planned.global_ms),
        phases: Some(PhaseMs {
            ik: planned.ik_ms,
            first_stage: planned.denoise_ms,
            judge: planned.select_ms,
            global: planned.global_ms,
            shortcut: planned.shortcut_ms,
        }),
        waves: u8::try_from(waves_run).ok(),
        candidates,
        acsm: acsm(&batch),
        waypoints: best.iter().map(|q| q.to_vec()).collect(),
    })
}

fn run_rrt(args: &Args, job: &Job<'_>) -> Result<Record, Failure> {
    with_arm!(args.robot, robot => run_rrt_for(robot, args, job))
}

fn run_rrt_for<const J: usize>(
    robot: &'static Robot<f32, J>,
    args: &Args,
    &Job { text, dir, problem }: &Job<'_>,
) -> Result<Record, Failure> {
    let reading = std::time::Instant::now();
    let parsed = parse_problem_for(text, dir, robot).map_err(|e| Failure::Input(format!("{problem}: {e}")))?;
    let read_ms = reading.elapsed().as_secs_f64() * 1e3;
    let goal = match parsed.goal {
        Goal::Joints(q) => q,
        Goal::Pose { .. } => crate::formats::json::joint_goal(&parsed).map_err(Failure::Input)?,
    };
    let config = crate::rrt::RrtConfig {
        budget: Duration::from_millis(args.budget_ms),
        ..crate::rrt::RrtConfig::default()
    };
    let began = std::time::Instant::now();
    let planned = crate::rrt::plan::<50, J, { edmp_core::scene::MAX_OBSTACLES }>(
        robot,
        &parsed.scene(),
        &parsed.start,
        &goal,
        &config,
        args.seed,
    );
    let time_ms = began.elapsed().as_secs_f64() * 1e3;
    let (status, path) = match planned {
        Ok(p) => {
            let report = check_trajectory(robot, &parsed.scene(), &p.waypoints, &CheckConfig::DEFAULT, true)
                .map_err(|e| Failure::Input(format!("{problem}: checker: {e}")))?;
            let status = if report.is_free() { "success" } else { "collision" };
            (status, p.waypoints.to_vec())
        }
        Err(_) => ("failure", Vec::new()),
    };
    Ok(Record {
        problem: problem.to_owned(),
        family: String::new(),
        planner: String::new(),
        guides: Vec::new(),
        config: String::new(),
        seed: args.seed,
        serial: args.serial,
        status: status.to_owned(),
        time_ms,
        read_ms,
        path_length: (!path.is_empty()).then(|| path_length(&path)),
        roughness: (!path.is_empty()).then(|| roughness(&path)),
        guide: None,
        stage: None,
        global_ms: None,
        phases: None,
        waves: None,
        candidates: Vec::new(),
        acsm: None,
        waypoints: path.iter().map(|q| q.to_vec()).collect(),
    })
}

/// One row of a per-family table: solved, times, path length and roughness of solved plans,
/// mean ACSM.
pub fn table_row(name: &str, records: &[&Record]) -> String {
    let n = records.len();
    let solved: Vec<&&Record> = records.iter().filter(|r| r.solved()).collect();
    let mut times: Vec<f64> = records.iter().map(|r| r.time_ms).collect();
    times.sort_by(f64::total_cmp);
    let mean = |f: &dyn Fn(&Record) -> Option<f64>| {
        let v: Vec<f64> = solved.iter().filter_map(|r| f(r)).collect();
        if v.is_empty() {
            "–".to_owned()
        } else {
            format!("{:.4}", v.iter().sum::<f64>() / v.len() as f64)
        }
    };
    let acsm: Vec<f64> = records.iter().filter_map(|r| r.acsm).collect();
    let acsm = if acsm.is_empty() {
        "–".to_owned()
    } else {
        format!("{:.4}", acsm.iter().sum::<f64>() / acsm.len() as f64)
    };
    format!(
        "| {name} | {}/{n} ({:.1} %) | {:.1} | {:.1} | {} | {} | {} | {} | {} | {acsm} |",
        solved.len(),
        100.0 * solved.len() as f64 / n.max(1) as f64,
        percentile(&times, 0.5),
        percentile(&times, 0.95),
        mean(&|r| r.path_length),
        mean(&|r| r.roughness.map(|x| x.ar)),
        mean(&|r| r.roughness.map(|x| x.mresg)),
        mean(&|r| r.roughness.map(|x| x.rf2w)),
        mean(&|r| r.roughness.map(|x| x.rl2w)),
    )
}

/// The header matching [`table_row`].
pub const TABLE_HEADER: &str = "| | solved | median ms | p95 ms | path length (rad) | AR | MRESG | RF2W | RL2W | ACSM |\n|---|---|---|---|---|---|---|---|---|---|";

/// The families of a record set, in order of first appearance.
pub fn families(records: &[Record]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in records {
        if !out.contains(&r.family) {
            out.push(r.family.clone());
        }
    }
    out
}

/// Stack of each of `bench`'s planning threads: a plan needs what `plan` has on the main thread.
const PLAN_STACK: usize = 16 << 20;

/// `one` over `jobs` on `threads` threads of their own, the results in the jobs' order. Not on
/// rayon's pool: a rayon worker that waits for a plan's own parallel work (the surface's tree,
/// the executor's pool) may start the next job on the same stack, and plans over point clouds
/// nested that way overflowed it.
fn on_threads<T: Sync, R: Send>(jobs: &[T], threads: usize, one: impl Fn(&T) -> R + Sync) -> Result<Vec<R>, String> {
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<(usize, R)>> = Mutex::new(Vec::with_capacity(jobs.len()));
    std::thread::scope(|scope| -> Result<(), String> {
        let work = || loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(job) = jobs.get(i) else { break };
            let result = one(job);
            if let Ok(mut done) = done.lock() {
                done.push((i, result));
            }
        };
        for _ in 0..threads.max(1) {
            std::thread::Builder::new()
                .name("edmp-bench".to_owned())
                .stack_size(PLAN_STACK)
                .spawn_scoped(scope, work)
                .map_err(|e| format!("cannot start a planning thread: {e}"))?;
        }
        Ok(())
    })?;
    let mut done = done.into_inner().map_err(|_| "a planning thread panicked".to_owned())?;
    if done.len() != jobs.len() {
        return Err("a planning thread panicked".to_owned());
    }
    done.sort_by_key(|(i, _)| *i);
    Ok(done.into_iter().map(|(_, r)| r).collect())
}

/// Runs the benchmark and writes its files.
pub fn run(args: &Args) -> Result<(), Failure> {
    let input = Failure::Input;
    let guides: Vec<u8> = match args.planner {
        Planner::Edmp => chosen_guides(&args.guides)?.iter().map(|g| g.id).collect(),
        Planner::RrtConnect => Vec::new(),
    };
    args.tuning.config()?;
    let label = label(args, &guides);
    let problems = args
        .problems
        .clone()
        .unwrap_or_else(|| Suite::InDistribution.default_folder(args.robot));
    let folders = crate::commands::gen_suite::read_folder(&problems, args.per_family).map_err(input)?;
    let jobs: Vec<(String, PathBuf)> = folders
        .iter()
        .flat_map(|(family, files)| files.iter().map(move |f| (family.clone(), f.clone())))
        .collect();
    std::fs::create_dir_all(&args.out).map_err(|e| input(format!("{}: {e}", args.out.display())))?;
    let bar = ProgressBar::new(jobs.len() as u64).with_message(label.clone());
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed}").map_err(|e| input(e.to_string()))?,
    );
    let one = |(family, path): &(String, PathBuf)| -> Result<Result<Record, String>, Failure> {
        let name = format!(
            "{family}/{}",
            path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default()
        );
        let text = std::fs::read_to_string(path).map_err(|e| input(format!("{}: {e}", path.display())))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let job = Job {
            text: &text,
            dir,
            problem: &name,
        };
        let planned = match args.planner {
            Planner::Edmp => run_edmp(args, &job),
            Planner::RrtConnect => run_rrt(args, &job),
        };
        bar.inc(1);
        match planned {
            Ok(mut record) => {
                record.family = family.clone();
                record.planner = label.clone();
                Ok(Ok(record))
            }
            // A problem the scene reader refuses (e.g. an end inside a cloud's balls) is
            // invalid input, not a planner failure: listed, not planned, the run goes on.
            Err(Failure::Input(message)) => Ok(Err(message)),
            Err(other) => Err(other),
        }
    };
    let outcomes: Vec<Result<Record, String>> = if args.serial {
        jobs.iter().map(one).collect::<Result<_, _>>()?
    } else {
        let threads = std::thread::available_parallelism().map_or(2, usize::from);
        on_threads(&jobs, threads, one)
            .map_err(input)?
            .into_iter()
            .collect::<Result<_, _>>()?
    };
    bar.finish_and_clear();
    let (records, refused): (Vec<_>, Vec<_>) = outcomes.into_iter().partition(Result::is_ok);
    let records: Vec<Record> = records.into_iter().filter_map(Result::ok).collect();
    let refused: Vec<String> = refused.into_iter().filter_map(Result::err).collect();
    write_outputs(&args.out, &label, &records).map_err(input)?;
    crate::commands::print_stdout(&summary(&label, &records)).map_err(input)?;
    if !refused.is_empty() {
        let path = args.out.join("refused.txt");
        std::fs::write(&path, refused.join("\n") + "\n").map_err(|e| input(format!("{}: {e}", path.display())))?;
        crate::commands::print_stdout(&format!(
            "\n{} problems refused as invalid input, not planned: {}\n",
            refused.len(),
            path.display()
        ))
        .map_err(input)?;
    }
    Ok(())
}

/// The Markdown summary of one run.
fn summary(label: &str, records: &[Record]) -> String {
    let mut out = format!("{label}\n\n{}\n", TABLE_HEADER.replacen("| |", "| family |", 1));
    for family in families(records) {
        let rows: Vec<&Record> = records.iter().filter(|r| r.family == family).collect();
        out += &table_row(&family, &rows);
        out.push('\n');
    }
    out += &table_row("all", &records.iter().collect::<Vec<_>>());
    out.push('\n');
    out += &stage_table(records);
    out += &tail_table(records);
    out += &phase_table(records);
    out
}

/// Where the time goes by phase of the pipeline (EDMP runs that recorded phases; empty
/// otherwise): each phase's median and mean per plan and its share of all planning time.
fn phase_table(records: &[Record]) -> String {
    let phases: Vec<PhaseMs> = records.iter().filter_map(|r| r.phases).collect();
    if phases.is_empty() {
        return String::new();
    }
    let total: f64 = phases.iter().flat_map(|p| p.named()).map(|(_, ms)| ms).sum();
    let mut out = format!(
        "\nBy phase, over {} plans:\n\n| phase | median ms | mean ms | share of all time |\n|---|---|---|---|\n",
        phases.len()
    );
    for (i, (name, _)) in PhaseMs::default().named().iter().enumerate() {
        let mut times: Vec<f64> = phases.iter().map(|p| p.named()[i].1).collect();
        times.sort_by(f64::total_cmp);
        let sum: f64 = times.iter().sum();
        out += &format!(
            "| {name} | {:.2} | {:.2} | {:.1} % |\n",
            percentile(&times, 0.5),
            sum / times.len() as f64,
            100.0 * sum / total.max(f64::MIN_POSITIVE),
        );
    }
    out
}

/// How an EDMP plan ended: `wave N` when the first stage's wave N freed the winner, else the
/// stage (`reseeded`, `search`, `none`).
fn outcome(r: &Record) -> Option<String> {
    match (r.stage.as_deref(), r.waves) {
        (Some("diffusion"), Some(w)) => Some(format!("wave {w}")),
        (Some(stage), _) => Some(stage.to_owned()),
        (None, _) => None,
    }
}

/// Where the slow plans come from (EDMP runs; empty for RRT-Connect): per way a plan ended,
/// its plans, their median and largest time, and how many took over 1.5 × the run's median
/// (the p95 / median ≤ 1.5 goal of docs/benchmark.md asks that at most 5 % do).
fn tail_table(records: &[Record]) -> String {
    let ended: Vec<(String, f64)> = records.iter().filter_map(|r| Some((outcome(r)?, r.time_ms))).collect();
    if ended.is_empty() {
        return String::new();
    }
    let mut all: Vec<f64> = ended.iter().map(|(_, t)| *t).collect();
    all.sort_by(f64::total_cmp);
    let (median, p95) = (percentile(&all, 0.5), percentile(&all, 0.95));
    let limit = 1.5 * median;
    let mut out = format!(
        "\nWhere the time goes: median {median:.1} ms, p95 {p95:.1} ms, p95 / median {:.2}; {} of {} plans took over \
         1.5 × the median ({limit:.1} ms).\n\n| ended by | plans | median ms | max ms | over 1.5 × median |\n|---|---|---|---|---|\n",
        p95 / median,
        all.iter().filter(|t| **t > limit).count(),
        all.len(),
    );
    let mut names: Vec<&String> = ended.iter().map(|(o, _)| o).collect();
    // Waves in order, then the global stage's outcomes in the order the planner reaches them.
    let rank = |o: &str| match o.strip_prefix("wave ") {
        Some(n) => (0, n.parse::<u32>().unwrap_or(u32::MAX), String::new()),
        None => (
            1,
            STAGES.iter().position(|s| *s == o).unwrap_or(STAGES.len()) as u32,
            o.to_owned(),
        ),
    };
    names.sort_by_key(|o| rank(o));
    names.dedup();
    for name in names {
        let mut times: Vec<f64> = ended.iter().filter(|(o, _)| o == name).map(|(_, t)| *t).collect();
        times.sort_by(f64::total_cmp);
        out += &format!(
            "| {name} | {} | {:.1} | {:.1} | {} |\n",
            times.len(),
            percentile(&times, 0.5),
            times.last().copied().unwrap_or(f64::NAN),
            times.iter().filter(|t| **t > limit).count(),
        );
    }
    out
}

/// The stages an EDMP plan can end in, in the order the planner reaches them.
const STAGES: [&str; 4] = ["diffusion", "reseeded", "search", "none"];

/// Which stage solved each family's problems (EDMP runs; empty for RRT-Connect).
fn stage_table(records: &[Record]) -> String {
    if records.iter().all(|r| r.stage.is_none()) {
        return String::new();
    }
    let mut out = "\n| family | diffusion | reseeded | search | none | median global-stage ms (when it ran) |\n|---|---|---|---|---|---|\n".to_owned();
    let mut names = families(records);
    names.push("all".to_owned());
    for family in names {
        let rows: Vec<&Record> = records
            .iter()
            .filter(|r| family == "all" || r.family == family)
            .collect();
        let count = |stage: &str| rows.iter().filter(|r| r.stage.as_deref() == Some(stage)).count();
        let mut ran: Vec<f64> = rows
            .iter()
            .filter(|r| matches!(r.stage.as_deref(), Some("reseeded" | "search" | "none")))
            .filter_map(|r| r.global_ms)
            .filter(|ms| *ms > 0.0)
            .collect();
        ran.sort_by(f64::total_cmp);
        let median = if ran.is_empty() {
            "–".to_owned()
        } else {
            format!("{:.1}", percentile(&ran, 0.5))
        };
        let counts: Vec<String> = STAGES.iter().map(|s| count(s).to_string()).collect();
        out += &format!("| {family} | {} | {median} |\n", counts.join(" | "));
    }
    out
}

fn write_outputs(dir: &Path, label: &str, records: &[Record]) -> Result<(), String> {
    let path = dir.join("results.jsonl");
    let mut file =
        std::io::BufWriter::new(std::fs::File::create(&path).map_err(|e| format!("{}: {e}", path.display()))?);
    for r in records {
        let line = serde_json::to_string(r).map_err(|e| e.to_string())?;
        writeln!(file, "{line}").map_err(|e| format!("{}: {e}", path.display()))?;
    }
    file.flush().map_err(|e| format!("{}: {e}", path.display()))?;
    let md = dir.join("summary.md");
    std::fs::write(&md, summary(label, records)).map_err(|e| format!("{}: {e}", md.display()))?;

    let families = families(records);
    let share = |family: &str| {
        let rows: Vec<&Record> = records.iter().filter(|r| r.family == family).collect();
        100.0 * rows.iter().filter(|r| r.solved()).count() as f64 / rows.len().max(1) as f64
    };
    plots::grouped_bars(
        &dir.join("success.png"),
        &format!("Solved per family: {label}"),
        "solved (%)",
        &families,
        &[(String::new(), families.iter().map(|f| share(f)).collect())],
        100.0,
    )?;
    let curves: Vec<(String, Vec<(f64, f64)>)> = families.iter().map(|f| (f.clone(), cdf(records, f))).collect();
    plots::time_distribution(&dir.join("time.png"), &format!("Planning time: {label}"), &curves)
}

/// The empirical distribution of one family's planning times, as (ms, %) steps.
pub fn cdf(records: &[Record], family: &str) -> Vec<(f64, f64)> {
    let mut t: Vec<f64> = records
        .iter()
        .filter(|r| family.is_empty() || r.family == family)
        .map(|r| r.time_ms)
        .collect();
    t.sort_by(f64::total_cmp);
    let n = t.len().max(1) as f64;
    let mut points = vec![(0.0, 0.0)];
    for (i, x) in t.iter().enumerate() {
        points.push((*x, 100.0 * i as f64 / n));
        points.push((*x, 100.0 * (i + 1) as f64 / n));
    }
    points
}

/// Reads a run's `results.jsonl`.
pub fn read_results(dir: &Path) -> Result<Vec<Record>, String> {
    let path = dir.join("results.jsonl");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| serde_json::from_str(l).map_err(|e| format!("{}:{}: {e}", path.display(), i + 1)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planning_threads_keep_the_jobs_order_and_have_a_plans_stack() {
        let jobs: Vec<usize> = (0..200).collect();
        // Each job uses a few MiB of stack, more than a rayon worker's default 2 MiB.
        let deep = |&j: &usize| {
            let buffer = core::hint::black_box([j as u8; 4 << 20]);
            buffer.iter().map(|&b| usize::from(b)).sum::<usize>() / (4 << 20)
        };
        assert_eq!(
            on_threads(&jobs, 3, deep).unwrap(),
            (0..200).map(|j| j % 256).collect::<Vec<_>>()
        );
    }

    fn record(stage: Option<&str>, waves: Option<u8>, time_ms: f64) -> Record {
        Record {
            problem: "f/000.json".to_owned(),
            family: "f".to_owned(),
            planner: String::new(),
            guides: Vec::new(),
            config: String::new(),
            seed: 0,
            serial: true,
            status: "success".to_owned(),
            time_ms,
            read_ms: 0.0,
            path_length: None,
            roughness: None,
            guide: None,
            stage: stage.map(str::to_owned),
            global_ms: None,
            phases: None,
            waves,
            candidates: Vec::new(),
            acsm: None,
            waypoints: Vec::new(),
        }
    }

    #[test]
    fn the_tail_table_counts_each_ending_and_the_plans_over_one_and_a_half_medians() {
        let mut records: Vec<Record> = [10.0, 11.0, 12.0, 20.0]
            .map(|t| record(Some("diffusion"), Some(1), t))
            .to_vec();
        records.push(record(Some("diffusion"), Some(2), 30.0));
        records.push(record(Some("search"), Some(4), 300.0));
        records.push(record(Some("reseeded"), Some(4), 100.0));
        // Median 20 ms (the 4th of 7), limit 30 ms: 20 and 30 are not over it, 100 and 300 are.
        let table = tail_table(&records);
        assert!(table.contains("median 20.0 ms"), "{table}");
        assert!(
            table.contains("2 of 7 plans took over 1.5 × the median (30.0 ms)"),
            "{table}"
        );
        let rows: Vec<&str> = table
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| ended"))
            .collect();
        assert_eq!(
            rows,
            [
                "| wave 1 | 4 | 12.0 | 20.0 | 0 |",
                "| wave 2 | 1 | 30.0 | 30.0 | 0 |",
                "| reseeded | 1 | 100.0 | 100.0 | 1 |",
                "| search | 1 | 300.0 | 300.0 | 1 |",
            ]
        );
        // RRT-Connect's records have no stage: no table.
        assert_eq!(tail_table(&[record(None, None, 5.0)]), "");
    }

    #[test]
    fn the_phase_table_gives_each_phase_its_median_mean_and_share() {
        let phased = |first_stage: f64, shortcut: f64| Record {
            phases: Some(PhaseMs {
                first_stage,
                shortcut,
                ..PhaseMs::default()
            }),
            ..record(Some("diffusion"), Some(1), first_stage + shortcut)
        };
        // 40 ms of first stage and 10 of shortcut in all: 80 % and 20 %.
        let table = phase_table(&[phased(10.0, 2.0), phased(10.0, 4.0), phased(20.0, 4.0)]);
        assert!(table.contains("over 3 plans"), "{table}");
        assert!(table.contains("| first stage | 10.00 | 13.33 | 80.0 % |"), "{table}");
        assert!(table.contains("| shortcut | 4.00 | 3.33 | 20.0 % |"), "{table}");
        assert!(table.contains("| global stage | 0.00 | 0.00 | 0.0 % |"), "{table}");
        // Runs without phases (RRT-Connect, older records): no table.
        assert_eq!(phase_table(&[record(None, None, 5.0)]), "");
    }
}
