//! `edmp-host bench`: one planner (EDMP in any of its variants, or RRT-Connect) over a problem
//! folder (the committed suite by default), with a progress bar. Writes, into `--out`:
//! - `results.jsonl`: one line per problem (status, time, path length, roughness, the
//!   project's checker's verdict, the winning guide, every candidate's verdict, the ensemble's
//!   ACSM diversity, the waypoints), which `benchmarks/judge.py` and `bench-report` read;
//! - `summary.md`: a table per family;
//! - `success.png` (success per family) and `time.png` (distribution of planning times).

use crate::Failure;
use crate::json::{Goal, parse_problem};
use crate::metrics::{Roughness, acsm, path_length, roughness};
use crate::plan_cmd::{Tuning, chosen_guides, plan_problem_on};
use crate::plots;
use core::time::Duration;
use edmp_core::checker::{CheckConfig, check_trajectory};
use edmp_core::kinematics::Joints;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};

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
    /// Folder with one sub-folder of `edmp-scene/1` files per family.
    #[arg(long, default_value = "benchmarks/problems")]
    problems: PathBuf,
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
    /// Every candidate's verdict (EDMP).
    pub candidates: Vec<Candidate>,
    /// Mean pairwise cosine similarity of the ensemble's candidates (EDMP; lower: more diverse).
    pub acsm: Option<f64>,
    /// The returned path (50 × 7; empty without a path).
    pub waypoints: Vec<Joints<f32>>,
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

fn run_edmp(args: &Args, text: &str, problem: &str) -> Result<Record, Failure> {
    let parsed = parse_problem(text).map_err(|e| Failure::Input(format!("{problem}: {e}")))?;
    let guides = args.tuning.guides(&args.guides)?;
    let config = args.tuning.config()?;
    let planned = plan_problem_on(&parsed, &guides, &config, args.seed, args.tuning.threads()?)?;
    let plan = &planned.plan;
    let per_guide = plan.paths.len() / guides.len();
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
    let batch: Vec<&[Joints<f32>]> = plan
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
        path_length: Some(path_length(best)),
        roughness: Some(roughness(best)),
        guide: Some(guides[plan.best / per_guide].id),
        stage: Some(plan.stage.name().to_owned()),
        global_ms: Some(planned.global_ms),
        candidates,
        acsm: acsm(&batch),
        waypoints: best.to_vec(),
    })
}

fn run_rrt(args: &Args, text: &str, problem: &str) -> Result<Record, Failure> {
    let parsed = parse_problem(text).map_err(|e| Failure::Input(format!("{problem}: {e}")))?;
    let goal = match parsed.goal {
        Goal::Joints(q) => q,
        Goal::Pose { .. } => crate::json::joint_goal(&parsed).map_err(Failure::Input)?,
    };
    let config = crate::rrt::RrtConfig {
        budget: Duration::from_millis(args.budget_ms),
        ..crate::rrt::RrtConfig::default()
    };
    let began = std::time::Instant::now();
    let planned = crate::rrt::plan::<50, { edmp_core::scene::MAX_OBSTACLES }>(
        &parsed.scene,
        &parsed.start,
        &goal,
        &config,
        args.seed,
    );
    let time_ms = began.elapsed().as_secs_f64() * 1e3;
    let (status, waypoints) = match planned {
        Ok(p) => {
            let report = check_trajectory(&parsed.scene, &p.waypoints, &CheckConfig::DEFAULT, true)
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
        path_length: (!waypoints.is_empty()).then(|| path_length(&waypoints)),
        roughness: (!waypoints.is_empty()).then(|| roughness(&waypoints)),
        guide: None,
        stage: None,
        global_ms: None,
        candidates: Vec::new(),
        acsm: None,
        waypoints,
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

/// Runs the benchmark and writes its files.
pub fn run(args: &Args) -> Result<(), Failure> {
    let input = Failure::Input;
    let guides: Vec<u8> = match args.planner {
        Planner::Edmp => chosen_guides(&args.guides)?.iter().map(|g| g.id).collect(),
        Planner::RrtConnect => Vec::new(),
    };
    args.tuning.config()?;
    let label = label(args, &guides);
    let folders = crate::suite::read_folder(&args.problems, args.per_family).map_err(input)?;
    let jobs: Vec<(String, PathBuf)> = folders
        .iter()
        .flat_map(|(family, files)| files.iter().map(move |f| (family.clone(), f.clone())))
        .collect();
    std::fs::create_dir_all(&args.out).map_err(|e| input(format!("{}: {e}", args.out.display())))?;
    let bar = ProgressBar::new(jobs.len() as u64).with_message(label.clone());
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed}").map_err(|e| input(e.to_string()))?,
    );
    let one = |(family, path): &(String, PathBuf)| -> Result<Record, Failure> {
        let name = format!(
            "{family}/{}",
            path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default()
        );
        let text = std::fs::read_to_string(path).map_err(|e| input(format!("{}: {e}", path.display())))?;
        let mut record = match args.planner {
            Planner::Edmp => run_edmp(args, &text, &name)?,
            Planner::RrtConnect => run_rrt(args, &text, &name)?,
        };
        record.family = family.clone();
        record.planner = label.clone();
        bar.inc(1);
        Ok(record)
    };
    let records: Vec<Record> = if args.serial {
        jobs.iter().map(one).collect::<Result<_, _>>()?
    } else {
        jobs.par_iter().map(one).collect::<Result<_, _>>()?
    };
    bar.finish_and_clear();
    write_outputs(&args.out, &label, &records).map_err(input)?;
    print!("{}", summary(&label, &records));
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
    out
}

/// Which stage solved each family's problems (EDMP runs; empty for RRT-Connect).
fn stage_table(records: &[Record]) -> String {
    const STAGES: [&str; 4] = ["diffusion", "reseeded", "search", "none"];
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
