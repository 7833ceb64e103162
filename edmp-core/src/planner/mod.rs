//! EDMP's Algorithm 2 on a fixed batch: denoise `B` trajectories together, after each denoising
//! step let every row follow its guide, then judge every candidate with the exact checker and
//! keep the free one with the lowest swept volume.
//!
//! When no candidate is free, the bounded global stage ([`crate::planner::global`]) searches for a
//! path and hands it back to the prior.
//!
//! Fixed work: the number of network forwards and cost gradients is set by the sampler, the
//! guidance schedule and `B`, never by the scene's luck; the checker's states are bounded by
//! the path length (at most `MAX_STEPS_PER_SEGMENT` per segment, each candidate checked at
//! most twice: once to its first contact, once in full when no candidate is free). The global
//! stage adds a bounded amount on top ([`crate::planner::global`] states it).

pub mod global;
pub mod search;
pub mod shortcut;

use crate::collision::checker::{CheckConfig, check_trajectory, check_trajectory_from};
use crate::cost::boxes::{BoxFrame, CylinderBox, Inflation};
use crate::cost::{CostConfig, CostKind, CostMemo, trajectory_cost};
use crate::error::Error;
use crate::executor::{Executor, Serial};
use crate::guidance::guides::Guide;
use crate::guidance::{StepControl, StepRule, guide_step_controlled, guide_step_on};
use crate::path::{HORIZON, Path};
use crate::planner::global::{GlobalConfig, SearchReport, Stage, rescue};
use crate::planner::search::SearchSpace;
use crate::planner::shortcut::{ShortcutConfig, ShortcutReport, shorten};
use crate::prior::{
    Sampler, Scratch, TimeEmbedding, check_joints, free_ends, initial_noise, inpaint, predict_noise_on,
};
use crate::rng::Rng;
use crate::robot::kinematics::Joints;
use crate::robot::{JOINTS, PANDA};
use crate::scene::Scene;

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
    /// which stops at the last denoising step; measured in the README.
    pub refine: u8,
    /// Largest move of one joint of one waypoint in one gradient step, radians
    /// (`f32::INFINITY`: the original, unlimited). A deviation: unlimited, the unnormalized
    /// swept-volume guide (10) throws trajectories across the workspace; measured in the README.
    pub step_limit: f32,
    /// How cylinders are boxed for the costs.
    pub cylinder: CylinderBox,
    /// The frame the costs box each obstacle and robot box pair in (a deviation from the
    /// original's world AABBs, measured in the README).
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
    /// Step-size control in the refinement ([`StepControl`]: a step that raised a guide's cost
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
    /// wave's share of the work; its other candidates are not made ([`Verdict::made`]). The
    /// default, 4 (three of EDMP's guides a wave, guides 1, 5 and 14 first), is a deviation
    /// from the paper, measured in docs/benchmark.md (tenth session).
    pub waves: u8,
}

/// Which candidates the exact checker judges once the guides are done. The winner, its path
/// and its verdict are the same bits either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Judging {
    /// Every candidate gets a verdict: the multimodal output with every alternative judged
    /// (`plan --candidates`, the ensemble studies of docs/benchmark.md).
    Every,
    /// Only what the winner needs. [`judge`] takes the candidates in order of swept volume
    /// (the lowest row on ties) and stops at the first free one, which is the candidate
    /// [`Judging::Every`] picks; the candidates after it keep `checked: false`. When none is
    /// free, every candidate is judged. The refinement's early stop likewise checks its rows
    /// one after the other (`Executor::parts` at a time) and stops at the certificate that
    /// ends it. A free candidate is checked state by state to the end, so each one skipped
    /// saves a whole trajectory's check.
    Winner,
}

/// When the refinement may end early: the exact checker certifies rows free (judged as
/// [`judge`] will judge them: clamped into the soft limits, ends exact), a certified row's guide
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
    /// The shipped setting (docs/benchmark.md, "Ending the refinement early"; the stall stop
    /// since the ninth session: the same first-stage solves on both suites, a sooner global
    /// stage for the rest).
    pub const DEFAULT: Self = Self {
        every: 8,
        free: 1,
        stall: 16,
    };
}

/// One candidate's verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// Swept volume of the final trajectory against the uninflated obstacles (m³·segments).
    pub swept: f32,
    /// Whether the exact checker judged this candidate; `false` only under
    /// [`Judging::Winner`], for candidates after the winner in order of swept volume (then
    /// `free` is `false` and `colliding_states` is `u32::MAX`: unknown, never picked).
    pub checked: bool,
    /// Whether the exact checker found no contact anywhere along the trajectory.
    pub free: bool,
    /// States the exact checker found in contact. Counted in full only when no candidate is
    /// free (the fallback ranks by it); otherwise the check of a colliding candidate stops at
    /// its first contact and this is 1. 0 exactly when `free`.
    pub colliding_states: u32,
    /// Whether the planner made this candidate: `false` only for the rows of waves that did
    /// not run ([`PlanConfig::waves`]); then the path is all zeros, `checked` and `free` are
    /// `false`, `swept` is +∞ and `colliding_states` is `u32::MAX`, and it is never picked.
    pub made: bool,
}

/// The planner's output: every candidate (row `r` followed guide `r / k`), its verdict, and the
/// chosen one.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan<const B: usize> {
    /// The candidates, each inside the soft joint limits, starting at the start and ending at
    /// the goal.
    pub paths: [Path; B],
    /// The checker's and the swept cost's verdict on each.
    pub verdicts: [Verdict; B],
    /// Index of the chosen candidate: the free one with the lowest swept volume (lowest index on
    /// ties), or, if none is free, the one with the fewest colliding states (then swept volume).
    pub best: usize,
    /// Which stage produced the chosen candidate. After the global stage, `paths` are its
    /// reseeded candidates, and with [`Stage::Search`] row `best` holds the search path.
    pub stage: Stage,
    /// What the global stage's search did, when it ran.
    pub search: Option<SearchReport>,
    /// What shortening did to the chosen candidate, when it ran (a free plan with
    /// `PlanConfig::shortcut`).
    pub shortcut: Option<ShortcutReport>,
}

/// Denoising steps of the shipped configuration ([`PlanConfig::DEFAULT`]): three network
/// evaluations per row (5 until 2026-12-02, ninth session: the network was 60 % of a median
/// plan's instructions; the unguided prior's roughness rises from 0.096 to 0.141 rad, the plans'
/// after shortening from 0.071 to 0.073; docs/benchmark.md, "Three denoising steps").
pub const DEFAULT_STEPS: u16 = 3;

/// Gradient steps per denoising step of the shipped configuration (4 with five denoising
/// steps; six with three keep the first stage's solves: 18 guided steps instead of 20).
pub const DEFAULT_GRADIENT_STEPS: u8 = 6;

/// Per-joint limit of one gradient step in the shipped configuration, radians.
pub const DEFAULT_STEP_LIMIT: f32 = 0.1;

/// Refinement gradient steps after the last denoising step in the shipped configuration: a
/// budget, which [`RefineStop::DEFAULT`] ends as soon as a row is certified free (48 steps,
/// every one of them run, until 2026-12-01; docs/benchmark.md, "Ending the refinement early").
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

    /// The shipped configuration, picked from the suite measurements in the README: the
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
    };
}

impl<const B: usize> Plan<B> {
    /// Zero candidates, not yet judged: the memory a plan is built in.
    pub const fn empty() -> Self {
        Self {
            paths: [[[0.0; JOINTS]; HORIZON]; B],
            verdicts: [Verdict {
                swept: 0.0,
                checked: false,
                free: false,
                colliding_states: 0,
                made: true,
            }; B],
            best: 0,
            stage: Stage::None,
            search: None,
            shortcut: None,
        }
    }

    /// Whether the chosen candidate passed the exact checker.
    pub fn is_free(&self) -> bool {
        self.verdicts.get(self.best).is_some_and(|v| v.free)
    }

