//! `edmp-host gen-suite`: the committed benchmark suites. For each family, problems are drawn
//! from consecutive seeds (kinds cycling task-oriented, neutral start, neutral goal) and kept
//! when RRT-Connect solves them within the budget, until `--per-family` are kept. Seeds are
//! processed in parallel batches but kept in seed order, so the output depends only on the
//! arguments. `--suite in-distribution` (the default) makes `benchmarks/problems` from the
//! training families; `--suite unseen` makes `benchmarks/unseen` from the kinds the prior
//! never saw, on seeds far from every in-distribution family's. `--robot NAME` makes another
//! arm's suites (`benchmarks/NAME/problems`, `benchmarks/NAME/unseen`) from the same seeds:
//! the same environments, that arm's ends.

use crate::arm::Arm;
use crate::rrt::{RrtConfig, plan};
use crate::scenes::{Family, Kind, Problem, problem_for};
use crate::with_arm;
use core::time::Duration;
use edmp_core::robot::Robot;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
/// A problem folder as written by `gen-suite`: each family's name and its first `per_family`
/// `.json` files, families and files in name order.
pub fn read_folder(root: &std::path::Path, per_family: usize) -> Result<Vec<(String, Vec<PathBuf>)>, String> {
    let list = |dir: &std::path::Path| -> Result<Vec<PathBuf>, String> {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        paths.sort();
        Ok(paths)
    };
    let mut out = Vec::new();
    for dir in list(root)?.into_iter().filter(|p| p.is_dir()) {
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut files: Vec<PathBuf> = list(&dir)?
            .into_iter()
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.truncate(per_family);
        out.push((name, files));
    }
    Ok(out)
}

use std::path::{Path, PathBuf};

/// Which committed suite to make.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Suite {
    /// The four MpiNets (training) families: `benchmarks/problems`.
    InDistribution,
    /// The four kinds the prior never saw in training: `benchmarks/unseen`.
    Unseen,
}

impl Suite {
    fn families(self) -> [Family; 4] {
        match self {
            Suite::InDistribution => Family::ALL,
            Suite::Unseen => Family::UNSEEN,
        }
    }

    fn folder(self) -> &'static str {
        match self {
            Suite::InDistribution => "problems",
            Suite::Unseen => "unseen",
        }
    }

    /// Where `arm`'s suite lives: `benchmarks/problems` for the Panda, `benchmarks/NAME/problems`
    /// for another arm (and `unseen` likewise).
    pub fn default_folder(self, arm: Arm) -> PathBuf {
        match arm {
            Arm::Panda => Path::new("benchmarks").join(self.folder()),
            other => Path::new("benchmarks").join(other.name()).join(self.folder()),
        }
    }
}

/// Arguments of `edmp-host gen-suite`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Which suite: its families and its default output folder.
    #[arg(long, value_enum, default_value_t = Suite::InDistribution)]
    suite: Suite,
    /// Output folder (one sub-folder per family); default `benchmarks/problems` or
    /// `benchmarks/unseen`, after `--suite`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Problems per family.
    #[arg(long, default_value_t = 100)]
    per_family: usize,
    /// First seed; family `f` (in the order tabletop, cubby, merged cubby, dresser) draws
    /// from `seed + f × 11,000,000` on; unseen kind `k` (cage, window box, bookshelf, under
    /// table) from `seed + 1,000,000,000 + k × 11,000,000`.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// RRT-Connect budget that makes a problem count as solvable, milliseconds.
    #[arg(long, default_value_t = 5000)]
    solvable_ms: u64,
    /// Only these families of the suite (default: all four).
    #[arg(long, value_enum)]
    family: Vec<Family>,
    /// The arm (docs/formats.md, "Other arms"): the problems' ends are its own.
    #[arg(long, value_enum, default_value_t = Arm::Panda)]
    robot: Arm,
}

const KINDS: [Kind; 3] = [Kind::TaskOriented, Kind::NeutralStart, Kind::NeutralGoal];

/// `robot`'s problem from `seed`, if it exists and RRT-Connect solves it within `budget`.
pub(crate) fn solvable<const J: usize>(
    robot: &'static Robot<f32, J>,
    family: Family,
    seed: u64,
    budget: Duration,
) -> Option<Problem<J>> {
    let p = problem_for(robot, family, KINDS[(seed % 3) as usize], seed)?;
    let config = RrtConfig {
        budget,
        ..RrtConfig::default()
    };
    plan::<50, J, { edmp_core::scene::MAX_OBSTACLES }>(robot, &p.scene, &p.start, &p.goal, &config, seed).ok()?;
    Some(p)
}

/// Writes the suite.
pub fn run(args: &Args) -> Result<(), String> {
    with_arm!(args.robot, robot => generate(robot, args))
}

