//! `edmp-host gen-data`: training trajectories for the diffusion prior.
//!
//! Environments are drawn from consecutive seeds with MpiNets' family mixture (tabletop and
//! dresser 1/3 each, cubby and merged cubby 1/6 each). Each gets up to 7 candidate
//! configurations (IK solutions of poses in its target volumes, and neutral configurations),
//! and every pair of candidates is planned with RRT-Connect (1 s budget): a path from `a` to
//! `b` is also, reversed, a path from `b` to `a` (kept when the checker, walking it that way,
//! agrees), so each success gives up to two trajectories, as MpiNets' 7 × 7 pairs do. Every
//! trajectory is 50 waypoints of the arm's joints (`--robot`; the candidates are its IK
//! solutions and its neutral configuration), within its limits and collision-free by the exact
//! checker with 0.01 rad interpolation (the planner checks it).
//! Output: one `.npy` file, float32, shape (count, 50, J), which `numpy.load` reads as is.
//! With `--environments` it is one shard of a run split over workers (`weights/prior/shards.py`).

use crate::arm::{Arm, with_arm};
use crate::rrt::{RrtConfig, path_length, plan};
use crate::scenes::{Family, environment, neutral, reach};
use core::time::Duration;
use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::rng::Rng;
use edmp_core::robot::Robot;
use edmp_core::scene::MAX_OBSTACLES;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `edmp-host gen-data`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// How many trajectories to write: environments run until there are this many.
    #[arg(long, required_unless_present = "environments", conflicts_with = "environments")]
    problems: Option<usize>,
    /// Instead of `--problems`: exactly this many environments (seeds `seed..seed + N`), and
    /// every trajectory they give. One shard of a run split over workers
    /// (`weights/prior/shards.py`): disjoint seed ranges give disjoint data.
    #[arg(long)]
    environments: Option<u64>,
    /// First environment seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output `.npy` file.
    #[arg(long)]
    out: PathBuf,
    /// The arm (docs/formats.md, "Other arms"): trajectories have its number of joints.
    #[arg(long, value_enum, default_value_t = Arm::Panda)]
    robot: Arm,
}

const HORIZON: usize = 50;
const CANDIDATES: usize = 7;

/// Family of environment `seed`: MpiNets' mixture, 2 : 1 : 1 : 2.
fn family_of(seed: u64) -> Family {
    match seed % 6 {
        0 | 1 => Family::Tabletop,
        2 => Family::Cubby,
        3 => Family::MergedCubby,
        _ => Family::Dresser,
    }
}

/// When a run stops.
#[derive(Clone, Copy)]
enum Until {
    /// This many trajectories (the last environment's extra ones dropped).
    Trajectories(usize),
    /// This many environments, all their trajectories kept (a shard).
    Environments(u64),
}

/// What one environment gave.
#[derive(Default)]
struct Harvest<const J: usize> {
    trajectories: Vec<[[f32; J]; HORIZON]>,
    failures: usize,
}

fn harvest<const J: usize>(robot: &'static Robot<f32, J>, seed: u64) -> Harvest<J> {
    let mut rng = Rng::new(seed ^ 0x5EED_DA7A);
    let env = environment(family_of(seed), &mut rng);
    let Some(scene) = env.scene() else {
        return Harvest::default();
    };
    let mut candidates: Vec<[f32; J]> = Vec::new();
    for k in 0..CANDIDATES {
        let got = if k < 2 || env.regions.is_empty() {
            neutral(robot, &scene, &mut rng)
        } else {
            let region = &env.regions[rng.below(env.regions.len() as u32) as usize];
            reach(robot, &scene, region, &mut rng, 4).map(|(q, _)| q)
        };
        candidates.extend(got);
    }
    let mut out = Harvest::default();
    let config = RrtConfig {
        budget: Duration::from_secs(1),
        ..RrtConfig::default()
    };
    for i in 0..candidates.len() {
        for j in i + 1..candidates.len() {
            match plan::<HORIZON, J, MAX_OBSTACLES>(
                robot,
                &scene,
                &candidates[i],
                &candidates[j],
                &config,
                rng.next_u64(),
            ) {
                Ok(p) => {
                    out.trajectories.push(p.waypoints);
                    // The checker may call a near-margin state colliding depending on the
                    // order it walks the states in (it is conservative, not symmetric), so the
                    // reversed path is kept only if it passes on its own.
                    let mut back = p.waypoints;
                    back.reverse();
                    match check_trajectory(robot, &scene, &back, &CheckConfig::default(), true) {
                        Ok(r) if r.is_free() => out.trajectories.push(back),
                        _ => out.failures += 1,
                    }
                }
                Err(_) => out.failures += 1,
            }
        }
    }
    out
}

/// Writes `data` as a C-order float32 `.npy` array of shape `(n, HORIZON, J)`.
pub fn write_npy<const J: usize>(path: &Path, data: &[[[f32; J]; HORIZON]]) -> std::io::Result<()> {
    let dict = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {HORIZON}, {J}), }}",
        data.len()
    );
    // Magic (6) + version (2) + header length (2) + header, padded with spaces to a multiple of 64.
    let unpadded = 10 + dict.len() + 1;
    let header = format!("{dict}{}\n", " ".repeat(unpadded.next_multiple_of(64) - unpadded));
    let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
    file.write_all(b"\x93NUMPY\x01\x00")?;
    file.write_all(&(header.len() as u16).to_le_bytes())?;
    file.write_all(header.as_bytes())?;
    for x in data.iter().flatten().flatten() {
        file.write_all(&x.to_le_bytes())?;
    }
    file.flush()
}