    /// FNV-1a (64 bit) over the bits of every candidate, every verdict and the chosen index:
    /// equal fingerprints on two machines mean the same plan, bit for bit.
    pub fn fingerprint(&self) -> u64 {
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |word: u32| {
            for byte in word.to_le_bytes() {
                hash = (hash ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for path in &self.paths {
            for v in path.iter().flatten() {
                eat(v.to_bits());
            }
        }
        for verdict in &self.verdicts {
            eat(verdict.swept.to_bits());
            eat(u32::from(verdict.checked));
            eat(u32::from(verdict.free));
            eat(verdict.colliding_states);
        }
        eat(self.best as u32);
        eat(self.stage as u32);
        if let Some(s) = &self.shortcut {
            eat(s.length_after.to_bits());
        }
        hash
    }
}

/// Nodes per tree of the global stage's search in the default [`Workspace`].
pub const DEFAULT_SEARCH_NODES: usize = 512;

/// Working memory of the planner for `B` rows (gradients and noise predictions) and of the
/// global stage's search (`CAP` nodes per tree).
#[derive(Debug)]
pub struct Workspace<const B: usize, const CAP: usize = DEFAULT_SEARCH_NODES> {
    pub(crate) eps: [Path; B],
    pub(crate) grads: [Path; B],
    /// What the refinement's checks learned of each row, for the judge ([`RefineStop`]).
    pub checks: RowChecks<B>,
    pub(crate) search: SearchSpace<CAP>,
}

impl<const B: usize, const CAP: usize> Default for Workspace<B, CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize, const CAP: usize> Workspace<B, CAP> {
    /// Zeroed working memory (`const`: it can live in a `static`).
    pub const fn new() -> Self {
        Self {
            eps: [[[0.0; JOINTS]; HORIZON]; B],
            grads: [[[0.0; JOINTS]; HORIZON]; B],
            checks: RowChecks::NONE,
            search: SearchSpace::new(),
        }
    }
}

/// What the refinement's checks ([`RefineStop`]) learned of each row, for the judge: a row
/// certified free and not moved since need not be checked again, and a row that touched is
/// walked from the segment where it last did (where it most likely touches still; whether it
/// is free does not depend on where the walk starts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RowChecks<const B: usize> {
    /// Certified free, in the form the judge checks (clamped, ends exact), and not moved since.
    pub free: [bool; B],
    /// The segment of each row's first contact at its last check.
    pub touched: [Option<u16>; B],
    /// Rows of waves that did not run ([`PlanConfig::waves`]): no candidate, nothing to judge.
    pub skipped: [bool; B],
}

impl<const B: usize> RowChecks<B> {
    /// Nothing known: the judge checks every row from its start.
    pub const NONE: Self = Self {
        free: [false; B],
        touched: [None; B],
        skipped: [false; B],
    };
}

/// Plans from `start` to `goal` in `scene` with `B` rows over `guides` (`B` a multiple of
/// `guides.len()`), drawing every random number from `rng`: the same inputs give the same bits.
/// [`denoise`] then [`select`], then [`finish`] and [`polish`].
#[allow(clippy::too_many_arguments)]
pub fn plan<const B: usize, const N: usize, const C: usize, const CAP: usize>(
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    work: &mut Workspace<B, CAP>,
) -> Result<Plan<B>, Error> {
    let scratches = core::slice::from_mut(scratch);
    plan_on(&Serial, scene, start, goal, guides, config, rng, scratches, work)
}

/// [`plan`] with the network's batch, the guides and the refinement's checks cut into parts
/// that `exec` runs (one part per scratch at most): the same bits as [`plan`] whatever the
/// executor ([`crate::executor`]).
#[allow(clippy::too_many_arguments)]
pub fn plan_on<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP>,
) -> Result<Plan<B>, Error> {
    // One plan's memory throughout: denoised into, judged in place, reseeded in place.
    let mut plan = Plan::empty();
    denoise_on(
        exec,
        scene,
        start,
        goal,
        guides,
        config,
        rng,
        scratches,
        work,
        &mut plan.paths,
    )?;
    judge(scene, start, goal, config, &mut plan, &work.checks)?;
    finish_on(
        exec, scene, start, goal, guides, config, rng, scratches, work, &mut plan,
    )?;
    polish(scene, start, goal, config, rng, &mut plan)?;
    Ok(plan)
}

/// After [`select`]: a plan with a free candidate is done; otherwise the global stage runs
/// when `config.global` asks for it ([`crate::planner::global::rescue`]), in place.
#[allow(clippy::too_many_arguments)]
pub fn finish<const B: usize, const N: usize, const C: usize, const CAP: usize>(
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    work: &mut Workspace<B, CAP>,
    plan: &mut Plan<B>,
) -> Result<(), Error> {
    let scratches = core::slice::from_mut(scratch);
    finish_on(&Serial, scene, start, goal, guides, config, rng, scratches, work, plan)
}

/// [`finish`] with its work run by `exec` ([`plan_on`]).
#[allow(clippy::too_many_arguments)]
pub fn finish_on<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP>,
    plan: &mut Plan<B>,
) -> Result<(), Error> {
    if let Some(global) = &config.global
        && !plan.is_free()
    {
        rescue(
            exec, scene, start, goal, guides, config, global, rng, scratches, work, plan,
        )?;
    }
    Ok(())
}

/// After [`finish`]: a free winner is shortened over the exact checker when `config.shortcut`
/// asks for it ([`crate::planner::shortcut::shorten`]), in place; its swept volume is recomputed.
pub fn polish<const B: usize, const N: usize>(
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    config: &PlanConfig,
    rng: &mut Rng,
    plan: &mut Plan<B>,
) -> Result<(), Error> {
    if let Some(shortcut) = &config.shortcut
        && plan.is_free()
    {
        let swept = CostConfig {
            kind: CostKind::Swept,
            inflation: Inflation::default(),
            cylinder: config.cylinder,
            frame: config.frame,
        };
        if let (Some(path), Some(verdict)) = (plan.paths.get_mut(plan.best), plan.verdicts.get_mut(plan.best)) {
            let report = shorten(scene, start, goal, &config.check, shortcut, rng, path)?;
            verdict.swept = trajectory_cost(scene, path, &swept, None)?;
            plan.shortcut = Some(report);
        }
    }
    Ok(())
}

/// `steps` gradient steps of every row's guide at diffusion step `t`, with the plan's step limit
/// and boxes (the first stage's and the global stage's guidance alike). A guide whose rows stop
/// moving is settled and skipped for the rest of the steps: at a fixed `t` its next step would
/// be the same no-op, so this saves work and changes no bit ([`guide_step`]).
/// `paths` holds at most `B` rows (a wave of them, [`PlanConfig::waves`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn guide_steps<E: Executor, const B: usize, const N: usize>(
    exec: &E,
    scene: &Scene<N>,
    paths: &mut [Path],
    grads: &mut [Path],
    guides: &[Guide],
    t: u16,
    steps: u8,
    config: &PlanConfig,
) -> Result<(), Error> {
    let mut settled = [false; B];
    let settled = settled.get_mut(..guides.len()).ok_or(Error::BadParameter)?;
    let mut memos = [CostMemo::NONE; B];
    let memos = memos.get_mut(..paths.len()).ok_or(Error::BadParameter)?;
    for _ in 0..steps {
        guide_once(exec, scene, paths, grads, guides, t, config, settled, memos)?;
        if settled.iter().all(|&s| s) {
            break;
        }
    }
    Ok(())
}

/// One [`guide_step`] with the plan's step limit and boxes, its guides run by `exec`.
#[allow(clippy::too_many_arguments)]
fn guide_once<E: Executor, const N: usize>(
    exec: &E,
    scene: &Scene<N>,
    paths: &mut [Path],
    grads: &mut [Path],
    guides: &[Guide],
    t: u16,
    config: &PlanConfig,
    settled: &mut [bool],
    memos: &mut [CostMemo],
) -> Result<(), Error> {
    let rule = StepRule {
        step_limit: config.step_limit,
        cylinder: config.cylinder,
        frame: config.frame,
    };
    guide_step_on(exec, scene, paths, grads, guides, t, &rule, settled, memos)
}

