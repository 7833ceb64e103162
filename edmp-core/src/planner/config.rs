//! Everything the planner is told besides the problem: the sampler, the guidance schedule, the
//! refinement and its early stop, how candidates are judged, the global stage and shortening.
//! [`PlanConfig::DEFAULT`] is the shipped tuning; the other values are the paper's settings or
//! ablations, each measured in docs/benchmark.md.

use crate::collision::checker::CheckConfig;
use crate::cost::boxes::{BoxFrame, CylinderBox};
use crate::error::Error;
use crate::guidance::guides::Guide;
use crate::planner::search::SearchConfig;
use crate::planner::shortcut::ShortcutConfig;
use crate::prior::{STEPS, Sampler};

/// When guidance runs and how often.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GuidanceSchedule {
    /// The original: one gradient step after every denoising step with an even t ≥ 6 (125 of
    /// the 255 ancestral steps).
    EvenSteps,
    /// `per_step` gradient steps after every denoising step with t ≥ 5 (for strided samplers,
    /// whose steps each stand for several of the original's).
    Every {
        /// Gradient steps per denoising step.
        per_step: u8,
    },
}

impl GuidanceSchedule {
    /// Gradient steps after the denoising step at `t`.
    pub fn steps_at(&self, t: u16) -> u8 {
        match *self {
            Self::EvenSteps => u8::from(t.is_multiple_of(2) && t >= 6),
            Self::Every { per_step } => {
                if t >= 5 {
                    per_step
                } else {
                    0
                }
            }
        }
    }
}

/// Everything the planner needs besides the scene and the ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanConfig {
    /// How the prior walks from noise to trajectories.
    pub sampler: Sampler,
    /// When the guides act.
    pub guidance: GuidanceSchedule,
    /// EDMP's start/goal conditioning: the ends are written in after every denoising step.
    /// `false` is the paper's unconditioned ablation: they are written in only after the last
    /// denoising step (before the refinement).
    pub condition: bool,
    /// Gradient steps of every guide after the last denoising step, with each guide's schedule
    /// at t = 1 (no expansion, its own clearance and step size): a deviation from the original,
    /// which stops at the last denoising step; measured in docs/benchmark.md.
    pub refine: u8,
    /// Largest move of one joint of one waypoint in one gradient step, radians
    /// (`f32::INFINITY`: the original, unlimited). A deviation: unlimited, the unnormalized
    /// swept-volume guide (10) throws trajectories across the workspace; measured in docs/benchmark.md.
    pub step_limit: f32,
    /// How cylinders are boxed for the costs.
    pub cylinder: CylinderBox,
    /// The frame the costs box each obstacle and robot box pair in (a deviation from the
    /// original's world AABBs, measured in docs/benchmark.md).
    pub frame: BoxFrame,
    /// The exact checker's settings for the final judgement.
    pub check: CheckConfig,
    /// The global stage when no candidate is free (`None`: EDMP alone, as the paper).
    pub global: Option<GlobalConfig>,
    /// Shortening of the free winner over the exact checker ([`crate::planner::shortcut`]; `None`: the
    /// winner as the guides left it, as the paper).
    pub shortcut: Option<ShortcutConfig>,
    /// Ending the refinement early on the exact checker's word ([`RefineStop`]; `None`: every
    /// refinement step runs, as in EDMP's fixed schedule).
    pub refine_stop: Option<RefineStop>,
    /// The guide every row follows in the refinement (`None`: each row its own, as EDMP; e.g.
    /// [`crate::guidance::guides::CLEARANCE_GUIDE`], the exact-clearance ablation, docs/benchmark.md).
    pub refine_guide: Option<Guide>,
    /// Step-size control in the refinement ([`StepControl`](crate::guidance::StepControl): a step that raised a guide's cost
    /// is undone and its step halves; `false`: EDMP's fixed steps). An ablation.
    pub step_control: bool,
    /// Which candidates the exact checker judges ([`Judging`]).
    pub judging: Judging,
    /// Distinct draws of noise the rows start from (1 ..= B; B or more: a draw per row, as
    /// EDMP; 0 counts as 1): row `r` starts from draw `r mod start_draws`. The first denoising step then
    /// runs the network once per draw, not once per row; rows that share a draw part at its
    /// update, which adds noise of its own to each (at K = 3, t = 255 → 170: β' z with
    /// β' = 0.76), and at their guides. Each row alone is still a sample of the same process;
    /// what is given up is the independence of rows in the first step (diversity: ACSM).
    pub start_draws: u8,
    /// Waves the ensemble runs in, at most (1: one batch of every guide, as EDMP; 0 is refused).
    /// The guides are dealt into the most waves up to this that divide them evenly
    /// ([`PlanConfig::waves_for`]; wave `w`: the guides `w`, `w + waves`, … of the caller's
    /// order) and each wave is denoised and refined on its own; a later wave runs only when no
    /// candidate of the earlier ones is free. A plan that the first wave solves costs that
    /// wave's share of the work; its other candidates are not made ([`Verdict::made`](crate::planner::Verdict::made)). The
    /// default, 4 (three of EDMP's guides a wave, guides 1, 5 and 14 first), is a deviation
    /// from the paper, measured in docs/benchmark.md.
    pub waves: u8,
    /// Waves the first stage runs at most before the global stage takes over (0 is refused;
    /// `u8::MAX`: all of them). Fewer decide earlier that the prior's basin holds no free row:
    /// the waves left unrun are work that a plan bound for the global stage never pays, and
    /// whatever they would have freed is left to the global stage. The global stage's
    /// reseeding always runs all its waves.
    pub first_stage_waves: u8,
    /// A bound on the waves the first stage and, apart, the global stage's reseeding run, in
    /// guide boxes × waves (`None`: the prior's own, [`Network::wave_budget`](crate::prior::Network::wave_budget);
    /// `u16::MAX`: no bound in practice). A wave's work grows with the boxes its guides cost,
    /// so a scene of many boxes runs fewer waves of the first stage before the global stage
    /// takes over, and fewer reseeding waves before the search's own path is kept; at least
    /// one wave of each always runs ([`waves_within`]). Each wave's own work is bounded by its
    /// steps, so this bounds the plan's guided work.
    pub wave_budget: Option<u16>,
}

