//! `edmp-host embed`: scene files as postcard bytes for the firmware (`edmp_core::wire`), and the
//! host's own plan of each, so that `scripts/firmware` can compare the two bit for bit.
//!
//! Writes `DIR/<name>.postcard` per scene (`<name>`: the file's folder and stem, e.g.
//! `tabletop-000`) and `DIR/expected.txt`, one line `<name> <status> <fingerprint>` per scene in
//! the order given. The host plans the scene it rebuilt from the wire bytes, with the firmware's
//! settings: [`PlanConfig::DEFAULT`], EDMP's 12 guides, 12 rows, `Rng::new(seed)`.
//! A scene with `points` or `mesh` obstacles travels with its pieces and tree as the host built
//! them (`edmp_core::wire`), at most [`FIRMWARE_PIECES`] of them.
//! `DIR/expected-timed.txt` has `<name> <fingerprint|none>`: the chosen path's time
//! parameterization (the arm's limits, jerk-limited) for free plans, as the firmware times it.
//! Every scene names its arm (`robot`): the bytes carry its joints, and the firmware built for
//! that arm (`scripts/firmware --robot NAME`) plans them. One call embeds one arm's scenes.

use crate::arm::Arm;
use crate::formats::json::{self, joint_goal, parse_problem, parse_problem_for, scene_arm};
use crate::formats::surface::SURFACE_BOXES;
use crate::{Failure, with_arm};
use core::fmt::Write as _;
use edmp_core::guidance::guides::EDMP_GUIDES;
use edmp_core::planner::{Plan, PlanConfig, Request, Workspace, plan};
use edmp_core::prior::{Network, Scratch};
use edmp_core::rng::Rng;
use edmp_core::robot::Robot;
use edmp_core::scene::{MAX_OBSTACLES, Scene};
use edmp_core::surface::bvh::nodes_for;
use edmp_core::trajectory::{Limits, Timed, parameterize_checked};
use edmp_core::wire::{Problem, WireSurface, decode, encode_surface, surface_bytes_max};
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

/// Pieces (balls and triangles of every cloud and mesh together) the firmware decodes into its
/// `WireSurface` (examples/firmware-qemu/src/main.rs, `PIECES`): the host refuses more.
pub const FIRMWARE_PIECES: usize = 320;

/// The firmware scene's obstacle capacity (examples/firmware-qemu/src/main.rs, `OBSTACLES`):
/// primitives and guide boxes of a scene with clouds or meshes must fit it, or the firmware's
/// guides would see fewer boxes than the host's.
pub const FIRMWARE_OBSTACLES: usize = 40;

/// A scene as the firmware receives it.
#[derive(Clone, Debug)]
pub struct Embedded<const J: usize> {
    /// The primitives, ends, finger opening and seed.
    pub problem: Problem<MAX_OBSTACLES, J>,
    /// The postcard bytes: the problem's, then the surface section when the scene has clouds
    /// or meshes (`edmp_core::wire::decode`).
    pub bytes: Vec<u8>,
}

/// Tree nodes the firmware holds: enough for any tree over [`FIRMWARE_PIECES`] pieces.
pub const FIRMWARE_NODES: usize = nodes_for(FIRMWARE_PIECES);

/// The decoded surface: the firmware's capacity.
type Decoded = WireSurface<FIRMWARE_PIECES, FIRMWARE_NODES>;

/// The wire problem of a scene file without clouds or meshes (those need [`embed_problem`]):
/// validated by `parse_problem`, goal resolved to joints.
pub fn wire_problem(text: &str, seed: u64) -> Result<Problem<MAX_OBSTACLES>, String> {
    let parsed = parse_problem(text).map_err(|e| e.to_string())?;
    if parsed.surfaces.pieces() > 0 {
        return Err("the scene has clouds or meshes: embed_problem carries them".to_owned());
    }
    Ok(embed_problem(&parsed, seed)?.problem)
}

