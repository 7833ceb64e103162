//! `edmp-host sample`: the quality of the unguided prior. For suite start/goal pairs it samples
//! 12 trajectories per problem with each sampler and prints, per sampler, the roughness metrics
//! of the paper's Table IV (L2 norm between adjacent waypoints, radians: AR average, MRESG max
//! excluding the first and last segment, RF2W first segment, RL2W last), the share of
//! trajectories leaving the hard joint limits or colliding with the robot itself (exact
//! checker, empty scene), and the sampling time. `--data` adds the same row for the training
//! trajectories; `--plot` draws some samples, joint by joint, to a PNG. `--robot` measures
//! another arm's prior; `--ends-from-data` takes the start/goal pairs from the held-out
//! training trajectories instead of a suite (an arm without suites yet).

use crate::arm::{Arm, with_arm};
use crate::commands::print_stdout;
use crate::commands::render::Canvas;
use crate::formats::json::{Goal, read_problem};
use crate::metrics::{Roughness, roughness, step_norm};
use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::path::{HORIZON, Path};
use edmp_core::prior::{Network, Sampler, Scratch, sample_with};
use edmp_core::rng::Rng;
use edmp_core::robot::Robot;
use edmp_core::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;

/// Trajectories per problem: one ensemble's worth.
const BATCH: usize = 12;

/// Arguments of `edmp-host sample`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder with one sub-folder of `edmp-scene/1` files per family (start and joint goal used).
    #[arg(long, default_value = "benchmarks/problems")]
    problems: PathBuf,
    /// Problems per family (the first N of each).
    #[arg(long, default_value_t = 25)]
    per_family: usize,
    /// Samplers: `ancestral` (EDMP's 255 steps), `strided:K` (its rule on K steps), `ddim:K`.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "ancestral,strided:50,strided:25,strided:10,strided:5,ddim:25,ddim:10"
    )]
    samplers: Vec<String>,
    /// Training data (`gen-data` .npy, or a folder of its shards) to measure the same metrics on
    /// (its last 1,200 trajectories, which the trainer holds out).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Draw the samples of the problem with the longest start-to-goal distance (first and last
    /// sampler given) to this PNG.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Random seed (problem i uses seed + i).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Also measure each sampler without start/goal conditioning (no inpainting while
    /// denoising, ends written at the end): the paper's Table IV ablation.
    #[arg(long)]
    no_conditioning: bool,
    /// The arm whose prior to measure (docs/formats.md, "Other arms").
    #[arg(long, value_enum, default_value_t = Arm::Panda)]
    robot: Arm,
    /// Start/goal pairs from the ends of the last `--per-family` × 4 held-out trajectories of
    /// `--data` instead of the `--problems` suite.
    #[arg(long, requires = "data")]
    ends_from_data: bool,
}

fn parse_sampler(s: &str) -> Result<Sampler, String> {
    let sampler = match s.split_once(':') {
        None if s == "ancestral" => Sampler::Ancestral,
        Some((kind @ ("ddim" | "strided"), k)) => {
            let steps = k
                .parse()
                .map_err(|_| format!("--samplers: `{s}`: K must be an integer"))?;
            if kind == "ddim" {
                Sampler::Ddim { steps }
            } else {
                Sampler::Strided { steps }
            }
        }
        _ => {
            return Err(format!(
                "--samplers: `{s}` is none of `ancestral`, `strided:K`, `ddim:K`"
            ));
        }
    };
    sampler
        .validate()
        .map_err(|_| format!("--samplers: `{s}`: K must be 1..={}", edmp_core::prior::STEPS))?;
    Ok(sampler)
}

fn name(sampler: Sampler) -> String {
    match sampler {
        Sampler::Ancestral => format!("ancestral, K = {}", edmp_core::prior::STEPS),
        Sampler::Strided { steps } => format!("strided, K = {steps}"),
        Sampler::Ddim { steps } => format!("DDIM, K = {steps}"),
    }
}

/// Per-trajectory measurements.
#[derive(Clone, Copy, Default)]
struct Quality {
    roughness: Roughness,
    outside_limits: bool,
    self_colliding: bool,
}

fn quality<const J: usize>(robot: &'static Robot<f32, J>, x: &Path<J>, empty: &Scene<1>) -> Quality {
    let outside_limits = x.iter().flatten().enumerate().any(|(i, v)| {
        let j = i % J;
        *v < robot.hard_lower[j] || *v > robot.hard_upper[j]
    });
    let config = CheckConfig {
        self_collision: true,
        ..CheckConfig::default()
    };
    let self_colliding = check_trajectory(robot, empty, x, &config, true).map_or(true, |r| !r.is_free());
    Quality {
        roughness: roughness(x),
        outside_limits,
        self_colliding,
    }
}

