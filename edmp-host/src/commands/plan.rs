//! `edmp-host plan`: EDMP on one `edmp-scene/1` file, written as an `edmp-plan/1` plan
//! (docs/formats.md). Exit 0: the chosen trajectory passed the exact checker; 1: no
//! candidate did (the least colliding one is written, status "collision"); 2: bad input,
//! nothing written.

use crate::Failure;
use crate::formats::json::{parse_problem_for, scene_arm};
use crate::formats::plan::{add_trajectory, plan_document};
use crate::formats::trajectory::TimedArgs;
use crate::planning::{HOST_SEARCH_ATTEMPTS, HOST_SEARCH_ITERATIONS, chosen_guides, plan_problem_on};
use crate::with_arm;
use edmp_core::cost::boxes::BoxFrame;
use edmp_core::guidance::guides::{CLEARANCE_GUIDE, Guide, Schedule};
use edmp_core::planner::search::SearchConfig;
use edmp_core::planner::{
    DEFAULT_GRADIENT_STEPS, DEFAULT_REFINE_STEPS, DEFAULT_STEP_LIMIT, DEFAULT_STEPS, GlobalConfig, GuidanceSchedule,
    Judging, MAX_ATTEMPTS, PlanConfig, RefineStop,
};
use edmp_core::prior::{Network, Sampler};
use edmp_core::robot::Robot;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `edmp-host plan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene and problem (`edmp-scene/1` JSON).
    scene: PathBuf,
    /// Write the plan here instead of standard output.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Also write every candidate (multimodal output).
    #[arg(long)]
    candidates: bool,
    /// Use only these guides (the original's numbers, e.g. `11,18`); their count must divide 12.
    #[arg(long, value_delimiter = ',')]
    guides: Vec<u8>,
    #[command(flatten)]
    tuning: Tuning,
    #[command(flatten)]
    timed: TimedArgs,
}

/// The planner's knobs, shared by `plan` and `bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct Tuning {
    /// Denoising steps K of the strided sampler.
    #[arg(long, default_value_t = DEFAULT_STEPS)]
    steps: u16,
    /// Gradient steps of every guide after each denoising step (strided sampler).
    #[arg(long, default_value_t = DEFAULT_GRADIENT_STEPS)]
    gradient_steps: u8,
    /// Refinement gradient steps of every guide after the last denoising step (at t = 1): a
    /// budget that `--refine-check-every` may end early.
    #[arg(long, default_value_t = DEFAULT_REFINE_STEPS)]
    refine_steps: u8,
    /// Largest move of one joint in one gradient step, radians (`inf`: the original's
    /// unlimited step).
    #[arg(long, default_value_t = DEFAULT_STEP_LIMIT)]
    step_limit: f32,
    /// Cost every obstacle as its world AABB, as the original EDMP code (default: each
    /// obstacle and robot box pair in the obstacle's frame).
    #[arg(long)]
    world_boxes: bool,
    /// Without start/goal conditioning: the ends are written in only after the last denoising
    /// step (the paper's ablation).
    #[arg(long)]
    no_conditioning: bool,
    /// EDMP's original sampler and guidance: 255 ancestral steps, guidance on even t ≥ 6.
    #[arg(long)]
    ancestral: bool,
    /// Without the global stage: when no candidate is free, return the least colliding one
    /// (EDMP alone, as the paper) instead of searching and reseeding the prior.
    #[arg(long)]
    no_global: bool,
    /// Without shortening the free winner (shortcuts, resampling and smoothing over the exact
    /// checker): the path as the guides left it, as the paper.
    #[arg(long)]
    no_shortcut: bool,
    /// End the refinement early: check the rows not yet free with the exact checker before the
    /// first refinement step and every N steps after, stop moving the free ones, and stop once
    /// `--refine-stop-free` rows are free (0: every refinement step runs).
    #[arg(long, default_value_t = PlanConfig::DEFAULT.refine_stop.map_or(0, |s| s.every))]
    refine_check_every: u8,
    /// With `--refine-check-every`: how many free rows end the refinement (12 or more: all).
    #[arg(long, default_value_t = PlanConfig::DEFAULT.refine_stop.map_or(RefineStop::DEFAULT.free, |s| s.free))]
    refine_stop_free: u8,
    /// With `--refine-check-every`: end the refinement at a check once this many steps have
    /// passed since any row's guide cost last fell 5 % below its lowest (0: never).
    #[arg(long, default_value_t = PlanConfig::DEFAULT.refine_stop.map_or(0, |s| s.stall))]
    refine_stall: u8,
    /// Global stage: sampling iterations of the search before it gives up.
    #[arg(long, default_value_t = HOST_SEARCH_ITERATIONS)]
    search_iterations: u32,
    /// Global stage: nodes per search tree (the host holds at most 16384).
    #[arg(long, default_value_t = SearchConfig::DEFAULT.max_nodes)]
    search_nodes: u16,
    /// Global stage: random shortcut attempts on the search's raw path before it is resampled
    /// and reseeded.
    #[arg(long, default_value_t = SearchConfig::DEFAULT.shortcuts)]
    search_shortcuts: u32,
    /// Global stage: searches tried, each from fresh trees, until one finds a path (1-8).
    #[arg(long, default_value_t = HOST_SEARCH_ATTEMPTS, value_parser = clap::value_parser!(u8).range(1..=i64::from(MAX_ATTEMPTS)))]
    search_attempts: u8,
    /// Global stage: strided denoising steps of the prior from the search's path noised to
    /// step 50 (1-50), each followed by 4 gradient steps of every guide.
    #[arg(long, default_value_t = GlobalConfig::DEFAULT.steps)]
    global_steps: u16,
    /// Global stage: grow the search's trees from the ends alone (classical RRT-Connect), not
    /// also from the first stage's least colliding candidate. An ablation.
    #[arg(long)]
    no_search_seed: bool,
    /// Global stage: check every edge the search grows in full (classical RRT-Connect) instead
    /// of each new node alone and the edges only on a path between the roots (lazy, the default).
    #[arg(long)]
    eager_search: bool,
    /// Distinct draws of noise the 12 rows start from (row r: draw r mod N); the first
    /// denoising step runs the network once per draw. 12: a draw per row, as EDMP.
    #[arg(long, default_value_t = PlanConfig::DEFAULT.start_draws.min(12), value_parser = clap::value_parser!(u8).range(1..=12))]
    start_draws: u8,
    /// Waves the ensemble runs in, at most: the guides dealt into the most waves up to N that
    /// divide them evenly (wave w: guides w, w + N, … of the order given), a later wave
    /// denoised only when no candidate of the earlier ones is free. 1: one batch of every
    /// guide, as EDMP. Default 4; with `--candidates`, 1 (every alternative made).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=12))]
    waves: Option<u8>,
    /// Waves the first stage runs at most before the global stage takes over (default: all).
    /// An experiment in deciding earlier (docs/benchmark.md).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=12))]
    first_stage_waves: Option<u8>,
    /// A bound on the waves of the first stage and, apart, of the global stage's reseeding, in
    /// guide boxes × waves: a scene of B boxes runs at most max(1, N / B) of each (0: no
    /// bound; default: the arm's prior's, 24 for the Panda, none for the others).
    /// Bounds a plan's guided work on scenes of many boxes (docs/benchmark.md).
    #[arg(long)]
    wave_budget: Option<u16>,
    /// Weight of a smoothness term in every guide's step (the bending energy of the path;
    /// 0: EDMP's guides; below 0.125). An ablation (docs/benchmark.md).
    #[arg(long, default_value_t = 0.0)]
    smooth: f32,
    /// Step-size control in the refinement: a step that raised a guide's cost is undone and
    /// its step halves (default: EDMP's fixed steps). An ablation.
    #[arg(long)]
    step_control: bool,
    /// Judge every candidate with the exact checker, not only as many as the winner needs (in
    /// order of swept volume up to the first free one): the same plan, with a verdict on every
    /// alternative. `plan --candidates` always does.
    #[arg(long)]
    judge_every: bool,
    /// Refine every row with the exact-clearance guide (the checker's hulls against the true
    /// obstacles, within this clearance in metres; 0.03 when given without a value) instead of
    /// its own guide. An ablation.
    #[arg(long, num_args = 0..=1, default_missing_value = "0.03", value_name = "METRES")]
    refine_clearance: Option<f32>,
    /// Plan on this many threads (the network's batch, the guides and the refinement's checks
    /// split among them): the same plan, bit for bit, as on one.
    #[arg(long, default_value_t = 1)]
    threads: usize,
}