/// The firmware's bytes of a parsed scene (its clouds and meshes built by `parse_problem`, the
/// pieces and the tree travelling as built), checked to decode to the host's scene exactly.
pub fn embed_problem<const J: usize>(parsed: &json::Problem<J>, seed: u64) -> Result<Embedded<J>, String>
where
    [f32; J]: serde::Serialize + for<'de> serde::Deserialize<'de>,
{
    let goal = joint_goal(parsed)?;
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
    let mut bytes = postcard::to_stdvec(&problem).map_err(|e| e.to_string())?;
    let surface = parsed.surfaces.surface();
    if !surface.is_empty() {
        let pieces = surface.pieces().len();
        if pieces > FIRMWARE_PIECES {
            return Err(format!(
                "{pieces} balls and triangles (clouds and meshes together), the firmware holds at most \
                 {FIRMWARE_PIECES}: fewer points or a coarser mesh"
            ));
        }
        let guides = problem.obstacles.len() + parsed.surfaces.boxes.len();
        if guides > FIRMWARE_OBSTACLES {
            return Err(format!(
                "{} primitives and {} boxes around the clouds and meshes, the firmware's scene holds \
                 at most {FIRMWARE_OBSTACLES}",
                problem.obstacles.len(),
                parsed.surfaces.boxes.len()
            ));
        }
        let mut section = vec![0u8; surface_bytes_max(pieces, surface.nodes().len())];
        // The limit the host's `build_surfaces` gave `covers`: the firmware fits the same boxes.
        let boxes = u8::try_from(SURFACE_BOXES).map_err(|e| e.to_string())?;
        let n = encode_surface(surface.pieces(), surface.nodes(), boxes, &mut section).map_err(|e| e.to_string())?;
        bytes.extend_from_slice(&section[..n]);
    }
    // The firmware rebuilds the scene from these bytes: it must be the host's scene exactly.
    let mut decoded = Box::new(Decoded::new());
    let back =
        decode::<MAX_OBSTACLES, FIRMWARE_PIECES, FIRMWARE_NODES, J>(&bytes, &mut decoded).map_err(|e| e.to_string())?;
    let rebuilt = back.to_scene_with(&decoded).map_err(|e| e.to_string())?;
    let scene = parsed.scene();
    if back != problem
        || rebuilt.obstacles() != scene.obstacles()
        || rebuilt.guide_obstacles() != scene.guide_obstacles()
        || rebuilt.surface().pieces() != scene.surface().pieces()
        || rebuilt.surface().nodes() != scene.surface().nodes()
        || rebuilt.held() != scene.held()
        || rebuilt.gripper() != scene.gripper()
    {
        return Err("the wire scene differs from the parsed one".to_owned());
    }
    Ok(Embedded { problem, bytes })
}

