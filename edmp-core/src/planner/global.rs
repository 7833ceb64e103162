//! The bounded global stage: what the planner does when no diffusion candidate is free.
//!
//! Local guidance cannot leave the basin the prior's sample fell into: a cage's slot, a box's
//! window or a shelf's pocket may need a detour that no gradient points to. Then
//! 1. [`crate::planner::search`] (RRT-Connect over the exact checker, fixed capacity, bounded
//!    iterations) finds a collision-free coarse path;
//! 2. the prior makes trajectories of its own from it, SDEdit-style: each row gets the path
//!    noised to an intermediate diffusion step ([`prior::diffuse`]) and is denoised from there
//!    with its guide, then refined, exactly as the first stage does from pure noise, and in the
//!    first stage's waves (`planner::in_waves`): the first wave with a free row ends it;
//! 3. the candidates are judged as any ([`select`]); only when none is free does the search
//!    path itself win (it passed the checker edge by edge).
//!
//! Worst-case work, on top of the first stage: `attempts ×`
//! [`SearchConfig::max_oracle_calls`] segment checks, `steps` network forwards of each wave's
//! rows, `steps × per_step + refine` guidance steps of each wave's rows (every row of the batch
//! once, when no wave frees one), and one more selection.
//! [`Plan::stage`] says which stage produced the winner.

use crate::collision::checker::check_segment;
use crate::error::Error;
use crate::executor::Executor;
use crate::guidance::guides::Guide;
use crate::path::Path;
use crate::planner::search::{SearchConfig, search_from};
use crate::planner::{
    Plan, PlanConfig, RowChecks, Workspace, guide_steps, in_waves, judge, rank_in_full, refine, select,
};
use crate::prior::{self, STEPS, Sampler, Scratch, Step, TimeEmbedding, predict_noise_on};
use crate::rng::Rng;
use crate::robot::kinematics::Joints;
use crate::scene::Scene;

/// Settings of the global stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalConfig {
    /// The search's budget, per attempt.
    pub search: SearchConfig,
    /// Searches tried, each from fresh trees and further on the random stream, until one finds
    /// a path (1 ..= 4). RRT-Connect's work to a narrow passage is a lottery: on the hardest
    /// unseen problem (window_box/080) one search of the default budget fails for 2-3 seeds in
    /// 16, its trees full before they meet; a second one mostly finds it. Only a problem whose
    /// first search failed pays for another. Four since the twelfth session (two before): over
    /// seeds 1-16 of both suites (12,800 plans) two searches left 7 plans unsolved (cage/061
    /// five times, window_box/047, dresser/042), every search spending its 8,000 iterations; a
    /// third or fourth found a path for 5 of the 7. No plan whose search succeeds within two
    /// changes a bit; those that needed more pay 0.3-1.1 s more (docs/benchmark.md).
    pub attempts: u8,
    /// Diffusion step the search path is noised to before the prior denoises it (1 ..=
    /// `STEPS`): high enough that the prior reshapes it, low enough that it keeps its route.
    pub noise_step: u16,
    /// Strided denoising steps from `noise_step` down (1 ..= `noise_step`). One since the ninth
    /// session (three before): the same share of reseeded plans within two in 98, a twelfth
    /// less work per global-stage plan (docs/benchmark.md).
    pub steps: u16,
    /// Gradient steps of every guide after each of those denoising steps.
    pub per_step: u8,
    /// Refinement gradient steps at t = 1 afterwards.
    pub refine: u8,
    /// Whether each search starts from the first stage's candidate with the lowest swept
    /// volume as well as from the ends ([`search_from`]): the trees take its free stretches
    /// from either end, and the search bridges what lies between. `false`: trees from the ends
    /// alone, as classical RRT-Connect (until 2026-12-02, ninth session).
    pub seeded: bool,
}

impl GlobalConfig {
    /// The shipped setting (measured in the README and docs/benchmark.md).
    pub const DEFAULT: Self = Self {
        search: SearchConfig::DEFAULT,
        attempts: 4,
        noise_step: 50,
        steps: 1,
        per_step: 4,
        refine: 24,
        seeded: true,
    };

    fn validate(&self) -> Result<(), Error> {
        let ok = self.noise_step >= 1
            && usize::from(self.noise_step) <= STEPS
            && self.steps >= 1
            && self.steps <= self.noise_step
            && (1..=4).contains(&self.attempts);
        if ok { Ok(()) } else { Err(Error::BadParameter) }
    }
}

/// Which stage produced the chosen trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The guided diffusion from noise (EDMP's Algorithm 2).
    Diffusion,
    /// The prior and the guides, started from the search's path noised to an intermediate step.
    Reseeded,
    /// The search's own path (shortcut and resampled): no reseeded candidate was free.
    Search,
    /// Nothing was free; the least colliding candidate is returned.
    None,
}