/// The refinement: `steps` gradient steps of every row's guide at t = 1 (or of
/// `config.refine_guide`, with step-size control if `config.step_control`), ended early by
/// `config.refine_stop` ([`RefineStop`]); shared by the first stage and the global stage.
/// `paths` holds at most `B` rows (a wave of them, [`PlanConfig::waves`]); `saved` is working
/// memory for the step-size control; `certified` and `touched` are what its checks learn of
/// each row ([`RowChecks`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine<E: Executor, const B: usize, const N: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    paths: &mut [Path],
    grads: &mut [Path],
    saved: &mut [Path],
    guides: &[Guide],
    steps: u8,
    config: &PlanConfig,
    certified: &mut [bool],
    touched: &mut [Option<u16>],
) -> Result<(), Error> {
    let rows = paths.len();
    if rows > B || certified.len() != rows || touched.len() != rows {
        return Err(Error::BadParameter);
    }
    certified.fill(false);
    touched.fill(None);
    let every_row: [Guide; B];
    let guides = match config.refine_guide {
        Some(g) => {
            every_row = [g; B];
            every_row.get(..rows).unwrap_or(&[])
        }
        None => guides,
    };
    if guides.is_empty() || !rows.is_multiple_of(guides.len()) {
        return Err(Error::BadParameter);
    }
    if let Some(stop) = config.refine_stop
        && (stop.every == 0 || stop.free == 0)
    {
        return Err(Error::BadParameter);
    }
    let per_guide = rows / guides.len();
    let mut settled = [false; B];
    let settled = settled.get_mut(..guides.len()).ok_or(Error::BadParameter)?;
    // One t (1) and rows moved only by the guides: each row's memo holds for the whole refinement.
    let mut memos = [CostMemo::NONE; B];
    let memos = memos.get_mut(..rows).ok_or(Error::BadParameter)?;
    let (mut best, mut scale) = ([f32::INFINITY; B], [1.0f32; B]);
    // Each row's lowest guide cost so far, and the refinement steps since any row's fell.
    let (mut lowest, mut stalled) = ([f32::INFINITY; B], 0u16);
    let rule = StepRule {
        step_limit: config.step_limit,
        cylinder: config.cylinder,
        frame: config.frame,
    };
    for s in 0..steps {
        if let Some(stop) = config.refine_stop
            && s % stop.every == 0
        {
            let free = certify::<E, B, N>(exec, scene, start, goal, config, paths, certified, touched, stop.free)?;
            if free >= usize::from(stop.free) || (stop.stall > 0 && stalled >= u16::from(stop.stall)) {
                return Ok(());
            }
            // A guide stops once all its rows are certified; a certified row whose guide goes on
            // moving it is checked again later.
            for (flag, rows) in settled.iter_mut().zip(certified.chunks_mut(per_guide.max(1))) {
                *flag |= rows.iter().all(|&c| c);
                if !*flag {
                    rows.fill(false);
                }
            }
        }
        if config.step_control {
            let mut control = StepControl {
                saved: saved.get_mut(..rows).ok_or(Error::BadParameter)?,
                best: best.get_mut(..guides.len()).unwrap_or(&mut []),
                scale: scale.get_mut(..guides.len()).unwrap_or(&mut []),
            };
            guide_step_controlled(scene, paths, grads, guides, 1, &rule, settled, &mut control)?;
        } else {
            guide_once(exec, scene, paths, grads, guides, 1, config, settled, memos)?;
            let mut progress = false;
            for (low, memo) in lowest.iter_mut().zip(memos.iter()) {
                let cost = memo.last_cost();
                progress |= cost < STALL_RATIO * *low;
                *low = low.min(cost);
            }
            stalled = if progress { 0 } else { stalled.saturating_add(1) };
        }
        if settled.iter().all(|&s| s) {
            break;
        }
    }
    Ok(())
}

/// The exact checker's word on the rows of `paths` not yet `certified`, judged as [`judge`]
/// will judge them (clamped into the soft limits, ends exact), each walked from where it last
/// `touched`: the number of certified rows after it. Each row's check is its own: `exec` may
/// run them at once. Under [`Judging::Winner`] a group of `exec.parts()` rows at a time, until
/// `need` are certified.
#[allow(clippy::too_many_arguments)]
fn certify<E: Executor, const B: usize, const N: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    config: &PlanConfig,
    paths: &[Path],
    certified: &mut [bool],
    touched: &mut [Option<u16>],
    need: u8,
) -> Result<usize, Error> {
    let mut free = certified.iter().filter(|&&c| c).count();
    let mut rows: heapless::Vec<(&Path, &mut bool, &mut Option<u16>), B> = heapless::Vec::new();
    for ((x, done), touched) in paths.iter().zip(certified.iter_mut()).zip(touched.iter_mut()) {
        if !*done && rows.push((x, done, touched)).is_err() {
            return Err(Error::BadParameter);
        }
    }
    let group = match config.judging {
        Judging::Every => B,
        Judging::Winner => exec.parts(),
    };
    for group in rows.chunks_mut(group.max(1)) {
        if free >= usize::from(need) {
            break;
        }
        exec.each(group, |(x, done, touched)| {
            let mut judged = **x;
            clamp_for_judging(&mut judged, start, goal);
            let from = touched.map_or(0, usize::from);
            let report = check_trajectory_from(scene, &judged, &config.check, from)?;
            **done = report.is_free();
            **touched = report.first_contact.map(|c| c.segment);
            Ok(())
        })?;
        free += group.iter().filter(|(_, done, _)| **done).count();
    }
    Ok(free)
}

/// Copies row `r mod draws` into every row `r ≥ draws`.
fn spread_draws(rows: &mut [Path], draws: usize) {
    for r in draws.max(1)..rows.len() {
        if let Some(&from) = rows.get(r % draws.max(1))
            && let Some(to) = rows.get_mut(r)
        {
            *to = from;
        }
    }
}

/// A candidate as the judge sees it: every joint clamped into the soft limits, the ends exact.
fn clamp_for_judging(x: &mut Path, start: &Joints<f32>, goal: &Joints<f32>) {
    for q in x.iter_mut() {
        for (j, v) in q.iter_mut().enumerate() {
            *v = v.clamp(PANDA.soft_lower[j], PANDA.soft_upper[j]);
        }
    }
    x[0] = *start;
    x[HORIZON - 1] = *goal;
}

/// The guided reverse diffusion: `paths` end as the `B` candidates (not yet clamped or judged).
#[allow(clippy::too_many_arguments)]
pub fn denoise<const B: usize, const N: usize, const C: usize, const CAP: usize>(
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    work: &mut Workspace<B, CAP>,
    paths: &mut [Path; B],
) -> Result<(), Error> {
    let scratches = core::slice::from_mut(scratch);
    denoise_on(&Serial, scene, start, goal, guides, config, rng, scratches, work, paths)
}

/// [`denoise`] with its work run by `exec` ([`plan_on`]).
#[allow(clippy::too_many_arguments)]
pub fn denoise_on<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP>,
    paths: &mut [Path; B],
) -> Result<(), Error> {
    config.sampler.validate()?;
    check_joints(start)?;
    check_joints(goal)?;
    in_waves(
        exec,
        scene,
        start,
        goal,
        guides,
        config,
        work,
        paths,
        |wave_guides, rows, checks| {
            denoise_wave::<E, B, N, C>(
                exec,
                scene,
                start,
                goal,
                wave_guides,
                config,
                rng,
                scratches,
                rows,
                checks,
            )
        },
    )
}

/// One wave's share of the batch: its rows' paths, noise predictions and gradients, and what
/// the checks learn of them (certified, touched).
pub(crate) type WaveRows<'a> = (&'a mut [Path], &'a mut [Path], &'a mut [Path]);
/// The refinement's checks of one wave's rows: certified free, where each touched.
pub(crate) type WaveChecks<'a> = (&'a mut [bool], &'a mut [Option<u16>]);