/// The firmware's plan of `bytes` for `robot`, on the host: the scene decoded from them, same
/// configuration, guides, rows and seed.
pub fn plan_like_firmware<const J: usize>(
    robot: &'static Robot<f32, J>,
    network: &'static Network<J>,
    bytes: &[u8],
) -> Result<Plan<ROWS, J>, String>
where
    [f32; J]: for<'de> serde::Deserialize<'de>,
{
    let mut decoded = Box::new(Decoded::new());
    let problem =
        decode::<MAX_OBSTACLES, FIRMWARE_PIECES, FIRMWARE_NODES, J>(bytes, &mut decoded).map_err(|e| e.to_string())?;
    let scene: Scene<MAX_OBSTACLES> = problem.to_scene_with(&decoded).map_err(|e| e.to_string())?;
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<ROWS, { edmp_core::planner::DEFAULT_SEARCH_NODES }, J>::new());
    let mut rng = Rng::new(problem.seed);
    plan::<ROWS, MAX_OBSTACLES, 4, { edmp_core::planner::DEFAULT_SEARCH_NODES }, J>(
        &Request {
            robot,
            network,
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
    let mut texts = Vec::new();
    let mut arms: Vec<Arm> = Vec::new();
    for path in &args.scenes {
        let text = std::fs::read_to_string(path).map_err(|e| input(format!("{}: {e}", path.display())))?;
        let arm = scene_arm(&text).map_err(|e| input(format!("{}: {e}", path.display())))?;
        if arms.first().is_some_and(|first| *first != arm) {
            return Err(input(format!(
                "{}: robot {arm}, but {} is {}: one firmware plans one arm (embed each arm's scenes apart)",
                path.display(),
                args.scenes[0].display(),
                arms[0]
            )));
        }
        arms.push(arm);
        texts.push(text);
    }
    let arm = arms.first().copied().unwrap_or_default();
    with_arm!(arm, robot, network => write_all(args, &texts, robot, network)).map_err(input)?
}

fn write_all<const J: usize>(
    args: &Args,
    texts: &[String],
    robot: &'static Robot<f32, J>,
    network: &'static Network<J>,
) -> Result<(), Failure>
where
    [f32; J]: serde::Serialize + for<'de> serde::Deserialize<'de>,
{
    let input = |e: String| Failure::Input(e);
    std::fs::create_dir_all(&args.out).map_err(|e| input(format!("{}: {e}", args.out.display())))?;
    let mut expected = String::new();
    let mut expected_timed = String::new();
    for (path, text) in args.scenes.iter().zip(texts) {
        let at = |e: String| Failure::Input(format!("{}: {e}", path.display()));
        let name = scene_name(path).map_err(input)?;
        // Files a scene names (clouds, meshes) lie beside it.
        let dir = path.parent().unwrap_or(Path::new("."));
        let parsed = parse_problem_for(text, dir, robot).map_err(|e| at(e.to_string()))?;
        let Embedded { bytes, .. } = embed_problem(&parsed, args.seed).map_err(at)?;
        let file = args.out.join(format!("{name}.postcard"));
        std::fs::write(&file, &bytes).map_err(|e| input(format!("{}: {e}", file.display())))?;
        let plan = plan_like_firmware(robot, network, &bytes).map_err(at)?;
        let status = if plan.is_free() { "success" } else { "collision" };
        let line = format!("{name} {status} {:016x}", plan.fingerprint());
        crate::commands::print_stdout(&format!("{line}  ({} bytes)\n", bytes.len())).map_err(input)?;
        let _ = writeln!(expected, "{line}");
        let timed = time_like_firmware(robot, &bytes, &plan).map_err(at)?;
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
pub fn time_like_firmware<const J: usize>(
    robot: &'static Robot<f32, J>,
    bytes: &[u8],
    plan: &Plan<ROWS, J>,
) -> Result<Option<u64>, String>
where
    [f32; J]: for<'de> serde::Deserialize<'de>,
{
    let Some(path) = plan.paths.get(plan.best).filter(|_| plan.is_free()) else {
        return Ok(None);
    };
    let mut decoded = Box::new(Decoded::new());
    let problem =
        decode::<MAX_OBSTACLES, FIRMWARE_PIECES, FIRMWARE_NODES, J>(bytes, &mut decoded).map_err(|e| e.to_string())?;
    let scene: Scene<MAX_OBSTACLES> = problem.to_scene_with(&decoded).map_err(|e| e.to_string())?;
    let mut timed: Box<Timed<{ edmp_core::trajectory::DEFAULT_GRID }, { edmp_core::path::HORIZON }, J>> =
        Box::new(Timed::new());
    parameterize_checked(
        robot,
        &scene,
        path,
        &Limits::DEFAULT,
        &PlanConfig::DEFAULT.check,
        &mut timed,
    )
    .map_err(|e| format!("time parameterization: {e}"))?;
    Ok(Some(timed.fingerprint()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::json::read_problem;
    use edmp_core::robot::JOINTS;

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
    fn clouds_and_meshes_travel_built_and_decode_to_the_hosts_scene() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        for (file, pieces) in [("wall-points.json", 280), ("wall-mesh.json", 12)] {
            let parsed = read_problem(&root.join(file)).unwrap();
            let e = embed_problem(&parsed, 0).unwrap();
            assert_eq!(e.problem.obstacles.len(), 3, "{file}");
            let mut decoded = Box::new(Decoded::new());
            let back =
                decode::<MAX_OBSTACLES, FIRMWARE_PIECES, FIRMWARE_NODES, JOINTS>(&e.bytes, &mut decoded).unwrap();
            assert_eq!(back, e.problem);
            assert_eq!(decoded.pieces().len(), pieces, "{file}");
            let scene = back.to_scene_with(&decoded).unwrap();
            assert_eq!(scene.guide_obstacles(), parsed.scene().guide_obstacles(), "{file}");
            assert!(scene.guide_obstacles().len() > 3, "{file}: guide boxes");
            // Without the section the bytes are a problem without a surface.
            let plain = postcard::to_stdvec(&e.problem).unwrap();
            assert!(e.bytes.len() > plain.len() && e.bytes.starts_with(&plain));
            assert!(wire_problem(&std::fs::read_to_string(root.join("wall-mesh.json")).unwrap(), 0).is_err());
        }
    }

    #[test]
    fn a_cloud_beyond_the_firmwares_capacity_is_refused() {
        let points: Vec<String> = (0..FIRMWARE_PIECES + 1)
            .map(|i| {
                format!(
                    "[-0.7, {}, {}]",
                    (i % 40) as f32 * 0.01 - 0.2,
                    0.3 + (i / 40) as f32 * 0.01
                )
            })
            .collect();
        let text = format!(
            r#"{{"format": "edmp-scene/1", "obstacles": [{{"type": "points", "radius": 0.004, "points": [{}]}}],
                "start": [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785], "goal": {{"joints": [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785]}}}}"#,
            points.join(", ")
        );
        let parsed = parse_problem(&text).unwrap();
        let e = embed_problem(&parsed, 0).unwrap_err();
        assert!(e.contains("the firmware holds at most 320"), "{e}");
    }

    #[test]
    fn names_scenes_by_folder_and_stem() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let suite = root.join("benchmarks/problems/tabletop/000.json");
        assert_eq!(scene_name(&suite).unwrap(), "tabletop-000");
        assert_eq!(scene_name(&root.join("examples/wall.json")).unwrap(), "examples-wall");
    }
}