fn row(label: &str, q: &[Quality], ms: Option<(f64, f64)>) -> String {
    let n = q.len() as f64;
    let mean = |f: fn(&Quality) -> f64| q.iter().map(f).sum::<f64>() / n;
    let share = |f: fn(&Quality) -> bool| 100.0 * q.iter().filter(|x| f(x)).count() as f64 / n;
    let time = ms.map_or_else(|| "–".to_owned(), |(median, p95)| format!("{median:.1} / {p95:.1}"));
    format!(
        "| {label} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.1} | {:.1} | {time} |",
        q.len(),
        mean(|x| x.roughness.ar),
        mean(|x| x.roughness.mresg),
        mean(|x| x.roughness.rf2w),
        mean(|x| x.roughness.rl2w),
        share(|x| x.outside_limits),
        share(|x| x.self_colliding),
    )
}

/// A `gen-data` `.npy`, or a folder of its shards (`weights/prior/shards.py`: `shard-*.npy`,
/// concatenated in name order, as `train.py` reads them).
fn read_npy<const J: usize>(path: &std::path::Path) -> Result<Vec<Path<J>>, String> {
    if !path.is_dir() {
        return read_npy_file(path);
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| format!("{}: {e}", path.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("shard-") && n.ends_with(".npy"))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(format!("{}: no shard-*.npy in this folder", path.display()));
    }
    let mut all = Vec::new();
    for file in &files {
        all.extend(read_npy_file::<J>(file)?);
    }
    Ok(all)
}

fn read_npy_file<const J: usize>(path: &std::path::Path) -> Result<Vec<Path<J>>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = || {
        format!(
            "{}: not a float32 (N, {HORIZON}, {J}) .npy from gen-data",
            path.display()
        )
    };
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(bad());
    }
    let header_len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
    let header = core::str::from_utf8(bytes.get(10..10 + header_len).ok_or_else(bad)?).map_err(|_| bad())?;
    if !header.contains("'<f4'") || !header.contains(&format!(", {HORIZON}, {J})")) {
        return Err(bad());
    }
    let data = &bytes[10 + header_len..];
    let per = HORIZON * J * 4;
    Ok(data
        .chunks_exact(per)
        .map(|t| {
            core::array::from_fn(|w| {
                core::array::from_fn(|j| {
                    let i = (w * J + j) * 4;
                    f32::from_le_bytes([t[i], t[i + 1], t[i + 2], t[i + 3]])
                })
            })
        })
        .collect())
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Runs the measurement and prints the table.
pub fn run(args: &Args) -> Result<(), String> {
    with_arm!(args.robot, robot, network => measure(robot, network, args))?
}

