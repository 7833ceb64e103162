//! The planner: EDMP's guided diffusion on a fixed batch, with a bounded global stage behind it
//! and shortening in front of the caller. One request runs one pipeline:
//!
//! 1. **first stage** ([`denoise_on`], in [`first_stage`](self) and its waves): the rows start
//!    from noise; every denoising step of the prior is followed by their guides' gradient
//!    steps, then the refinement, which the exact checker may end early;
//! 2. **judge** ([`judge`]): every candidate clamped, its swept volume and the exact checker's
//!    word; the free one with the lowest swept volume wins;
//! 3. **global stage** ([`finish_on`], [`global`]): when none is free, a bounded search finds
//!    a path and the prior and the guides reshape it;
//! 4. **shortcut** ([`polish`], [`shortcut`]): the free winner is shortened over the checker.
//!
//! [`plan_observed`] runs the four in order and tells an [`Observer`] where each begins and
//! ends (the host times the stages so); [`plan`] and [`plan_on`] are the same without one.
//!
//! Fixed work: the number of network forwards and cost gradients is set by the sampler, the
//! guidance schedule and `B`, never by the scene's luck; the checker's states are bounded by
//! the path length (at most `MAX_STEPS_PER_SEGMENT` per segment, each candidate checked at
//! most twice: once to its first contact, once in full when no candidate is free). The global
//! stage adds a bounded amount on top ([`global`] states it).
//!
//! The files below this one depend only downwards: `config`, `plan`, `workspace`, `request`
//! (types); `judge`; `refine` and `waves`; `first_stage` and `global`; this file on top.

mod config;
mod first_stage;
pub mod global;
mod judge;
mod plan;
mod refine;
mod request;
pub mod search;
pub mod shortcut;
mod waves;
mod workspace;

#[cfg(test)]
mod tests;

pub use config::{
    DEFAULT_GRADIENT_STEPS, DEFAULT_REFINE_STEPS, DEFAULT_STEP_LIMIT, DEFAULT_STEPS, GlobalConfig, GuidanceSchedule,
    Judging, MAX_ATTEMPTS, PlanConfig, RefineStop, STALL_RATIO, WAVE_BUDGET, waves_within,
};
pub use first_stage::{denoise, denoise_on};
pub use judge::{judge, rank_in_full, select};
pub use plan::{Plan, SearchReport, Stage, Verdict};
pub use request::Request;
pub use workspace::{DEFAULT_SEARCH_NODES, RowChecks, Workspace};

use crate::cost::boxes::Inflation;
use crate::cost::{CostConfig, CostKind, trajectory_cost};
use crate::error::Error;
use crate::executor::{Executor, Serial};
use crate::planner::global::rescue;
use crate::planner::shortcut::shorten;
use crate::prior::Scratch;
use crate::rng::Rng;

/// The pipeline's phases, in the order [`plan_observed`] runs them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The guided denoising and the refinement, in waves ([`denoise_on`]).
    FirstStage,
    /// The candidates judged and the winner picked ([`judge`]).
    Judge,
    /// The global stage, which does nothing when a candidate is free ([`finish_on`]).
    GlobalStage,
    /// The free winner shortened ([`polish`]).
    Shortcut,
}

/// Told where each phase of a plan begins and ends: how a host times the stages without
/// running them itself. Both methods do nothing unless overridden.
pub trait Observer {
    /// `phase` is about to run.
    fn begin(&mut self, phase: Phase) {
        let _ = phase;
    }
    /// `phase` has run.
    fn end(&mut self, phase: Phase) {
        let _ = phase;
    }
}

/// The observer that watches nothing.
impl Observer for () {}

/// Plans `req` with `B` rows (`B` a multiple of `req.guides.len()`), drawing every random
/// number from `rng`: the same inputs give the same bits. [`denoise`] then [`judge`], then
/// [`finish_on`] and [`polish`].
pub fn plan<const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    work: &mut Workspace<B, CAP, J>,
) -> Result<Plan<B, J>, Error> {
    let scratches = core::slice::from_mut(scratch);
    plan_observed(&Serial, req, rng, scratches, work, &mut ())
}

/// [`plan`] with the network's batch, the guides and the refinement's checks cut into parts
/// that `exec` runs (one part per scratch at most): the same bits as [`plan`] whatever the
/// executor ([`crate::executor`]).
pub fn plan_on<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP, J>,
) -> Result<Plan<B, J>, Error> {
    plan_observed(exec, req, rng, scratches, work, &mut ())
}

/// [`plan_on`], telling `observer` where each [`Phase`] begins and ends.
pub fn plan_observed<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP, J>,
    observer: &mut impl Observer,
) -> Result<Plan<B, J>, Error> {
    // One plan's memory throughout: denoised into, judged in place, reseeded in place.
    let mut plan = Plan::empty();
    observer.begin(Phase::FirstStage);
    denoise_on(exec, req, rng, scratches, work, &mut plan.paths)?;
    observer.end(Phase::FirstStage);
    observer.begin(Phase::Judge);
    judge(req, &mut plan, &work.checks)?;
    observer.end(Phase::Judge);
    observer.begin(Phase::GlobalStage);
    finish_on(exec, req, rng, scratches, work, &mut plan)?;
    observer.end(Phase::GlobalStage);
    observer.begin(Phase::Shortcut);
    polish(req, rng, &mut plan)?;
    observer.end(Phase::Shortcut);
    Ok(plan)
}

/// After [`judge`]: a plan with a free candidate is done; otherwise the global stage runs
/// when `req.config.global` asks for it ([`global::rescue`]), in place; `exec` runs its work
/// ([`plan_on`]).
pub fn finish_on<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP, J>,
    plan: &mut Plan<B, J>,
) -> Result<(), Error> {
    if req.config.global.is_some() && !plan.is_free() {
        rescue(exec, req, rng, scratches, work, plan)?;
    }
    Ok(())
}

/// After [`finish_on`]: a free winner is shortened over the exact checker when
/// `req.config.shortcut` asks for it ([`shortcut::shorten`]), in place; its swept volume is
/// recomputed.
pub fn polish<const B: usize, const N: usize, const J: usize>(
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    plan: &mut Plan<B, J>,
) -> Result<(), Error> {
    let Request {
        scene,
        start,
        goal,
        config,
        ..
    } = *req;
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
            let report = shorten(req.robot, scene, [start, goal], &config.check, shortcut, rng, path)?;
            verdict.swept = trajectory_cost(req.robot, scene, path, &swept, None)?;
            plan.shortcut = Some(report);
        }
    }
    Ok(())
}