/// Runs `wave` on the batch in [`PlanConfig::waves`] waves, one after another: wave `w` gives
/// guides `w`, `w + waves`, `w + 2·waves`, … (so that each wave mixes the caller's order) their
/// rows of `paths`; the exact checker certifies each wave's rows ([`certify`]) before the next
/// runs, and the first wave with a free row ends it. The rows of waves not run are
/// `RowChecks::skipped` in `work.checks` (never judged), and every row is put back in the
/// caller's order (row r follows guide r / k whatever the waves). Shared by the first stage
/// ([`denoise_on`]) and the global stage's reseeding ([`crate::planner::global`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn in_waves<E: Executor, const B: usize, const N: usize, const CAP: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    work: &mut Workspace<B, CAP>,
    paths: &mut [Path; B],
    mut wave: impl FnMut(&[Guide], WaveRows<'_>, WaveChecks<'_>) -> Result<(), Error>,
) -> Result<(), Error> {
    if B == 0 || guides.is_empty() || !B.is_multiple_of(guides.len()) {
        return Err(Error::BadParameter);
    }
    let waves = config.waves_for(guides.len())?;
    let per_wave = guides.len() / waves;
    let rows = B / waves;
    // The guides in the order the waves run them, the rows likewise: wave w runs rows
    // `w·rows .. (w + 1)·rows` of `paths`, which are put back in the caller's order at the end.
    let Some(&first) = guides.first() else {
        return Err(Error::BadParameter);
    };
    let mut order = [first; B];
    for (slot, g) in order.iter_mut().zip(wave_order(guides.len(), waves)) {
        *slot = guides.get(g).copied().ok_or(Error::BadParameter)?;
    }
    work.checks = RowChecks::NONE;
    let Workspace { eps, grads, checks, .. } = work;
    let mut ran = 0;
    for w in 0..waves {
        let (Some(wave_guides), Some(x), Some(e), Some(d), Some(free), Some(touched)) = (
            order.get(w * per_wave..(w + 1) * per_wave),
            paths.get_mut(w * rows..(w + 1) * rows),
            eps.get_mut(w * rows..(w + 1) * rows),
            grads.get_mut(w * rows..(w + 1) * rows),
            checks.free.get_mut(w * rows..(w + 1) * rows),
            checks.touched.get_mut(w * rows..(w + 1) * rows),
        ) else {
            return Err(Error::BadParameter);
        };
        wave(wave_guides, (x, e, d), (free, touched))?;
        ran = w + 1;
        // A later wave runs only when no row of this one is free (the judge would check them
        // the same way; what is learnt here it does not check again).
        if ran < waves && certify::<E, B, N>(exec, scene, start, goal, config, x, free, touched, 1)? > 0 {
            break;
        }
    }
    for skipped in checks.skipped.iter_mut().skip(ran * rows) {
        *skipped = true;
    }
    if waves > 1 {
        let k = B / guides.len();
        // Row `r` of the caller's order (guide `r / k`) is row `source[r]` of the waves' order:
        // `wave_order` inverted, so the two orders cannot disagree.
        let mut source = [0usize; B];
        for (slot, g) in wave_order(guides.len(), waves).enumerate() {
            for i in 0..k {
                if let Some(src) = source.get_mut(g * k + i) {
                    *src = slot * k + i;
                }
            }
        }
        permute(paths, &source);
        permute(&mut checks.free, &source);
        permute(&mut checks.touched, &source);
        permute(&mut checks.skipped, &source);
    }
    Ok(())
}

/// The caller's guide index at each slot of the waves' order: wave `w` takes guides `w`,
/// `w + waves`, `w + 2·waves`, … (`waves` divides `guides`).
fn wave_order(guides: usize, waves: usize) -> impl Iterator<Item = usize> {
    let per_wave = guides / waves.max(1);
    (0..guides).map(move |slot| (slot % per_wave.max(1)) * waves + slot / per_wave.max(1))
}

/// `items[r] = old items[source[r]]` for every `r`, in place (`source` a permutation).
fn permute<T>(items: &mut [T], source: &[usize]) {
    for (r, &first) in source.iter().enumerate().take(items.len()) {
        // Follow the cycle to where the swaps before have moved the item that belongs at `r`.
        let mut from = first;
        while from < r {
            from = source.get(from).copied().unwrap_or(r);
        }
        if from < items.len() {
            items.swap(r, from);
        }
    }
}

/// One wave of [`denoise_on`]: `rows` (paths, noise predictions, gradients) follow `guides`
/// through the denoising steps and the refinement; `checks` (certified, touched) are what the
/// refinement's checks learn of them.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn denoise_wave<E: Executor, const B: usize, const N: usize, const C: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    (paths, eps, grads): WaveRows<'_>,
    (certified, touched): WaveChecks<'_>,
) -> Result<(), Error> {
    let rows = paths.len();
    // Rows `0..draws` draw; row r copies row r mod draws.
    let draws = usize::from(config.start_draws).clamp(1, rows.max(1));
    for x in paths.iter_mut().take(draws) {
        initial_noise(x, rng, start, goal);
        if !config.condition {
            free_ends(x, rng);
        }
    }
    spread_draws(paths, draws);
    for j in 0..config.sampler.evaluations() {
        let step = config.sampler.step(j);
        let time = TimeEmbedding::new(step.t)?;
        if j == 0 && draws < rows {
            // Row r holds row r mod draws: so does its noise, bit for bit (a trajectory's
            // result does not depend on its batch).
            let (Some(drawn), Some(drawn_eps)) = (paths.get(..draws), eps.get_mut(..draws)) else {
                return Err(Error::BadParameter);
            };
            predict_noise_on(exec, drawn, &time, scratches, drawn_eps)?;
            spread_draws(eps, draws);
        } else {
            predict_noise_on(exec, paths, &time, scratches, eps)?;
        }
        for (x, e) in paths.iter_mut().zip(eps.iter()) {
            if config.condition {
                config.sampler.update(step, x, e, rng, start, goal);
            } else {
                config.sampler.advance(step, x, e, rng);
            }
        }
        let steps = config.guidance.steps_at(step.t);
        guide_steps::<E, B, N>(exec, scene, paths, grads, guides, step.t, steps, config)?;
    }
    if !config.condition {
        for x in paths.iter_mut() {
            inpaint(x, start, goal);
        }
    }
    refine::<E, B, N>(
        exec,
        scene,
        start,
        goal,
        paths,
        grads,
        eps,
        guides,
        config.refine,
        config,
        certified,
        touched,
    )
}

/// Clamps every candidate into the soft limits (ends exact), judges it with the exact checker
/// and the uninflated swept volume, and picks the winner.
///
/// The check of a colliding candidate stops at its first contact; only when no candidate is
/// free are the colliding states counted in full, to rank the fallback ([`rank_in_full`]) —
/// unless the global stage is to run, which counts them only if it too finds nothing. A free
/// candidate is checked state by state to the end either way, unless `checks` says the
/// refinement's early stop already did (`Workspace::checks` after [`denoise`];
/// [`RowChecks::NONE`]: check every candidate).
pub fn select<const B: usize, const N: usize>(
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    config: &PlanConfig,
    paths: [Path; B],
    checks: &RowChecks<B>,
) -> Result<Plan<B>, Error> {
    let mut plan = Plan { paths, ..Plan::empty() };
    judge(scene, start, goal, config, &mut plan, checks)?;
    Ok(plan)
}