impl Tuning {
    /// Threads per plan (`--threads`, at least 1).
    pub fn threads(&self) -> Result<usize, Failure> {
        match self.threads {
            0 => Err(Failure::Input(
                "--threads: 0 threads cannot plan (at least 1)".to_owned(),
            )),
            n => Ok(n),
        }
    }

    /// The guides named by `ids` ([`chosen_guides`]) with this tuning's smoothness weight.
    pub fn guides(&self, ids: &[u8]) -> Result<Vec<Guide>, Failure> {
        if !(self.smooth.is_finite() && (0.0..0.125).contains(&self.smooth)) {
            return Err(Failure::Input(format!(
                "--smooth: {} outside 0 ≤ w < 0.125 (larger steps on the bending energy diverge)",
                self.smooth
            )));
        }
        let mut guides = chosen_guides(ids)?;
        for g in &mut guides {
            g.smooth = self.smooth;
        }
        Ok(guides)
    }

    /// The core's configuration, or the bad flag.
    pub fn config(&self) -> Result<PlanConfig, Failure> {
        let config = PlanConfig {
            sampler: if self.ancestral {
                Sampler::Ancestral
            } else {
                Sampler::Strided { steps: self.steps }
            },
            guidance: if self.ancestral {
                GuidanceSchedule::EvenSteps
            } else {
                GuidanceSchedule::Every {
                    per_step: self.gradient_steps,
                }
            },
            condition: !self.no_conditioning,
            refine: self.refine_steps,
            step_limit: self.step_limit,
            frame: if self.world_boxes {
                BoxFrame::World
            } else {
                BoxFrame::Obstacle
            },
            global: if self.no_global {
                None
            } else {
                Some(GlobalConfig {
                    search: SearchConfig {
                        max_iterations: self.search_iterations,
                        max_nodes: self.search_nodes,
                        shortcuts: self.search_shortcuts,
                        lazy: !self.eager_search,
                        ..SearchConfig::DEFAULT
                    },
                    attempts: self.search_attempts,
                    seeded: !self.no_search_seed,
                    steps: self.global_steps,
                    ..GlobalConfig::DEFAULT
                })
            },
            shortcut: if self.no_shortcut {
                None
            } else {
                PlanConfig::DEFAULT.shortcut
            },
            refine_stop: (self.refine_check_every > 0).then_some(RefineStop {
                every: self.refine_check_every,
                free: self.refine_stop_free,
                stall: self.refine_stall,
            }),
            refine_guide: self.refine_clearance.map(|c| Guide {
                clearance: Schedule::Constant(c),
                ..CLEARANCE_GUIDE
            }),
            step_control: self.step_control,
            // 12 is a draw per row, which the core spells u8::MAX (any batch size).
            start_draws: if self.start_draws >= 12 {
                u8::MAX
            } else {
                self.start_draws
            },
            waves: self.waves.unwrap_or(PlanConfig::DEFAULT.waves),
            first_stage_waves: self.first_stage_waves.unwrap_or(PlanConfig::DEFAULT.first_stage_waves),
            wave_budget: self.wave_budget.map(|n| if n == 0 { u16::MAX } else { n }),
            judging: if self.judge_every {
                Judging::Every
            } else {
                Judging::Winner
            },
            ..PlanConfig::DEFAULT
        };
        if self.step_limit.is_nan() || self.step_limit <= 0.0 {
            return Err(Failure::Input(format!(
                "--step-limit: {} is not a positive number of radians",
                self.step_limit
            )));
        }
        if let Some(c) = self.refine_clearance
            && !(c.is_finite() && c >= 0.0)
        {
            return Err(Failure::Input(format!(
                "--refine-clearance: {c} is not a clearance in metres (finite, at least 0)"
            )));
        }
        if !(1..=GlobalConfig::DEFAULT.noise_step).contains(&self.global_steps) {
            return Err(Failure::Input(format!(
                "--global-steps: {} outside 1..={}",
                self.global_steps,
                GlobalConfig::DEFAULT.noise_step
            )));
        }
        if self.refine_check_every > 0 && self.refine_stop_free == 0 {
            return Err(Failure::Input(
                "--refine-stop-free: 0 free rows cannot end the refinement (at least 1)".to_owned(),
            ));
        }
        config.sampler.validate().map_err(|_| {
            Failure::Input(format!(
                "--steps: {} outside 1..={}",
                self.steps,
                edmp_core::prior::STEPS
            ))
        })?;
        Ok(config)
    }

