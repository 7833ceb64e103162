//! `edmp-host embed`: scene files as postcard bytes for the firmware (`edmp_core::wire`), and the
//! host's own plan of each, so that `scripts/firmware` can compare the two bit for bit.
//!
//! Writes `DIR/<name>.postcard` per scene (`<name>`: the file's folder and stem, e.g.
//! `tabletop-000`) and `DIR/expected.txt`, one line `<name> <status> <fingerprint>` per scene in
//! the order given. The host plans the scene it rebuilt from the wire bytes, with the firmware's
//! settings: [`PlanConfig::DEFAULT`], EDMP's 12 guides, 12 rows, `Rng::new(seed)`.
//! `DIR/expected-timed.txt` has `<name> <fingerprint|none>`: the chosen path's time
//! parameterization (Franka's limits, jerk-limited) for free plans, as the firmware times it.

use crate::Failure;
use crate::formats::json::{joint_goal, parse_problem};
use core::fmt::Write as _;
use edmp_core::guidance::guides::EDMP_GUIDES;
use edmp_core::planner::{Plan, PlanConfig, Request, Workspace, plan};
use edmp_core::prior::Scratch;
use edmp_core::rng::Rng;
use edmp_core::scene::{MAX_OBSTACLES, Scene};
use edmp_core::trajectory::{Limits, Timed, parameterize_checked};
use edmp_core::wire::Problem;
use std::path::{Path, PathBuf};

/// Rows of the firmware's batch: one per EDMP guide.
pub const ROWS: usize = 12;

/// Arguments of `edmp-host embed`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene files (`edmp-scene/1` JSON).
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// Folder for the `.postcard` files and `expected.txt`.
    #[arg(long)]
    out: PathBuf,
    /// Seed of every plan (stored in each problem's bytes).
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// `tabletop-000` for `benchmarks/problems/tabletop/000.json`, `examples-wall` for `examples/wall.json`.
fn scene_name(path: &Path) -> Result<String, String> {
    let stem = path.file_stem().and_then(|s| s.to_str());
    let folder = path
        .canonicalize()
        .ok()
        .and_then(|p| p.parent()?.file_name()?.to_str().map(str::to_owned));
    match (folder, stem) {
        (Some(folder), Some(stem)) => Ok(format!("{folder}-{stem}")),
        _ => Err(format!("{}: cannot name this scene", path.display())),
    }
}

/// The same conversion as `json::parse_problem`: f64 → f32, rounding to nearest.
/// The wire problem of a scene file: validated by `parse_problem`, goal resolved to joints.
pub fn wire_problem(text: &str, seed: u64) -> Result<Problem<MAX_OBSTACLES>, String> {
    let parsed = parse_problem(text).map_err(|e| e.to_string())?;
    let goal = joint_goal(&parsed)?;
    let mut problem = Problem {
        obstacles: Default::default(),
        held: parsed.held,
        finger: parsed.scene().gripper(),
        start: parsed.start,
        goal,
        seed,
    };
    for p in &parsed.primitives {
        problem
            .obstacles
            .push(*p)
            .map_err(|_| format!("more than {MAX_OBSTACLES} obstacles"))?;
    }
    // The firmware rebuilds the scene from these numbers: it must be the host's scene exactly.
    let rebuilt = problem.to_scene().map_err(|e| e.to_string())?;
    if rebuilt.obstacles() != parsed.scene().obstacles()
        || rebuilt.held() != parsed.scene().held()
        || rebuilt.gripper() != parsed.scene().gripper()
    {
        return Err("the wire scene differs from the parsed one".to_owned());
    }
    Ok(problem)
}