/// [`select`] on the candidates already in `plan.paths`, in place (no copy of the batch: what
/// keeps the firmware's stack small).
pub fn judge<const B: usize, const N: usize>(
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    config: &PlanConfig,
    plan: &mut Plan<B>,
    checks: &RowChecks<B>,
) -> Result<(), Error> {
    if B == 0 {
        return Err(Error::BadParameter);
    }
    let Plan { paths, verdicts, .. } = plan;
    let swept = CostConfig {
        kind: CostKind::Swept,
        inflation: Inflation::default(),
        cylinder: config.cylinder,
        frame: config.frame,
    };
    for ((x, verdict), &skipped) in paths.iter_mut().zip(verdicts.iter_mut()).zip(&checks.skipped) {
        if skipped {
            *x = [[0.0; JOINTS]; HORIZON];
            *verdict = Verdict {
                swept: f32::INFINITY,
                checked: false,
                free: false,
                colliding_states: u32::MAX,
                made: false,
            };
            continue;
        }
        clamp_for_judging(x, start, goal);
        *verdict = Verdict {
            swept: trajectory_cost(scene, x, &swept, None)?,
            checked: false,
            free: false,
            colliding_states: u32::MAX,
            made: true,
        };
    }
    // Under `Judging::Winner`, the order `pick` ranks free candidates in: swept volume, then
    // row (a selection, not a library sort: no panic path for the firmware). Rows not made
    // count as judged.
    let mut judged = checks.skipped;
    for _ in 0..B {
        let next = match config.judging {
            Judging::Every => judged.iter().position(|&j| !j),
            Judging::Winner => (0..B).filter(|&r| judged.get(r) == Some(&false)).min_by(|&a, &b| {
                let swept = |r: usize| verdicts.get(r).map_or(f32::INFINITY, |v| v.swept);
                swept(a).total_cmp(&swept(b)).then(a.cmp(&b))
            }),
        };
        let Some(r) = next else { break };
        if let Some(j) = judged.get_mut(r) {
            *j = true;
        }
        let (Some(x), Some(verdict), Some(&known_free), Some(touched)) = (
            paths.get(r),
            verdicts.get_mut(r),
            checks.free.get(r),
            checks.touched.get(r),
        ) else {
            continue;
        };
        // A certified row was checked in this very form (clamped, ends exact) and not moved.
        let colliding_states = if known_free {
            0
        } else {
            let from = touched.map_or(0, usize::from);
            check_trajectory_from(scene, x, &config.check, from)?.colliding_states
        };
        verdict.checked = true;
        verdict.free = colliding_states == 0;
        verdict.colliding_states = colliding_states;
        if verdict.free && config.judging == Judging::Winner {
            break;
        }
    }
    plan.best = pick(&plan.verdicts);
    plan.stage = if plan.is_free() { Stage::Diffusion } else { Stage::None };
    plan.search = None;
    plan.shortcut = None;
    if !plan.is_free() && config.global.is_none() {
        rank_in_full(scene, config, plan)?;
    }
    Ok(())
}

/// The free candidate with the lowest swept volume, else the fewest colliding states (then
/// swept volume); the lowest row on ties.
fn pick<const B: usize>(verdicts: &[Verdict; B]) -> usize {
    verdicts
        .iter()
        .enumerate()
        .min_by(|(a, va), (b, vb)| {
            va.colliding_states
                .cmp(&vb.colliding_states)
                .then(va.swept.total_cmp(&vb.swept))
                .then(a.cmp(b))
        })
        .map_or(0, |(i, _)| i)
}