fn measure<const J: usize>(robot: &'static Robot<f32, J>, network: &Network<J>, args: &Args) -> Result<(), String> {
    let samplers = args
        .samplers
        .iter()
        .map(|s| parse_sampler(s))
        .collect::<Result<Vec<_>, _>>()?;
    if samplers.is_empty() {
        return Err("--samplers: give at least one".into());
    }
    let data = match &args.data {
        Some(path) => read_npy::<J>(path)?,
        None => Vec::new(),
    };
    let held = &data[data.len().saturating_sub(1200)..];
    let mut problems: Vec<([f32; J], [f32; J])> = Vec::new();
    if args.ends_from_data {
        problems.extend(held.iter().take(4 * args.per_family).map(|x| (x[0], x[HORIZON - 1])));
    } else if args.robot != Arm::Panda {
        return Err(format!(
            "--robot {}: the suites are the Panda's; give --data and --ends-from-data",
            robot.name
        ));
    } else {
        for (_, files) in crate::commands::gen_suite::read_folder(&args.problems, args.per_family)? {
            for path in files {
                let p = read_problem(&path)?;
                let Goal::Joints(goal) = p.goal else {
                    return Err(format!("{}: suite problems have joint goals", path.display()));
                };
                let (Ok(start), Ok(goal)) = (<[f32; J]>::try_from(&p.start[..]), <[f32; J]>::try_from(&goal[..]))
                else {
                    return Err(format!("{}: not {J} joints", path.display()));
                };
                problems.push((start, goal));
            }
        }
    }
    if problems.is_empty() {
        return Err(format!("{}: no problems found", args.problems.display()));
    }
    let empty = Scene::<1>::new();
    print_stdout(&format!(
        "Unguided prior of the {}, {} problems x {BATCH} trajectories ({} parameters, {} MAC per forward); \
         roughness in radians (joint-space L2 between adjacent waypoints), time per problem on one core.\n\n\
         | source | trajectories | AR | MRESG | RF2W | RL2W | outside hard limits % | self-colliding % | ms median / p95 |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        robot.name,
        problems.len(),
        edmp_core::prior::PARAMETERS,
        edmp_core::prior::MACS
    ))?;
    if !held.is_empty() {
        let q: Vec<Quality> = held.par_iter().map(|x| quality(robot, x, &empty)).collect();
        print_stdout(&format!("{}\n", row("training data (held out)", &q, None)))?;
    }
    // The plot shows the problem with the longest way from start to goal.
    let shown = (0..problems.len())
        .max_by(|a, b| {
            let d = |i: usize| step_norm(&problems[i].0, &problems[i].1);
            d(*a).total_cmp(&d(*b))
        })
        .unwrap_or(0);
    let mut plotted: Vec<(Sampler, [Path<J>; BATCH])> = Vec::new();
    let conditions: &[bool] = if args.no_conditioning { &[true, false] } else { &[true] };
    let runs: Vec<(Sampler, bool)> = samplers
        .iter()
        .flat_map(|s| conditions.iter().map(move |c| (*s, *c)))
        .collect();
    for &(sampler, condition) in &runs {
        let label = if condition {
            name(sampler)
        } else {
            format!("{}, no conditioning", name(sampler))
        };
        let bar = ProgressBar::new(problems.len() as u64).with_style(
            ProgressStyle::with_template("{msg:>18} {bar:40} {pos}/{len} [{elapsed} < {eta}]")
                .map_err(|e| e.to_string())?,
        );
        bar.set_message(label.clone());
        let results: Vec<Result<(f64, [Path<J>; BATCH]), String>> = problems
            .par_iter()
            .enumerate()
            .map(|(i, (start, goal))| {
                let mut scratch = Box::new(Scratch::<4>::new());
                let mut out = Box::new([[[0.0f32; J]; HORIZON]; BATCH]);
                let began = std::time::Instant::now();
                sample_with(
                    network,
                    sampler,
                    condition,
                    start,
                    goal,
                    &mut Rng::new(args.seed + i as u64),
                    &mut scratch,
                    &mut out,
                )
                .map_err(|e| format!("problem {i}: {e}"))?;
                let ms = began.elapsed().as_secs_f64() * 1e3;
                bar.inc(1);
                Ok((ms, *out))
            })
            .collect();
        bar.finish_and_clear();
        let mut times = Vec::new();
        let mut paths = Vec::new();
        for r in results {
            let (ms, out) = r?;
            times.push(ms);
            paths.push(out);
        }
        times.sort_by(f64::total_cmp);
        let q: Vec<Quality> = paths.par_iter().flatten().map(|x| quality(robot, x, &empty)).collect();
        print_stdout(&format!(
            "{}\n",
            row(&label, &q, Some((percentile(&times, 0.5), percentile(&times, 0.95))))
        ))?;
        if condition {
            plotted.push((sampler, paths[shown]));
        }
    }
    if let Some(path) = &args.plot {
        let first = plotted.first().map(|p| p.1);
        let last = plotted.last().map(|p| p.1);
        if let (Some(a), Some(b)) = (first, last) {
            plot(robot, path, &a, &b)?;
            print_stdout(&format!(
                "\nwrote {} (joints top to bottom; blue: {}, orange: {}; grey: hard limits)\n",
                path.display(),
                name(plotted[0].0),
                name(plotted[plotted.len() - 1].0)
            ))?;
        }
    }
    Ok(())
}

/// One panel per joint: waypoint index across, the joint's hard range up.
fn plot<const J: usize>(
    robot: &Robot<f32, J>,
    path: &std::path::Path,
    a: &[Path<J>; BATCH],
    b: &[Path<J>; BATCH],
) -> Result<(), String> {
    const W: usize = 900;
    const PANEL_H: usize = 110;
    const GAP: usize = 12;
    let mut canvas = Canvas::new(W, J * (PANEL_H + GAP) + GAP);
    let (left, right) = (20.0, W as f32 - 20.0);
    for j in 0..J {
        let top = (GAP + j * (PANEL_H + GAP)) as f32;
        let (lo, hi) = (robot.hard_lower[j], robot.hard_upper[j]);
        // Values outside the hard range are drawn on the panel's edge.
        let to_px = |w: usize, v: f32| {
            [
                left + (right - left) * w as f32 / (HORIZON - 1) as f32,
                top + PANEL_H as f32 * (hi - v.clamp(lo, hi)) / (hi - lo),
            ]
        };
        canvas.fill(
            &[
                [left, top],
                [right, top],
                [right, top + PANEL_H as f32],
                [left, top + PANEL_H as f32],
            ],
            [0.5; 3],
            0.06,
        );
        canvas.line([left, top], [right, top], 1.0, [0.6, 0.6, 0.6], 1.0);
        canvas.line(
            [left, top + PANEL_H as f32],
            [right, top + PANEL_H as f32],
            1.0,
            [0.6, 0.6, 0.6],
            1.0,
        );
        for (set, color) in [(a, [0.12, 0.47, 0.71]), (b, [1.0, 0.5, 0.05])] {
            for x in set.iter().take(4) {
                for w in 0..HORIZON - 1 {
                    canvas.line(to_px(w, x[w][j]), to_px(w + 1, x[w + 1][j]), 1.6, color, 0.8);
                }
            }
        }
    }
    canvas.png(path)
}