/// Which candidates the exact checker judges once the guides are done. The winner, its path
/// and its verdict are the same bits either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Judging {
    /// Every candidate gets a verdict: the multimodal output with every alternative judged
    /// (`plan --candidates`, the ensemble studies of docs/benchmark.md).
    Every,
    /// Only what the winner needs. [`judge`](crate::planner::judge) takes the candidates in order of swept volume
    /// (the lowest row on ties) and stops at the first free one, which is the candidate
    /// [`Judging::Every`] picks; the candidates after it keep `checked: false`. When none is
    /// free, every candidate is judged. The refinement's early stop likewise checks its rows
    /// one after the other (`Executor::parts` at a time) and stops at the certificate that
    /// ends it. A free candidate is checked state by state to the end, so each one skipped
    /// saves a whole trajectory's check.
    Winner,
}

/// When the refinement may end early: the exact checker certifies rows free (judged as
/// [`judge`](crate::planner::judge) will judge them: clamped into the soft limits, ends exact), a certified row's guide
/// stops moving it once all its rows are certified, and the refinement ends once `free` rows are
/// certified. A deviation from the original (which refines a fixed number of steps), measured
/// in docs/benchmark.md: the rows that are free already stop paying for steps, and the ones that
/// are not keep the whole budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RefineStop {
    /// Check the rows not yet certified before the first refinement step and then every
    /// `every` steps (at least 1).
    pub every: u8,
    /// End the refinement once this many rows are certified free (at least 1; the batch size or
    /// more: only when all are).
    pub free: u8,
    /// End the refinement, at a check that certifies too few rows, once this many steps have
    /// passed since any row's guide cost last fell below [`STALL_RATIO`] of its lowest so far
    /// (0: never). Rows stuck in a basin bounce at full step length without getting lower;
    /// the global stage then gets the problem sooner.
    pub stall: u8,
}

/// How far below its lowest cost so far a row must get to count as progress for
/// [`RefineStop::stall`].
pub const STALL_RATIO: f32 = 0.95;

impl RefineStop {
    /// The shipped setting (docs/benchmark.md, "Ending the refinement early": the stall stop
    /// keeps the first stage's solves on both suites and hands the rest to the global stage
    /// sooner).
    pub const DEFAULT: Self = Self {
        every: 8,
        free: 1,
        stall: 16,
    };
}

/// Denoising steps of the shipped configuration ([`PlanConfig::DEFAULT`]): three network
/// evaluations per row, the network being the largest share of a plan's work
/// (docs/benchmark.md, "Three denoising steps").
pub const DEFAULT_STEPS: u16 = 3;

/// Gradient steps per denoising step of the shipped configuration (4 with five denoising
/// steps; six with three keep the first stage's solves: 18 guided steps instead of 20).
pub const DEFAULT_GRADIENT_STEPS: u8 = 6;

/// Per-joint limit of one gradient step in the shipped configuration, radians.
pub const DEFAULT_STEP_LIMIT: f32 = 0.1;

/// Refinement gradient steps after the last denoising step in the shipped configuration: a
/// budget, which [`RefineStop::DEFAULT`] ends as soon as a row is certified free
/// (docs/benchmark.md, "Ending the refinement early").
pub const DEFAULT_REFINE_STEPS: u8 = 96;