/// When no candidate is free: counts every candidate's colliding states in full and picks the
/// least colliding one (the plan a caller gets with status "collision").
pub fn rank_in_full<const B: usize, const N: usize>(
    scene: &Scene<N>,
    config: &PlanConfig,
    plan: &mut Plan<B>,
) -> Result<(), Error> {
    if plan.is_free() {
        return Ok(());
    }
    for (x, verdict) in plan.paths.iter().zip(plan.verdicts.iter_mut()) {
        if verdict.made {
            verdict.colliding_states = check_trajectory(scene, x, &config.check, false)?.colliding_states;
        }
    }
    plan.best = pick(&plan.verdicts);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::guides::EDMP_GUIDES;
    use crate::planner::search::SearchConfig;
    use crate::scene::Obstacle;
    use std::boxed::Box;

    fn wall_scene() -> Scene<4> {
        let mut s = Scene::new();
        s.push(Obstacle::cuboid([0.5, 0.0, -0.01], [1.2, 1.6, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        s.push(Obstacle::cuboid([0.55, 0.0, 0.45], [0.3, 0.02, 0.5], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        s
    }

    const START: Joints<f32> = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    const GOAL: Joints<f32> = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];

    fn config() -> PlanConfig {
        PlanConfig {
            sampler: Sampler::Strided { steps: 10 },
            guidance: GuidanceSchedule::Every { per_step: 4 },
            condition: true,
            refine: 0,
            step_limit: f32::INFINITY,
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
            check: CheckConfig::default(),
            global: None,
            shortcut: None,
            refine_stop: None,
            refine_guide: None,
            step_control: false,
            judging: Judging::Every,
            start_draws: u8::MAX,
            waves: 1,
        }
    }

    /// `plan` with EDMP's guides, the test config and seed 1.
    fn plan_wall<const B: usize, const C: usize>(
        goal: &Joints<f32>,
        scratch: &mut Scratch<C>,
        work: &mut Workspace<B>,
    ) -> Result<Plan<B>, Error> {
        plan(
            &wall_scene(),
            &START,
            goal,
            &EDMP_GUIDES,
            &config(),
            &mut Rng::new(1),
            scratch,
            work,
        )
    }

    /// The test config with two unguided denoising steps, which leave every first-stage
    /// candidate across the wall, and `global` to rescue them.
    fn across_the_wall(global: GlobalConfig) -> PlanConfig {
        PlanConfig {
            sampler: Sampler::Strided { steps: 2 },
            guidance: GuidanceSchedule::Every { per_step: 0 },
            global: Some(global),
            ..config()
        }
    }

    /// `plan` of the wall problem with EDMP's guides, `cfg` and seed 1, in a batch of 12.
    fn plan_wall_with(cfg: &PlanConfig) -> Result<Plan<12>, Error> {
        let mut scratch = Box::new(Scratch::<4>::new());
        let mut work = Box::new(Workspace::<12>::new());
        plan(
            &wall_scene(),
            &START,
            &GOAL,
            &EDMP_GUIDES,
            cfg,
            &mut Rng::new(1),
            &mut scratch,
            &mut work,
        )
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn guided_plans_go_around_a_wall_that_the_straight_line_crosses_and_repeat_bit_for_bit() {
        let scene = wall_scene();
        // The straight line collides.
        let straight: Path = core::array::from_fn(|w| {
            let s = w as f32 / (HORIZON - 1) as f32;
            core::array::from_fn(|j| START[j] + s * (GOAL[j] - START[j]))
        });
        assert!(
            !check_trajectory(&scene, &straight, &CheckConfig::default(), true)
                .unwrap()
                .is_free()
        );
        let mut scratch = Box::new(Scratch::<4>::new());
        let mut work = Box::new(Workspace::<12>::new());
        let a = plan_wall(&GOAL, &mut scratch, &mut work).unwrap();
        assert!(a.is_free(), "{:?}", a.verdicts);
        let best = &a.paths[a.best];
        assert_eq!(best[0], START);
        assert_eq!(best[HORIZON - 1], GOAL);
        assert!(best.iter().all(|q| PANDA.within_soft_limits(q, 0.0)));
        let b = plan_wall(&GOAL, &mut scratch, &mut work).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn selection_stops_at_the_first_contact_unless_no_candidate_is_free() {
        let scene = wall_scene();
        let straight: Path = core::array::from_fn(|w| {
            let s = w as f32 / (HORIZON - 1) as f32;
            core::array::from_fn(|j| START[j] + s * (GOAL[j] - START[j]))
        });
        let cfg = config();
        // None free: every candidate's contacts are counted in full; ties go to the lower row.
        let none = select(&scene, &START, &GOAL, &cfg, [straight, straight], &RowChecks::NONE).unwrap();
        assert!(!none.is_free());
        assert!(none.verdicts.iter().all(|v| !v.free && v.colliding_states > 1));
        assert_eq!(none.best, 0);
        // One free: it wins, and the colliding one's check stopped at its first contact.
        let mut scratch = Box::new(Scratch::<4>::new());
        let mut work = Box::new(Workspace::<12>::new());
        let planned = plan_wall(&GOAL, &mut scratch, &mut work).unwrap();
        let free = planned.paths[planned.best];
        let one = select(&scene, &START, &GOAL, &cfg, [straight, free], &RowChecks::NONE).unwrap();
        assert_eq!(one.best, 1);
        assert!(one.verdicts[1].free && one.verdicts[1].colliding_states == 0);
        assert!(!one.verdicts[0].free && one.verdicts[0].colliding_states == 1);
    }

    /// [`denoise`] of the wall scene with EDMP's guides and seed `seed`: the 12 candidates.
    fn denoise_wall(cfg: &PlanConfig, seed: u64) -> [Path; 12] {
        let mut scratch = Box::new(Scratch::<4>::new());
        let mut work = Box::new(Workspace::<12>::new());
        let mut paths = [[[0.0f32; JOINTS]; HORIZON]; 12];
        denoise(
            &wall_scene(),
            &START,
            &GOAL,
            &EDMP_GUIDES,
            cfg,
            &mut Rng::new(seed),
            &mut scratch,
            &mut work,
            &mut paths,
        )
        .unwrap();
        paths
    }

    #[test]
    #[cfg_attr(miri, ignore = "the network over a batch: too slow under Miri")]
    fn rows_that_share_a_draw_share_the_first_step_bit_for_bit() {
        // One denoising step (t = 255 → 0 adds no noise) and no guidance: a row is a function
        // of its draw alone, so rows with one draw end equal and rows with two differ.
        let run = |start_draws: u8| {
            let cfg = PlanConfig {
                sampler: Sampler::Strided { steps: 1 },
                guidance: GuidanceSchedule::Every { per_step: 0 },
                start_draws,
                ..config()
            };
            denoise_wall(&cfg, 5)
        };
        let (one, three, all, more) = (run(1), run(3), run(12), run(200));
        assert!(one.iter().all(|p| *p == one[0]));
        for r in 0..12 {
            for s in 0..12 {
                assert_eq!(three[r] == three[s], r % 3 == s % 3, "rows {r} and {s}");
                assert_eq!(all[r] == all[s], r == s, "rows {r} and {s}");
            }
        }
        // Row 0's draw is the same first draw in every setting; 12 or more is a draw per row.
        assert_eq!((one[0], three[0]), (all[0], all[0]));
        assert_eq!(three[..3], all[..3]);
        assert_eq!(more, all);
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn without_conditioning_the_ends_are_written_in_only_at_the_end() {
        let run = |condition: bool| denoise_wall(&PlanConfig { condition, ..config() }, 1);
        let (with, without) = (run(true), run(false));
        for p in with.iter().chain(without.iter()) {
            assert_eq!((p[0], p[HORIZON - 1]), (START, GOAL));
        }
        // The network never saw the ends: the first step is long.
        let first_step = |p: &Path| {
            p[0].iter()
                .zip(&p[1])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max)
        };
        assert!(first_step(&without[0]) > 5.0 * first_step(&with[0]));
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn the_global_stage_rescues_a_failed_first_stage_within_its_bound_and_repeats_bit_for_bit() {
        let cfg = across_the_wall(GlobalConfig::DEFAULT);
        let run = |cfg: &PlanConfig| plan_wall_with(cfg).unwrap();
        let alone = run(&PlanConfig { global: None, ..cfg });
        assert!(!alone.is_free() && alone.stage == Stage::None && alone.search.is_none());
        let a = run(&cfg);
        assert!(a.is_free(), "{:?}", a.verdicts);
        assert!(matches!(a.stage, Stage::Reseeded | Stage::Search), "{:?}", a.stage);
        let report = a.search.unwrap();
        assert!(report.found && report.nodes >= 2);
        let bound = u64::from(GlobalConfig::DEFAULT.attempts)
            * GlobalConfig::DEFAULT.search.max_oracle_calls(DEFAULT_SEARCH_NODES);
        assert!(u64::from(report.segment_checks) <= bound, "{report:?} > {bound}");
        let best = &a.paths[a.best];
        assert_eq!((best[0], best[HORIZON - 1]), (START, GOAL));
        assert!(
            check_trajectory(&wall_scene(), best, &CheckConfig::default(), true)
                .unwrap()
                .is_free()
        );
        assert_eq!(a, run(&cfg));
        assert_eq!(a.fingerprint(), run(&cfg).fingerprint());
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn the_reseeding_runs_in_the_first_stages_waves_up_to_the_first_free_row() {
        // Every first-stage candidate crosses the wall, the global stage reseeds.
        let cfg = PlanConfig {
            judging: Judging::Winner,
            ..across_the_wall(GlobalConfig::DEFAULT)
        };
        let run = |waves: u8| plan_wall_with(&PlanConfig { waves, ..cfg }).unwrap();
        let made = |p: &Plan<12>| -> [bool; 12] { core::array::from_fn(|r| p.verdicts[r].made) };
        // One wave: the twelve reseeded rows together, every one made.
        let one = run(1);
        assert_eq!(one.stage, Stage::Reseeded);
        assert_eq!(made(&one), [true; 12]);
        // Four: wave w (guides w, w + 4, w + 8) runs only when the waves before freed no row, so
        // the rows made are whole waves, up to the one that holds the free winner.
        let four = run(4);
        assert_eq!(four.stage, Stage::Reseeded);
        assert!(four.is_free());
        let ran = 1 + four.best % 4;
        assert_eq!(
            made(&four),
            core::array::from_fn(|r| r % 4 < ran),
            "winner row {}",
            four.best
        );
        assert!(
            ran < 4,
            "the reseeding ran every wave: the test no longer shows one cut short"
        );
        assert_eq!(four, run(4));
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn a_failed_search_is_tried_again_from_fresh_trees_up_to_its_attempts() {
        // No sampling iterations and no seed: each search asks only for the direct edge,
        // through the wall.
        let global = |attempts: u8, iterations: u32| GlobalConfig {
            search: SearchConfig {
                max_iterations: iterations,
                ..SearchConfig::DEFAULT
            },
            attempts,
            seeded: false,
            ..GlobalConfig::DEFAULT
        };
        let run = |global: GlobalConfig| plan_wall_with(&across_the_wall(global));
        for attempts in 1..=4 {
            let report = run(global(attempts, 0)).unwrap().search.unwrap();
            assert!(!report.found);
            assert_eq!(
                (report.attempts, report.segment_checks),
                (attempts, u32::from(attempts))
            );
        }
        // A search that finds the path is not repeated.
        let found = run(global(4, SearchConfig::DEFAULT.max_iterations)).unwrap();
        assert_eq!(found.search.map(|r| (r.found, r.attempts)), Some((true, 1)));
        for attempts in [0, 5] {
            assert_eq!(run(global(attempts, 0)), Err(Error::BadParameter));
        }
    }

    /// [`refine`] of [`mixed_batch`] on one thread, starting from `checks`: the refined rows
    /// and which of them the refinement certified free.
    fn refine_batch(
        scene: &Scene<4>,
        cfg: &PlanConfig,
        steps: u8,
        mut checks: RowChecks<12>,
    ) -> Result<([Path; 12], [bool; 12]), Error> {
        let mut paths = mixed_batch();
        let mut grads = [[[0.0; JOINTS]; HORIZON]; 12];
        let mut saved = grads;
        refine::<_, 12, 4>(
            &Serial,
            scene,
            &START,
            &GOAL,
            &mut paths,
            &mut grads,
            &mut saved,
            &EDMP_GUIDES,
            steps,
            cfg,
            &mut checks.free,
            &mut checks.touched,
        )?;
        Ok((paths, checks.free))
    }

    /// Rows 0-5 on the straight line through the wall, rows 6-11 a detour above it (free).
    fn mixed_batch() -> [Path; 12] {
        let line = |lift: f32| -> Path {
            core::array::from_fn(|w| {
                let s = w as f32 / (HORIZON - 1) as f32;
                let bump = lift * libm::sinf(core::f32::consts::PI * s);
                core::array::from_fn(|j| START[j] + s * (GOAL[j] - START[j]) - if j == 1 { bump } else { 0.0 })
            })
        };
        core::array::from_fn(|r| if r < 6 { line(0.0) } else { line(1.2) })
    }

    #[test]
    #[cfg_attr(miri, ignore = "refinement steps over a batch: too slow under Miri")]
    fn a_stalled_refinement_ends_at_a_check() {
        // Rows 0-5 go straight through the wall; all twelve must be free to end by the count.
        let scene = wall_scene();
        let run = |stall: u8, steps: u8| {
            let cfg = PlanConfig {
                refine_stop: Some(RefineStop {
                    every: 8,
                    free: 12,
                    stall,
                }),
                step_limit: 0.1,
                ..config()
            };
            refine_batch(&scene, &cfg, steps, RowChecks::NONE).unwrap().0
        };
        let full = run(0, 96);
        // The checks fall on steps 0, 8, 16, ...: a stalled run is a shorter budget's run.
        let ended_at = |stall: u8| {
            let stalled = run(stall, 96);
            (0..=12u8).map(|k| 8 * k).find(|&k| run(0, k) == stalled)
        };
        let early = ended_at(1).expect("a stalled run ends at a check");
        assert!(early < 96, "the wall's rows bounce without 5 % progress at some step");
        let later = ended_at(16).expect("a stalled run ends at a check");
        assert!(early <= later, "{early} {later}");
        assert_eq!(run(255, 96), full, "a stall longer than the budget never ends it");
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker over a batch: too slow under Miri")]
    fn where_the_judge_starts_its_walk_changes_no_verdict() {
        let scene = wall_scene();
        let cfg = PlanConfig {
            global: None,
            ..config()
        };
        let plain = select(&scene, &START, &GOAL, &cfg, mixed_batch(), &RowChecks::NONE).unwrap();
        for first in [0u16, 7, 24, 48, 49, 200] {
            let hinted = RowChecks {
                free: [false; 12],
                touched: [Some(first); 12],
                skipped: [false; 12],
            };
            let judged = select(&scene, &START, &GOAL, &cfg, mixed_batch(), &hinted).unwrap();
            assert_eq!(judged.verdicts, plain.verdicts, "walks from segment {first}");
            assert_eq!(judged.best, plain.best);
        }
        assert!(plain.verdicts[..6].iter().all(|v| !v.free) && plain.verdicts[6..].iter().all(|v| v.free));
    }

    #[test]
    #[cfg_attr(miri, ignore = "the exact checker over a batch: too slow under Miri")]
    fn judging_the_winner_only_picks_what_judging_every_candidate_picks() {
        let scene = wall_scene();
        let every = PlanConfig {
            global: None,
            ..config()
        };
        let winner = PlanConfig {
            judging: Judging::Winner,
            ..every
        };
        // Rows 0-5 collide, 6-11 are free: the lowest swept volume among the free ones wins.
        let all = select(&scene, &START, &GOAL, &every, mixed_batch(), &RowChecks::NONE).unwrap();
        let lazy = select(&scene, &START, &GOAL, &winner, mixed_batch(), &RowChecks::NONE).unwrap();
        assert!(all.verdicts.iter().all(|v| v.checked));
        assert_eq!(
            (lazy.best, lazy.verdicts[lazy.best]),
            (all.best, all.verdicts[all.best])
        );
        assert_eq!(lazy.paths, all.paths);
        let best_swept = all.verdicts[all.best].swept;
        for (l, a) in lazy.verdicts.iter().zip(&all.verdicts) {
            assert_eq!(l.swept, a.swept);
            if l.checked {
                assert_eq!(l, a);
                assert!(!l.free || l.swept == best_swept);
            } else {
                // Skipped: after the winner in the judging order, and never picked.
                assert!(l.swept >= best_swept && !l.free && l.colliding_states == u32::MAX);
            }
        }
        assert!(
            lazy.verdicts.iter().filter(|v| v.checked).count() < 12,
            "some check was saved"
        );
        // Nothing free: every candidate is judged, as under `Judging::Every`.
        let colliding: [Path; 12] = core::array::from_fn(|_| mixed_batch()[0]);
        let a = select(&scene, &START, &GOAL, &every, colliding, &RowChecks::NONE).unwrap();
        let b = select(&scene, &START, &GOAL, &winner, colliding, &RowChecks::NONE).unwrap();
        assert_eq!(a, b);
        // The refinement's stop checks rows in order up to the first free one; the paths are
        // the same as when it checks them all.
        let refined = |cfg: &PlanConfig| {
            let cfg = PlanConfig {
                refine_stop: Some(RefineStop {
                    every: 8,
                    free: 1,
                    stall: 0,
                }),
                ..*cfg
            };
            refine_batch(&scene, &cfg, 16, RowChecks::NONE).unwrap()
        };
        let (paths_all, certified_all) = refined(&every);
        let (paths_lazy, certified_lazy) = refined(&winner);
        assert_eq!(paths_all, paths_lazy);
        assert_eq!(certified_all[..], [[false; 6], [true; 6]].concat()[..]);
        let first_free: [bool; 12] = core::array::from_fn(|r| r == 6);
        assert_eq!(certified_lazy, first_free);
    }

    #[test]
    #[cfg_attr(miri, ignore = "refinement steps over a batch: too slow under Miri")]
    fn the_refinement_stops_on_the_checkers_word_and_keeps_certified_rows() {
        let scene = wall_scene();
        let batch = mixed_batch();
        let free = |x: &Path| {
            let mut judged = *x;
            clamp_for_judging(&mut judged, &START, &GOAL);
            check_trajectory(&scene, &judged, &CheckConfig::default(), true)
                .unwrap()
                .is_free()
        };
        assert!(
            !free(&batch[0]) && free(&batch[11]),
            "the test batch mixes colliding and free rows"
        );
        let run = |stop: Option<RefineStop>, steps: u8| {
            let cfg = PlanConfig {
                refine_stop: stop,
                step_limit: 0.1,
                ..config()
            };
            let stale = RowChecks {
                free: [true; 12],
                touched: [Some(3); 12],
                skipped: [false; 12],
            };
            refine_batch(&scene, &cfg, steps, stale)
        };
        let free_rows = [[false; 6], [true; 6]].concat();
        // One free row is enough: nothing moves, and the judge is told which rows are free.
        let (once, certified) = run(
            Some(RefineStop {
                every: 8,
                free: 1,
                stall: 0,
            }),
            16,
        )
        .unwrap();
        assert_eq!(once, batch);
        assert_eq!(certified[..], free_rows[..]);
        // All twelve: the free rows stay as they were, the colliding ones are refined.
        let (all, certified) = run(
            Some(RefineStop {
                every: 8,
                free: 12,
                stall: 0,
            }),
            16,
        )
        .unwrap();
        assert_eq!(all[6..], batch[6..]);
        assert!(all[..6].iter().zip(&batch[..6]).all(|(a, b)| a != b));
        assert!(certified[6..].iter().all(|&c| c));
        for (x, &c) in all.iter().zip(&certified) {
            assert!(!c || free(x), "a certified row is free as it stands");
        }
        // Without the stop every row that has a gradient moves, as before, and none is certified.
        let (plain, none) = run(None, 16).unwrap();
        assert_eq!(none, [false; 12]);
        assert_eq!(all[..6], plain[..6], "the refined rows take the same steps either way");
        assert_ne!(
            plain[6..],
            batch[6..],
            "unfrozen, the free rows move too (the guides' clearance)"
        );
        assert_eq!(
            run(
                Some(RefineStop {
                    every: 8,
                    free: 12,
                    stall: 0
                }),
                16
            )
            .unwrap()
            .0,
            all
        );
        for bad in [
            RefineStop {
                every: 0,
                free: 1,
                stall: 0,
            },
            RefineStop {
                every: 8,
                free: 0,
                stall: 0,
            },
        ] {
            assert_eq!(run(Some(bad), 4).map(|r| r.0), Err(Error::BadParameter));
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn bad_batches_and_inputs_are_typed_errors() {
        let mut scratch = Box::new(Scratch::<1>::new());
        let mut work = Box::new(Workspace::<5>::new());
        let err = plan_wall(&GOAL, &mut scratch, &mut work);
        assert_eq!(err.unwrap_err(), Error::BadParameter);
        let mut work = Box::new(Workspace::<12>::new());
        let mut nan = GOAL;
        nan[2] = f32::NAN;
        let err = plan_wall(&nan, &mut scratch, &mut work);
        assert_eq!(err.unwrap_err(), Error::NonFiniteJoint { joint: 2 });
    }

    #[test]
    fn permute_gathers_every_permutation_of_up_to_six_items() {
        fn each(n: usize, prefix: &mut std::vec::Vec<usize>, out: &mut std::vec::Vec<std::vec::Vec<usize>>) {
            if prefix.len() == n {
                out.push(prefix.clone());
                return;
            }
            for i in 0..n {
                if !prefix.contains(&i) {
                    prefix.push(i);
                    each(n, prefix, out);
                    prefix.pop();
                }
            }
        }
        for n in 0..=6 {
            let mut all = std::vec::Vec::new();
            each(n, &mut std::vec::Vec::new(), &mut all);
            for source in &all {
                let old: std::vec::Vec<usize> = (0..n).map(|i| 100 + i).collect();
                let mut items = old.clone();
                permute(&mut items, source);
                for (r, &s) in source.iter().enumerate() {
                    assert_eq!(items[r], old[s], "{source:?}");
                }
            }
        }
    }

    #[test]
    fn waves_take_every_waves_th_guide() {
        let order = |g, w| wave_order(g, w).collect::<std::vec::Vec<_>>();
        assert_eq!(order(12, 1), (0..12).collect::<std::vec::Vec<_>>());
        assert_eq!(order(12, 3), [0, 3, 6, 9, 1, 4, 7, 10, 2, 5, 8, 11]);
        assert_eq!(order(12, 4), [0, 4, 8, 1, 5, 9, 2, 6, 10, 3, 7, 11]);
        assert_eq!(order(12, 12), (0..12).collect::<std::vec::Vec<_>>());
        assert_eq!(order(6, 2), [0, 2, 4, 1, 3, 5]);
    }

    /// The wall scene with a block through the robot's shoulder: no state is free.
    fn blocked_scene() -> Scene<4> {
        let mut s = wall_scene();
        s.push(Obstacle::cuboid([0.0, 0.0, 0.45], [0.3, 0.3, 0.3], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        s
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn each_wave_is_the_plan_of_its_guides_alone_and_rows_keep_the_callers_order() {
        // Nothing is free: every wave runs. Wave w, run with one Rng carried on, is a batch of
        // 4 rows following guides w, w + 3, w + 6, w + 9; its rows land where the guides are.
        let scene = blocked_scene();
        let cfg = PlanConfig {
            sampler: Sampler::Strided { steps: 3 },
            guidance: GuidanceSchedule::Every { per_step: 2 },
            refine: 4,
            waves: 3,
            ..config()
        };
        let mut scratch = Box::new(Scratch::<4>::new());
        let mut work = Box::new(Workspace::<12>::new());
        let mut waved = [[[0.0f32; JOINTS]; HORIZON]; 12];
        let mut rng = Rng::new(9);
        denoise(
            &scene,
            &START,
            &GOAL,
            &EDMP_GUIDES,
            &cfg,
            &mut rng,
            &mut scratch,
            &mut work,
            &mut waved,
        )
        .unwrap();
        assert!(work.checks.skipped.iter().all(|&s| !s));
        let mut alone = Rng::new(9);
        let mut small = Box::new(Workspace::<4>::new());
        for w in 0..3 {
            let guides: [Guide; 4] = core::array::from_fn(|j| EDMP_GUIDES[w + 3 * j]);
            let mut paths = [[[0.0f32; JOINTS]; HORIZON]; 4];
            let single = PlanConfig { waves: 1, ..cfg };
            denoise(
                &scene,
                &START,
                &GOAL,
                &guides,
                &single,
                &mut alone,
                &mut scratch,
                &mut small,
                &mut paths,
            )
            .unwrap();
            for (j, p) in paths.iter().enumerate() {
                assert_eq!(*p, waved[w + 3 * j], "wave {w}, its row {j}");
            }
        }
        assert_eq!(rng.next_u64(), alone.next_u64(), "the same draws, in the same order");
        // Nothing free: the judge judges all 12, none is free.
        let mut plan = Plan::<12>::empty();
        plan.paths = waved;
        judge(&scene, &START, &GOAL, &cfg, &mut plan, &work.checks).unwrap();
        assert!(plan.verdicts.iter().all(|v| v.made && v.checked && !v.free));
    }

    #[test]
    #[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
    fn a_free_wave_ends_the_plan_and_the_rows_not_made_are_never_picked() {
        let cfg = PlanConfig { waves: 3, ..config() };
        let mut scratch = Box::new(Scratch::<4>::new());
        let mut work = Box::new(Workspace::<12>::new());
        let mut run = |seed: u64| {
            plan(
                &wall_scene(),
                &START,
                &GOAL,
                &EDMP_GUIDES,
                &cfg,
                &mut Rng::new(seed),
                &mut *scratch,
                &mut *work,
            )
            .unwrap()
        };
        let mut early = 0;
        for seed in 1..=8 {
            let a = run(seed);
            assert!(a.is_free(), "seed {seed}: {:?}", a.verdicts);
            // Rows follow guides in the caller's order (one row each); wave w holds the rows
            // r ≡ w (mod 3). The waves run in order until one has a free row (all judged here).
            let ran = 1
                + (0..3)
                    .position(|w| (w..12).step_by(3).any(|r| a.verdicts[r].free))
                    .unwrap();
            for (r, v) in a.verdicts.iter().enumerate() {
                assert_eq!(v.made, r % 3 < ran, "seed {seed}, row {r}");
                assert!(
                    !v.free || r % 3 == ran - 1,
                    "seed {seed}, row {r}: free before the last wave"
                );
                if !v.made {
                    assert_eq!(a.paths[r], [[0.0; JOINTS]; HORIZON]);
                    assert!(!v.checked && !v.free && v.swept == f32::INFINITY);
                }
            }
            assert!(a.verdicts[a.best].made);
            assert_eq!(a, run(seed), "seed {seed}: bit for bit");
            early += usize::from(ran < 3);
        }
        assert!(early > 0, "some plan of the wall scene ends before its last wave");
        // `waves: 1` is EDMP's one batch: every row made.
        let one = plan_wall(&GOAL, &mut scratch, &mut work).unwrap();
        assert!(one.verdicts.iter().all(|v| v.made));
        // At most `waves`: 5 run as 4 (the most that divide 12); 0 is refused.
        let mut waved = |waves: u8| {
            let cfg = PlanConfig { waves, ..config() };
            plan(
                &wall_scene(),
                &START,
                &GOAL,
                &EDMP_GUIDES,
                &cfg,
                &mut Rng::new(2),
                &mut *scratch,
                &mut *work,
            )
        };
        assert_eq!(waved(5).unwrap(), waved(4).unwrap());
        assert_eq!(waved(0).unwrap_err(), Error::BadParameter);
        let counts = |waves: u8, guides: usize| PlanConfig { waves, ..config() }.waves_for(guides);
        assert_eq!(
            [counts(4, 12), counts(5, 12), counts(13, 12), counts(7, 12)],
            [Ok(4), Ok(4), Ok(12), Ok(6)]
        );
        assert_eq!(
            [counts(4, 2), counts(4, 1), counts(3, 4), counts(1, 12)],
            [Ok(2), Ok(1), Ok(2), Ok(1)]
        );
        assert_eq!(counts(4, 0), Err(Error::BadParameter));
    }
}