impl Stage {
    /// A short name for plans and tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::Diffusion => "diffusion",
            Self::Reseeded => "reseeded",
            Self::Search => "search",
            Self::None => "none",
        }
    }
}

/// What the search did, when it ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SearchReport {
    /// Whether it found a path.
    pub found: bool,
    /// Tree nodes grown (both trees; 0 when nothing was found, since a failed search reports
    /// no trees).
    pub nodes: u32,
    /// Sampling iterations of the last attempt (when nothing was found: the budget, which the
    /// trees' capacity may have cut short).
    pub iterations: u32,
    /// Searches run ([`GlobalConfig::attempts`] at most): the last one found the path, or all
    /// failed.
    pub attempts: u8,
    /// Segment checks asked of the exact checker.
    pub segment_checks: u32,
}

/// The global stage after a first stage whose candidates all collide (`plan`, changed in
/// place): when the search finds nothing, `plan` keeps the first stage's candidates (ranked
/// in full) and the search's report.
#[allow(clippy::too_many_arguments)]
pub fn rescue<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize>(
    exec: &E,
    scene: &Scene<N>,
    start: &Joints<f32>,
    goal: &Joints<f32>,
    guides: &[Guide],
    config: &PlanConfig,
    global: &GlobalConfig,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP>,
    plan: &mut Plan<B>,
) -> Result<(), Error> {
    global.validate()?;
    let mut calls = 0u32;
    let mut edge_free = |a: &Joints<f32>, b: &Joints<f32>| {
        calls = calls.saturating_add(1);
        check_segment(scene, a, b, [start, goal], &config.check)
    };
    // The first stage's candidate with the lowest swept volume (first on ties): the one that
    // reaches least into the obstacles.
    let seed = if global.seeded {
        let mut best: Option<(f32, &Path)> = None;
        for (x, v) in plan.paths.iter().zip(&plan.verdicts) {
            if best.is_none_or(|(swept, _)| v.swept < swept) {
                best = Some((v.swept, x));
            }
        }
        best.map_or(&[][..], |(_, x)| &x[..])
    } else {
        &[]
    };
    let mut found = None;
    let mut attempts = 0u8;
    while found.is_none() && attempts < global.attempts {
        attempts += 1;
        found = search_from(start, goal, seed, &global.search, &mut work.search, rng, &mut edge_free)?;
    }
    let report = |found: bool, nodes: usize, iterations: u32| SearchReport {
        found,
        nodes: nodes as u32,
        iterations,
        attempts,
        segment_checks: calls,
    };
    let Some(outcome) = found else {
        rank_in_full(scene, config, plan)?;
        plan.search = Some(report(false, 0, global.search.max_iterations));
        return Ok(());
    };
    let searched = report(true, outcome.nodes, outcome.iterations);
    // The first stage's candidates are spent: their memory holds the reseeded ones, made in
    // the first stage's waves (the first wave with a free row ends the reseeding too).
    let path = outcome.path;
    in_waves(
        exec,
        scene,
        start,
        goal,
        guides,
        config,
        work,
        &mut plan.paths,
        |wave_guides, (paths, eps, grads), (free, touched)| {
            for x in paths.iter_mut() {
                *x = path;
                prior::diffuse(x, global.noise_step, rng, start, goal);
            }
            let strided = Sampler::Strided { steps: global.steps };
            for j in 0..usize::from(global.steps) {
                let step = Step::partial(global.noise_step, global.steps, j);
                predict_noise_on(exec, paths, &TimeEmbedding::new(step.t)?, scratches, eps)?;
                for (x, e) in paths.iter_mut().zip(eps.iter()) {
                    strided.update(step, x, e, rng, start, goal);
                }
                if step.t >= 5 {
                    guide_steps::<E, B, N>(exec, scene, paths, grads, wave_guides, step.t, global.per_step, config)?;
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
                wave_guides,
                global.refine,
                config,
                free,
                touched,
            )
        },
    )?;
    judge(scene, start, goal, config, plan, &work.checks)?;
    plan.search = Some(searched);
    if plan.is_free() {
        plan.stage = Stage::Reseeded;
        return Ok(());
    }
    // The last resort: the search path itself, judged like a candidate, in the chosen row.
    let own = select(scene, start, goal, config, [outcome.path], &RowChecks::NONE)?;
    if !own.is_free() {
        // The search checked every segment with the same checker, so only the checker's
        // carried-direction wrinkle near the margin could get here; a colliding path is never
        // passed off as a success.
        rank_in_full(scene, config, plan)?;
        return Ok(());
    }
    let best = plan.best;
    if let (Some(slot), Some(verdict), Some(path), Some(own_verdict)) = (
        plan.paths.get_mut(best),
        plan.verdicts.get_mut(best),
        own.paths.first(),
        own.verdicts.first(),
    ) {
        *slot = *path;
        *verdict = *own_verdict;
    }
    plan.stage = Stage::Search;
    Ok(())
}