    /// A short label for tables.
    pub fn label(&self) -> String {
        let boxes = match (self.world_boxes, self.no_conditioning) {
            (false, false) => "",
            (true, false) => ", world AABBs",
            (false, true) => ", no conditioning",
            (true, true) => ", world AABBs, no conditioning",
        };
        let limit = if self.step_limit.is_finite() {
            format!("step limit {} rad", self.step_limit)
        } else {
            "no step limit".to_owned()
        };
        let defaults = (
            HOST_SEARCH_ITERATIONS,
            SearchConfig::DEFAULT.max_nodes,
            SearchConfig::DEFAULT.shortcuts,
            HOST_SEARCH_ATTEMPTS,
        );
        let search = (
            self.search_iterations,
            self.search_nodes,
            self.search_shortcuts,
            self.search_attempts,
        );
        let boxes = if self.no_global {
            format!("{boxes}, no global stage")
        } else if search != defaults {
            format!(
                "{boxes}, search {} iterations × {} nodes, {} shortcuts, {} attempts",
                search.0, search.1, search.2, search.3
            )
        } else {
            boxes.to_owned()
        };
        let boxes = if self.no_search_seed && !self.no_global {
            format!("{boxes}, unseeded search")
        } else {
            boxes
        };
        let boxes = if self.eager_search && !self.no_global {
            format!("{boxes}, eager search")
        } else {
            boxes
        };
        let boxes = if self.global_steps != GlobalConfig::DEFAULT.steps && !self.no_global {
            format!("{boxes}, {} reseeding steps", self.global_steps)
        } else {
            boxes
        };
        let boxes = if self.start_draws < 12 {
            format!("{boxes}, {} start draws", self.start_draws)
        } else {
            boxes
        };
        let boxes = match self.waves {
            Some(1) => format!("{boxes}, one batch"),
            Some(n) if n != PlanConfig::DEFAULT.waves => format!("{boxes}, {n} waves"),
            _ => boxes,
        };
        let boxes = match self.first_stage_waves {
            Some(n) => format!("{boxes}, first stage at most {n} waves"),
            None => boxes,
        };
        let boxes = match self.wave_budget {
            Some(0) => format!("{boxes}, no wave budget"),
            Some(n) => format!("{boxes}, wave budget {n} boxes × waves"),
            None => boxes,
        };
        let boxes = if self.no_shortcut {
            format!("{boxes}, no shortcut")
        } else {
            boxes
        };
        let stop = (self.refine_check_every, self.refine_stop_free);
        let default_stop = PlanConfig::DEFAULT
            .refine_stop
            .map_or((0, RefineStop::DEFAULT.free), |s| (s.every, s.free));
        let boxes = if stop == default_stop {
            boxes
        } else if self.refine_check_every == 0 {
            format!("{boxes}, every refinement step runs")
        } else {
            format!(
                "{boxes}, refinement checked every {} steps, ends at {} free",
                self.refine_check_every, self.refine_stop_free
            )
        };
        let mut boxes = boxes;
        if self.smooth > 0.0 {
            boxes = format!("{boxes}, smoothness {}", self.smooth);
        }
        if self.step_control {
            boxes = format!("{boxes}, step control");
        }
        if let Some(c) = self.refine_clearance {
            boxes = format!("{boxes}, clearance refinement ({c} m)");
        }
        if self.threads > 1 {
            boxes = format!("{boxes}, {} threads", self.threads);
        }
        if self.ancestral {
            format!(
                "ancestral K = 255, guidance on even t, {} refinement steps, {limit}{boxes}",
                self.refine_steps
            )
        } else {
            format!(
                "strided K = {}, {} gradient steps per step, {} refinement steps, {limit}{boxes}",
                self.steps, self.gradient_steps, self.refine_steps
            )
        }
    }
}