/// Generates and writes the trajectories, with a progress bar and a summary.
pub fn run(args: &Args) -> Result<(), String> {
    with_arm!(args.robot, robot => generate(robot, args))
}

fn generate<const J: usize>(robot: &'static Robot<f32, J>, args: &Args) -> Result<(), String> {
    let began = Instant::now();
    let until = match (args.problems, args.environments) {
        (Some(n), _) => Until::Trajectories(n),
        (None, Some(e)) => Until::Environments(e),
        (None, None) => return Err("give --problems or --environments".into()),
    };
    let (total, unit) = match until {
        Until::Trajectories(n) => (n as u64, "trajectories"),
        Until::Environments(e) => (e, "environments"),
    };
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "[{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} elapsed, {{per_sec}}, eta {{eta}}"
        ))
        .map_err(|e| e.to_string())?
        .progress_chars("=> "),
    );
    let (mut data, mut failures, mut environments) = (Vec::new(), 0usize, 0u64);
    let batch = 2 * rayon::current_num_threads() as u64;
    loop {
        let end = match until {
            Until::Trajectories(n) if data.len() >= n => break,
            Until::Trajectories(_) => environments + batch,
            Until::Environments(e) if environments >= e => break,
            Until::Environments(e) => (environments + batch).min(e),
        };
        let seeds: Vec<u64> = (environments..end).map(|e| args.seed + e).collect();
        environments = end;
        let harvests: Vec<Harvest<J>> = seeds.par_iter().map(|&s| harvest(robot, s)).collect();
        for h in harvests {
            failures += h.failures;
            let room = match until {
                Until::Trajectories(n) => n - data.len(),
                Until::Environments(_) => usize::MAX,
            };
            data.extend(h.trajectories.into_iter().take(room));
        }
        bar.set_position(match until {
            Until::Trajectories(_) => data.len() as u64,
            Until::Environments(_) => environments,
        });
    }
    bar.finish();
    write_npy(&args.out, &data).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let mean = data.iter().map(|t| f64::from(path_length(t))).sum::<f64>() / data.len().max(1) as f64;
    eprintln!(
        "gen-data ({}): {} trajectories from {environments} environments in {:.1} s ({:.1}/s); {failures} failures \
         (pairs without a path in 1 s, reversed paths the checker refused); mean joint-space path length {mean:.2} rad; wrote {}",
        robot.name,
        data.len(),
        began.elapsed().as_secs_f64(),
        data.len() as f64 / began.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unseen suite measures generalization only if training never draws its kinds.
    #[test]
    fn training_never_draws_an_unseen_kind() {
        for seed in 0..600u64 {
            let family = family_of(seed);
            assert!(Family::ALL.contains(&family), "seed {seed}: {family:?}");
            assert!(!Family::UNSEEN.contains(&family), "seed {seed}: {family:?}");
        }
    }

    #[test]
    fn npy_header_is_what_numpy_expects() {
        let path = std::env::temp_dir().join(format!("edmp-npy-{}.npy", std::process::id()));
        let data = vec![[[0.5f32; 7]; HORIZON]; 3];
        write_npy(&path, &data).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        let len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
        assert_eq!((10 + len) % 64, 0);
        let header = core::str::from_utf8(&bytes[10..10 + len]).unwrap();
        assert!(header.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 50, 7), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(bytes.len(), 10 + len + 3 * 50 * 7 * 4);
        assert_eq!(&bytes[10 + len..14 + len], &0.5f32.to_le_bytes());
    }

    #[test]
    fn a_six_joint_arm_writes_six_columns() {
        let path = std::env::temp_dir().join(format!("edmp-npy6-{}.npy", std::process::id()));
        write_npy(&path, &[[[0.25f32; 6]; HORIZON]; 2]).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).ok();
        let len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
        let header = core::str::from_utf8(&bytes[10..10 + len]).unwrap();
        assert!(header.contains("'shape': (2, 50, 6)"), "{header}");
        assert_eq!(bytes.len(), 10 + len + 2 * 50 * 6 * 4);
    }

    /// Every trajectory `harvest` gives for `robot` is free by the exact checker, within the
    /// arm's limits and joins two of its candidates; some are found.
    fn harvest_is_free<const J: usize>(robot: &'static Robot<f32, J>, seeds: core::ops::Range<u64>) {
        let mut total = 0;
        for seed in seeds {
            let mut rng = Rng::new(seed ^ 0x5EED_DA7A);
            let env = environment(family_of(seed), &mut rng);
            let scene = env.scene().unwrap();
            let h = harvest(robot, seed);
            for (i, t) in h.trajectories.iter().enumerate() {
                assert!(
                    t.iter().all(|q| robot.within_soft_limits(q, 1e-5)),
                    "{} seed {seed} trajectory {i}",
                    robot.name
                );
                let r = check_trajectory(robot, &scene, t, &CheckConfig::default(), true).unwrap();
                assert!(r.is_free(), "{} seed {seed} trajectory {i}: {r:?}", robot.name);
            }
            total += h.trajectories.len();
        }
        assert!(total > 0, "{}: no trajectory", robot.name);
    }

    #[test]
    fn harvested_trajectories_are_free_and_within_limits() {
        harvest_is_free(&edmp_core::robot::PANDA, 0..3);
    }

    #[test]
    fn other_arms_harvest_their_own_trajectories() {
        harvest_is_free(&edmp_core::robot::arms::iiwa7::ROBOT, 0..2);
        harvest_is_free(&edmp_core::robot::arms::xarm6::ROBOT, 0..2);
    }
}