impl PlanConfig {
    /// The waves `guides` guides run in: the most, up to [`PlanConfig::waves`], that divide
    /// them evenly (12 guides: 4 → 4, 5 → 4; 2 guides: 4 → 2; 1 guide: 1).
    pub fn waves_for(&self, guides: usize) -> Result<usize, Error> {
        let most = usize::from(self.waves).min(guides);
        (1..=most)
            .rev()
            .find(|w| guides.is_multiple_of(*w))
            .ok_or(Error::BadParameter)
    }

    /// The shipped configuration, picked from the suite measurements in docs/benchmark.md: the
    /// strided sampler with [`DEFAULT_STEPS`] steps, [`DEFAULT_GRADIENT_STEPS`] gradient steps
    /// after each, [`DEFAULT_REFINE_STEPS`] refinement steps, moves limited to
    /// [`DEFAULT_STEP_LIMIT`], enclosing boxes for cylinders, obstacle-frame boxes, the
    /// project's checker, the guides in four waves.
    pub const DEFAULT: Self = Self {
        sampler: Sampler::Strided { steps: DEFAULT_STEPS },
        guidance: GuidanceSchedule::Every {
            per_step: DEFAULT_GRADIENT_STEPS,
        },
        condition: true,
        refine: DEFAULT_REFINE_STEPS,
        step_limit: DEFAULT_STEP_LIMIT,
        cylinder: CylinderBox::Enclosing,
        frame: BoxFrame::Obstacle,
        check: CheckConfig::DEFAULT,
        global: Some(GlobalConfig::DEFAULT),
        shortcut: Some(ShortcutConfig::DEFAULT),
        refine_stop: Some(RefineStop::DEFAULT),
        refine_guide: None,
        step_control: false,
        judging: Judging::Winner,
        start_draws: u8::MAX,
        waves: 4,
        first_stage_waves: u8::MAX,
        wave_budget: None,
    };
}

/// The Panda prior's wave budget ([`PlanConfig::wave_budget`]), guide boxes × waves: a scene
/// of up to 6 boxes runs all four waves of each stage, 7-8 boxes three, 9-12 two, more one
/// (chosen on the Panda's in-distribution suite, where it lowered p95 and p99 the most without
/// moving the median; docs/benchmark.md, "Bounding the waves"). The other arms' priors free
/// fewer rows per wave and run every wave.
pub const WAVE_BUDGET: u16 = 24;

/// The waves one stage may run under `budget` (guide boxes × waves) in a scene whose guides
/// cost `boxes` boxes: at least 1; `usize::MAX` without a budget.
pub fn waves_within(budget: Option<u16>, boxes: usize) -> usize {
    budget.map_or(usize::MAX, |budget| (usize::from(budget) / boxes.max(1)).max(1))
}

/// The most searches [`GlobalConfig::attempts`] allows: a bound on the global stage's work.
pub const MAX_ATTEMPTS: u8 = 8;

/// Settings of the global stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalConfig {
    /// The search's budget, per attempt.
    pub search: SearchConfig,
    /// Searches tried, each from fresh trees and further on the random stream, until one finds
    /// a path (1 ..= [`MAX_ATTEMPTS`]). RRT-Connect's work to a narrow passage is a lottery: on
    /// the hardest unseen problem (window_box/080) one search of the default budget fails for
    /// 2-3 seeds in 16, its trees full before they meet; a second one mostly finds it. Only a
    /// problem whose first search failed pays for another (docs/benchmark.md measures the
    /// default).
    pub attempts: u8,
    /// Diffusion step the search path is noised to before the prior denoises it (1 ..=
    /// `STEPS`): high enough that the prior reshapes it, low enough that it keeps its route.
    pub noise_step: u16,
    /// Strided denoising steps from `noise_step` down (1 ..= `noise_step`).
    pub steps: u16,
    /// Gradient steps of every guide after each of those denoising steps.
    pub per_step: u8,
    /// Refinement gradient steps at t = 1 afterwards.
    pub refine: u8,
    /// Whether each search starts from the first stage's candidate with the lowest swept
    /// volume as well as from the ends ([`search_from`](crate::planner::search::search_from)): the trees take its free stretches
    /// from either end, and the search bridges what lies between. `false`: trees from the ends
    /// alone, as classical RRT-Connect.
    pub seeded: bool,
}

impl GlobalConfig {
    /// The shipped setting (measured in docs/benchmark.md).
    pub const DEFAULT: Self = Self {
        search: SearchConfig::DEFAULT,
        attempts: 4,
        noise_step: 50,
        steps: 1,
        per_step: 4,
        refine: 24,
        seeded: true,
    };

    pub(crate) fn validate(&self) -> Result<(), Error> {
        let ok = self.noise_step >= 1
            && usize::from(self.noise_step) <= STEPS
            && self.steps >= 1
            && self.steps <= self.noise_step
            && (1..=MAX_ATTEMPTS).contains(&self.attempts);
        if ok { Ok(()) } else { Err(Error::BadParameter) }
    }
}