/// Plans for the arm the scene names (`robot`) and writes the plan.
pub fn run(args: &Args) -> Result<(), Failure> {
    let began = Instant::now();
    let text =
        std::fs::read_to_string(&args.scene).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    let in_file = |e: String| Failure::Input(format!("{}: {e}", args.scene.display()));
    let arm = scene_arm(&text).map_err(|e| in_file(e.to_string()))?;
    with_arm!(arm, robot, network => plan_for(args, began, &text, robot, network)).map_err(in_file)?
}

fn plan_for<const J: usize>(
    args: &Args,
    began: Instant,
    text: &str,
    robot: &'static Robot<f32, J>,
    network: &'static Network<J>,
) -> Result<(), Failure> {
    let dir = args.scene.parent().unwrap_or(std::path::Path::new("."));
    let problem =
        parse_problem_for(text, dir, robot).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    let guides = args.tuning.guides(&args.guides)?;
    let mut config = args.tuning.config()?;
    if args.candidates {
        // Every alternative written gets its verdict, and every one is made unless the waves
        // were asked for.
        config.judging = Judging::Every;
        config.waves = args.tuning.waves.unwrap_or(1);
    }
    let timed = args.timed.request()?;

    let planned = plan_problem_on(network, &problem, &guides, &config, args.seed, args.tuning.threads()?)?;
    let total_ms = began.elapsed().as_secs_f64() * 1e3;
    let mut out = plan_document(
        &problem,
        &planned,
        &guides,
        &config,
        args.seed,
        args.candidates,
        total_ms,
    )?;
    let plan = &planned.plan;
    if let Some(request) = &timed
        && !add_trajectory(&mut out, &problem, plan, &config, request)?
    {
        eprintln!("edmp-host: no trajectory: the plan collides, so it is not timed");
    }
    let text = serde_json::to_string_pretty(&out).map_err(|e| Failure::Input(e.to_string()))? + "\n";
    crate::commands::write_document(args.output.as_deref(), &text).map_err(Failure::Input)?;
    if plan.is_free() {
        Ok(())
    } else {
        Err(Failure::NoPath(format!(
            "no collision-free candidate; wrote the least colliding one ({} colliding states)",
            plan.verdicts[plan.best].colliding_states
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, clap::Parser)]
    struct Cli {
        #[command(flatten)]
        tuning: Tuning,
    }

    #[test]
    fn the_flags_default_to_the_hosts_shipped_configuration() {
        let cli = Cli::parse_from(["edmp-host"]);
        assert!(cli.tuning.config().is_ok_and(|c| c == crate::planning::HOST_CONFIG));
        let cli = Cli::parse_from(["edmp-host", "--step-limit", "0"]);
        assert!(cli.tuning.config().is_err());
        for steps in ["0", "51"] {
            let cli = Cli::parse_from(["edmp-host", "--global-steps", steps]);
            assert!(cli.tuning.config().is_err(), "--global-steps {steps}");
        }
    }

    #[test]
    fn waves_default_to_the_cores_and_stay_within_1_to_12() {
        let waves = |args: &[&str]| {
            let cli = Cli::parse_from([&["edmp-host"][..], args].concat());
            cli.tuning.config().map(|c| c.waves)
        };
        assert_eq!(waves(&[]).ok(), Some(PlanConfig::DEFAULT.waves));
        assert_eq!(waves(&["--waves", "1"]).ok(), Some(1));
        assert_eq!(waves(&["--waves", "5"]).ok(), Some(5));
        assert!(Cli::try_parse_from(["edmp-host", "--waves", "0"]).is_err());
        assert!(Cli::try_parse_from(["edmp-host", "--waves", "13"]).is_err());
    }
}