fn generate<const J: usize>(robot: &'static Robot<f32, J>, args: &Args) -> Result<(), String> {
    let families: Vec<Family> = if args.family.is_empty() {
        args.suite.families().to_vec()
    } else {
        args.family.clone()
    };
    if let Some(f) = families.iter().find(|f| !args.suite.families().contains(f)) {
        return Err(format!(
            "--family {}: not a family of {} (see --suite)",
            f.name(),
            args.suite.default_folder(args.robot).display()
        ));
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| args.suite.default_folder(args.robot));
    let budget = Duration::from_millis(args.solvable_ms);
    for &family in &families {
        let began = std::time::Instant::now();
        let dir = out.join(family.name());
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let bar = ProgressBar::new(args.per_family as u64).with_message(family.name());
        bar.set_style(
            ProgressStyle::with_template("{msg:>13} [{bar:40}] {pos}/{len} problems, {elapsed} ({per_sec} )")
                .map_err(|e| e.to_string())?
                .progress_chars("=> "),
        );
        let base = args.seed + family_offset(family);
        let (mut kept, mut tried) = (Vec::new(), 0u64);
        while kept.len() < args.per_family && tried < 100 * args.per_family as u64 + 100 {
            let batch: Vec<u64> = (tried..tried + 16).map(|i| base + i).collect();
            tried += 16;
            let found: Vec<Option<Problem<J>>> =
                batch.par_iter().map(|&s| solvable(robot, family, s, budget)).collect();
            for p in found.into_iter().flatten() {
                if kept.len() < args.per_family {
                    kept.push(p);
                    bar.inc(1);
                }
            }
        }
        bar.finish();
        for (i, p) in kept.iter().enumerate() {
            let path = dir.join(format!("{i:03}.json"));
            let text = serde_json::to_string(&p.json()).map_err(|e| e.to_string())? + "\n";
            std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        }
        eprintln!(
            "{}: {} problems from {tried} seeds in {:.1} s",
            family.name(),
            kept.len(),
            began.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Where the unseen kinds' seeds begin: far above the in-distribution families' (4 × 11 M).
const UNSEEN_SEEDS: u64 = 1_000_000_000;

/// Keeps the families' seed ranges apart, the same whichever `--family` subset is asked for.
fn family_offset(family: Family) -> u64 {
    match Family::UNSEEN.iter().position(|&f| f == family) {
        Some(k) => UNSEEN_SEEDS + k as u64 * 11_000_000,
        None => Family::ALL.iter().position(|&f| f == family).unwrap_or(0) as u64 * 11_000_000,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::json::{Goal, parse_problem};

    const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../benchmarks/problems");
    const UNSEEN_ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../benchmarks/unseen");

    #[test]
    fn generators_are_deterministic() {
        for family in Family::ALL.into_iter().chain(Family::UNSEEN) {
            for seed in [1u64, 2, 3] {
                let a =
                    problem_for(&edmp_core::robot::PANDA, family, KINDS[(seed % 3) as usize], seed).map(|p| p.json());
                let b =
                    problem_for(&edmp_core::robot::PANDA, family, KINDS[(seed % 3) as usize], seed).map(|p| p.json());
                assert_eq!(a, b, "{family:?} seed {seed}");
            }
        }
    }

    #[test]
    fn every_suite_problem_is_valid_and_solvable() {
        let mut count = 0;
        for family in Family::ALL {
            let dir = Path::new(ROOT).join(family.name());
            let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
            files.sort();
            assert_eq!(files.len(), 100, "{}", dir.display());
            let results: Vec<Result<(), String>> = files
                .par_iter()
                .map(|path| {
                    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
                    let p = parse_problem(&text).map_err(|e| format!("{}: {e}", path.display()))?;
                    let Goal::Joints(goal) = p.goal else {
                        return Err("joint goal expected".into());
                    };
                    let meta: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
                    let seed = meta["meta"]["seed"].as_u64().ok_or("meta.seed")?;
                    // The seed and the generous budget make this the search that admitted it; the
                    // checker has since changed near the margin (GJK restarts, the ends' rule),
                    // so a search whose resampled path grazes the margin tries the next seeds.
                    let config = RrtConfig {
                        budget: Duration::from_secs(60),
                        ..RrtConfig::default()
                    };
                    let mut last = Err(String::new());
                    for s in seed..seed + 4 {
                        last = plan::<50, { edmp_core::robot::JOINTS }, { edmp_core::scene::MAX_OBSTACLES }>(
                            &edmp_core::robot::PANDA,
                            &p.scene(),
                            &p.start,
                            &goal,
                            &config,
                            s,
                        )
                        .map(|_| ())
                        .map_err(|e| format!("{}: {e:?}", path.display()));
                        if last.is_ok() {
                            break;
                        }
                    }
                    last
                })
                .collect();
            for r in results {
                r.unwrap();
                count += 1;
            }
        }
        assert_eq!(count, 400);
    }

    /// Every committed problem of another arm's suites parses as that arm's (its joint count,
    /// limits and valid ends), and every 20th is drawn again from its seed, byte for byte.
    fn other_arms_suites_are_valid<const J: usize>(robot: &'static Robot<f32, J>, arm: Arm) {
        for suite in [Suite::InDistribution, Suite::Unseen] {
            let root = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("..")
                .join(suite.default_folder(arm));
            let mut count = 0;
            for family in suite.families() {
                let dir = root.join(family.name());
                let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
                files.sort();
                assert_eq!(files.len(), 100, "{}", dir.display());
                for (i, path) in files.iter().enumerate() {
                    let text = std::fs::read_to_string(path).unwrap();
                    crate::formats::json::parse_problem_for(&text, Path::new("."), robot)
                        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                    if i % 20 == 0 {
                        let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
                        let seed = doc["meta"]["seed"].as_u64().unwrap();
                        let again = problem_for(robot, family, KINDS[(seed % 3) as usize], seed).unwrap();
                        assert_eq!(
                            serde_json::to_string(&again.json()).unwrap() + "\n",
                            text,
                            "{}",
                            path.display()
                        );
                    }
                    count += 1;
                }
            }
            assert_eq!(count, 400, "{}", root.display());
        }
    }

    #[test]
    fn other_arms_suites_are_valid_and_reproduced_from_their_seeds() {
        other_arms_suites_are_valid(&edmp_core::robot::arms::iiwa7::ROBOT, Arm::Iiwa7);
        other_arms_suites_are_valid(&edmp_core::robot::arms::xarm6::ROBOT, Arm::Xarm6);
    }

    #[test]
    fn seed_ranges_of_the_suites_are_apart() {
        for f in Family::ALL {
            assert!(family_offset(f) + 11_000_000 <= UNSEEN_SEEDS, "{f:?}");
        }
        let mut unseen: Vec<u64> = Family::UNSEEN.iter().map(|&f| family_offset(f)).collect();
        unseen.dedup();
        assert_eq!(unseen.len(), 4);
        assert!(unseen.iter().all(|&o| o >= UNSEEN_SEEDS));
    }

    /// Every committed unseen problem parses, is of its folder's kind, and has ends inside
    /// the joint limits that the core checker finds free. Every 20th is drawn again from its
    /// seed (the very same JSON) and solved again by RRT-Connect: a sample, to keep CI short.
    #[test]
    fn every_unseen_problem_is_valid_and_a_sample_is_reproduced() {
        use edmp_core::collision::checker::{CheckConfig, check_state};
        use edmp_core::robot::PANDA;
        let mut count = 0;
        for family in Family::UNSEEN {
            let dir = Path::new(UNSEEN_ROOT).join(family.name());
            let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
            files.sort();
            assert_eq!(files.len(), 100, "{}", dir.display());
            let results: Vec<Result<(), String>> = files
                .par_iter()
                .enumerate()
                .map(|(i, path)| {
                    let name = path.display();
                    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
                    let p = parse_problem(&text).map_err(|e| format!("{name}: {e}"))?;
                    let Goal::Joints(goal) = p.goal else {
                        return Err(format!("{name}: joint goal expected"));
                    };
                    for (end, q) in [("start", &p.start), ("goal", &goal)] {
                        if !PANDA.within_soft_limits(q, 1e-5) {
                            return Err(format!("{name}: {end} outside the joint limits"));
                        }
                        if check_state(&edmp_core::robot::PANDA, &p.scene(), q, &CheckConfig::default()) != Ok(None) {
                            return Err(format!("{name}: {end} not free"));
                        }
                    }
                    let doc: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
                    let seed = doc["meta"]["seed"].as_u64().ok_or("meta.seed")?;
                    if doc["meta"]["family"] != family.name() || seed < family_offset(family) {
                        return Err(format!("{name}: meta {}", doc["meta"]));
                    }
                    if i % 20 != 0 {
                        return Ok(());
                    }
                    let again = problem_for(&edmp_core::robot::PANDA, family, KINDS[(seed % 3) as usize], seed)
                        .ok_or("no problem")?;
                    if serde_json::to_string(&again.json()).map_err(|e| e.to_string())? + "\n" != text {
                        return Err(format!("{name}: seed {seed} draws another problem"));
                    }
                    let config = RrtConfig {
                        budget: Duration::from_secs(60),
                        ..RrtConfig::default()
                    };
                    plan::<50, { edmp_core::robot::JOINTS }, { edmp_core::scene::MAX_OBSTACLES }>(
                        &edmp_core::robot::PANDA,
                        &p.scene(),
                        &p.start,
                        &goal,
                        &config,
                        seed,
                    )
                    .map(|_| ())
                    .map_err(|e| format!("{name}: {e:?}"))
                })
                .collect();
            for r in results {
                r.unwrap();
                count += 1;
            }
        }
        assert_eq!(count, 400);
    }
}
