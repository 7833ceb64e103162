//! The host's way of running the core planner: the batch and search memory it gives a plan, IK
//! for a pose goal, the executor (`--threads`), and the time each phase takes (reported by the
//! core's pipeline through an observer, not re-run here). `plan`, `bench` and the Python
//! package all plan through [`plan_problem_on`].

use crate::Failure;
use crate::formats::json::{Problem, joint_goal};
use crate::threads::Threads;
use edmp_core::executor::{Executor, Serial};
use edmp_core::guidance::guides::{EDMP_GUIDES, Guide};
use edmp_core::planner::search::SearchConfig;
use edmp_core::planner::{GlobalConfig, Observer, Phase, Plan, PlanConfig, Request, Workspace, plan_observed};
use edmp_core::prior::{Network, Scratch};
use edmp_core::rng::Rng;
use edmp_core::robot::JOINTS;
use std::time::Instant;

/// Rows of the batch: EDMP's 12 guides, one trajectory each.
pub const ROWS: usize = 12;

/// Nodes per search tree the host's workspace holds (the core's default search takes all of
/// them, `--search-nodes` fewer; the firmware and `edmp-host embed` hold 512). About 1 MB: a
/// host has the memory, and the iiwa 7's unseen problems need trees this large
/// (docs/robots.md).
pub const HOST_SEARCH_NODES: usize = 16384;

/// Sampling iterations of one search on the host. The core's default (8,000) bounds the
/// firmware's work; trees of [`HOST_SEARCH_NODES`] need more iterations to fill.
pub const HOST_SEARCH_ITERATIONS: u32 = 32_000;

/// Searches the host's global stage tries before it gives up (the core's default and the
/// firmware's: 4). A search to a narrow passage is a lottery, and searches 5 to 8 run only for
/// a problem whose first four failed, so they change no other plan; a plan that fails takes
/// twice as long (docs/robots.md measures both).
pub const HOST_SEARCH_ATTEMPTS: u8 = 8;

/// The configuration the host plans with (`plan`, `bench`, the Python package): the core's
/// [`PlanConfig::DEFAULT`] with [`HOST_SEARCH_ITERATIONS`] and [`HOST_SEARCH_ATTEMPTS`].
/// `edmp-host embed` plans as the firmware does, with the core's default.
pub const HOST_CONFIG: PlanConfig = PlanConfig {
    global: Some(GlobalConfig {
        search: SearchConfig {
            max_iterations: HOST_SEARCH_ITERATIONS,
            ..SearchConfig::DEFAULT
        },
        attempts: HOST_SEARCH_ATTEMPTS,
        ..GlobalConfig::DEFAULT
    }),
    ..PlanConfig::DEFAULT
};

/// A planned problem for an arm of `J` joints and where the time went.
#[derive(Debug)]
pub struct Planned<const J: usize = JOINTS> {
    /// Candidates, verdicts, the winner.
    pub plan: Plan<ROWS, J>,
    /// Milliseconds in IK.
    pub ik_ms: f64,
    /// Milliseconds in the guided denoising.
    pub denoise_ms: f64,
    /// Milliseconds in the selection.
    pub select_ms: f64,
    /// Milliseconds in the global stage.
    pub global_ms: f64,
    /// Milliseconds shortening the winner.
    pub shortcut_ms: f64,
}

impl<const J: usize> Planned<J> {
    /// Planning time in all, milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.ik_ms + self.denoise_ms + self.select_ms + self.global_ms + self.shortcut_ms
    }
}

/// Plans a parsed problem with its arm's prior `network`: IK for a pose goal, then the core
/// planner with `ROWS` rows.
pub fn plan_problem<const J: usize>(
    network: &'static Network<J>,
    problem: &Problem<J>,
    guides: &[Guide],
    config: &PlanConfig,
    seed: u64,
) -> Result<Planned<J>, Failure> {
    plan_problem_on(network, problem, guides, config, seed, 1)
}