/// The firmware's plan, on the host: same configuration, guides, rows and seed.
pub fn plan_like_firmware(problem: &Problem<MAX_OBSTACLES>) -> Result<Plan<ROWS>, String> {
    let scene: Scene<MAX_OBSTACLES> = problem.to_scene().map_err(|e| e.to_string())?;
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<ROWS>::new());
    let mut rng = Rng::new(problem.seed);
    plan::<ROWS, MAX_OBSTACLES, 4, { edmp_core::planner::DEFAULT_SEARCH_NODES }>(
        &Request {
            scene: &scene,
            start: &problem.start,
            goal: &problem.goal,
            guides: &EDMP_GUIDES,
            config: &PlanConfig::DEFAULT,
        },
        &mut rng,
        &mut scratch,
        &mut work,
    )
    .map_err(|e| format!("planner: {e}"))
}

/// Writes the bytes and the expected results.
pub fn run(args: &Args) -> Result<(), Failure> {
    let input = |e: String| Failure::Input(e);
    std::fs::create_dir_all(&args.out).map_err(|e| input(format!("{}: {e}", args.out.display())))?;
    let mut expected = String::new();
    let mut expected_timed = String::new();
    for path in &args.scenes {
        let at = |e: String| Failure::Input(format!("{}: {e}", path.display()));
        let name = scene_name(path).map_err(input)?;
        let text = std::fs::read_to_string(path).map_err(|e| at(e.to_string()))?;
        let problem = wire_problem(&text, args.seed).map_err(at)?;
        let bytes = postcard::to_stdvec(&problem).map_err(|e| at(e.to_string()))?;
        let file = args.out.join(format!("{name}.postcard"));
        std::fs::write(&file, &bytes).map_err(|e| input(format!("{}: {e}", file.display())))?;
        let plan = plan_like_firmware(&problem).map_err(at)?;
        let status = if plan.is_free() { "success" } else { "collision" };
        let line = format!("{name} {status} {:016x}", plan.fingerprint());
        println!("{line}  ({} bytes)", bytes.len());
        let _ = writeln!(expected, "{line}");
        let timed = time_like_firmware(&problem, &plan).map_err(at)?;
        let _ = writeln!(
            expected_timed,
            "{name} {}",
            timed.map_or("none".to_owned(), |f| format!("{f:016x}"))
        );
    }
    for (name, text) in [("expected.txt", expected), ("expected-timed.txt", expected_timed)] {
        let file = args.out.join(name);
        std::fs::write(&file, text).map_err(|e| input(format!("{}: {e}", file.display())))?;
    }
    Ok(())
}

/// The firmware's time parameterization of a free plan's chosen path, on the host: its
/// fingerprint, `None` for a colliding plan (the firmware times only free ones).
pub fn time_like_firmware(problem: &Problem<MAX_OBSTACLES>, plan: &Plan<ROWS>) -> Result<Option<u64>, String> {
    let Some(path) = plan.paths.get(plan.best).filter(|_| plan.is_free()) else {
        return Ok(None);
    };
    let scene: Scene<MAX_OBSTACLES> = problem.to_scene().map_err(|e| e.to_string())?;
    let mut timed: Box<Timed> = Box::new(Timed::new());
    parameterize_checked(&scene, path, &Limits::DEFAULT, &PlanConfig::DEFAULT.check, &mut timed)
        .map_err(|e| format!("time parameterization: {e}"))?;
    Ok(Some(timed.fingerprint()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wall_round_trips_through_postcard() {
        let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/wall.json")).unwrap();
        let problem = wire_problem(&text, 3).unwrap();
        assert_eq!(problem.obstacles.len(), 4);
        let bytes = postcard::to_stdvec(&problem).unwrap();
        let back: Problem<MAX_OBSTACLES> = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back, problem);
        assert_eq!(back.seed, 3);
    }

    #[test]
    fn names_scenes_by_folder_and_stem() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let suite = root.join("benchmarks/problems/tabletop/000.json");
        assert_eq!(scene_name(&suite).unwrap(), "tabletop-000");
        assert_eq!(scene_name(&root.join("examples/wall.json")).unwrap(), "examples-wall");
    }
}