/// [`plan_problem`] on `threads` threads (1: on the calling thread): the same plan, bit for bit.
pub fn plan_problem_on<const J: usize>(
    network: &'static Network<J>,
    problem: &Problem<J>,
    guides: &[Guide],
    config: &PlanConfig,
    seed: u64,
    threads: usize,
) -> Result<Planned<J>, Failure> {
    if threads <= 1 {
        // Four trajectories per network pass share each weight tile.
        let mut scratches = vec![Scratch::<4>::new()];
        return plan_with(&Serial, network, problem, guides, config, seed, &mut scratches);
    }
    let exec = Threads::new(threads).map_err(Failure::Input)?;
    // Three per pass: the 12 rows split evenly over 2, 4 (or 3) threads.
    let mut scratches: Vec<Scratch<3>> = (0..threads.min(ROWS)).map(|_| Scratch::new()).collect();
    plan_with(&exec, network, problem, guides, config, seed, &mut scratches)
}

fn plan_with<E: Executor, const C: usize, const J: usize>(
    exec: &E,
    network: &'static Network<J>,
    problem: &Problem<J>,
    guides: &[Guide],
    config: &PlanConfig,
    seed: u64,
    scratches: &mut [Scratch<C>],
) -> Result<Planned<J>, Failure> {
    let ik_began = Instant::now();
    let goal = joint_goal(problem).map_err(Failure::Input)?;
    let ik_ms = ik_began.elapsed().as_secs_f64() * 1e3;
    let mut work = Box::new(Workspace::<ROWS, HOST_SEARCH_NODES, J>::new());
    let req = Request {
        robot: problem.robot,
        network,
        scene: &problem.scene(),
        start: &problem.start,
        goal: &goal,
        guides,
        config,
    };
    let mut stopwatch = Stopwatch::default();
    let plan = plan_observed(exec, &req, &mut Rng::new(seed), scratches, &mut work, &mut stopwatch)
        .map_err(|e| Failure::Input(format!("planner: {e}")))?;
    let [denoise_ms, select_ms, global_ms, shortcut_ms] = stopwatch.ms;
    Ok(Planned {
        plan,
        ik_ms,
        denoise_ms,
        select_ms,
        global_ms,
        shortcut_ms,
    })
}

/// Milliseconds in each [`Phase`] of the core's pipeline, in its order.
#[derive(Default)]
struct Stopwatch {
    began: Option<Instant>,
    ms: [f64; 4],
}

impl Observer for Stopwatch {
    fn begin(&mut self, _: Phase) {
        self.began = Some(Instant::now());
    }

    fn end(&mut self, phase: Phase) {
        let slot = match phase {
            Phase::FirstStage => 0,
            Phase::Judge => 1,
            Phase::GlobalStage => 2,
            Phase::Shortcut => 3,
        };
        if let Some(began) = self.began.take() {
            self.ms[slot] += began.elapsed().as_secs_f64() * 1e3;
        }
    }
}

/// The guides named on the command line (all of EDMP's when none).
pub fn chosen_guides(ids: &[u8]) -> Result<Vec<Guide>, Failure> {
    if ids.is_empty() {
        return Ok(EDMP_GUIDES.to_vec());
    }
    let mut out = Vec::new();
    for id in ids {
        let guide = EDMP_GUIDES.iter().find(|g| g.id == *id).ok_or_else(|| {
            let known: Vec<String> = EDMP_GUIDES.iter().map(|g| g.id.to_string()).collect();
            Failure::Input(format!("--guides: no guide {id} (EDMP's are {})", known.join(", ")))
        })?;
        out.push(*guide);
    }
    if !ROWS.is_multiple_of(out.len()) {
        return Err(Failure::Input(format!(
            "--guides: {} guides do not divide the {ROWS} rows",
            out.len()
        )));
    }
    Ok(out)
}
