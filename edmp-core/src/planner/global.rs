//! The bounded global stage: what the planner does when no diffusion candidate is free.
//!
//! Local guidance cannot leave the basin the prior's sample fell into: a cage's slot, a box's
//! window or a shelf's pocket may need a detour that no gradient points to. Then
//! 1. [`crate::planner::search`] (RRT-Connect over the exact checker, fixed capacity, bounded
//!    iterations) finds a collision-free coarse path;
//! 2. the prior makes trajectories of its own from it, SDEdit-style: each row gets the path
//!    noised to an intermediate diffusion step ([`prior::diffuse`]) and is denoised from there
//!    with its guide, then refined, exactly as the first stage does from pure noise, and in the
//!    first stage's waves: the first wave with a free row ends it;
//! 3. the candidates are judged as any ([`select`]); only when none is free does the search
//!    path itself win (it passed the checker edge by edge).
//!
//! Worst-case work, on top of the first stage: `attempts ×`
//! [`SearchConfig::max_oracle_calls`](crate::planner::search::SearchConfig::max_oracle_calls) segment checks, `steps` network forwards of each wave's
//! rows, `steps × per_step + refine` guidance steps of each wave's rows (every row of the batch
//! once, when no wave frees one), and one more selection.
//! [`Plan::stage`] says which stage produced the winner.

use crate::collision::checker::SegmentChecker;
use crate::error::Error;
use crate::executor::Executor;
use crate::path::Path;
use crate::planner::config::GlobalConfig;
use crate::planner::judge::{judge, rank_in_full, select};
use crate::planner::plan::{Plan, SearchReport, Stage};
use crate::planner::refine::{guide_steps, refine};
use crate::planner::request::Request;
use crate::planner::search::{SearchOutcome, search_from};
use crate::planner::waves::in_waves;
use crate::planner::workspace::{RowChecks, Workspace};
use crate::prior::{self, Sampler, Scratch, Step};
use crate::rng::Rng;
use crate::robot::kinematics::Joints;

/// The global stage after a first stage whose candidates all collide (`plan`, changed in
/// place), with `req.config.global`'s settings (none is [`Error::BadParameter`]): when the
/// search finds nothing, `plan` keeps the first stage's candidates (ranked in full) and the
/// search's report.
pub fn rescue<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP, J>,
    plan: &mut Plan<B, J>,
) -> Result<(), Error> {
    let Request {
        start, goal, config, ..
    } = *req;
    let Some(global) = &config.global else {
        return Err(Error::BadParameter);
    };
    global.validate()?;
    let (found, attempts, calls) = search_with_one_checker(req, global, rng, work, plan)?;
    let report = |found: bool, nodes: usize, iterations: u32| SearchReport {
        found,
        nodes: nodes as u32,
        iterations,
        attempts,
        segment_checks: calls,
    };
    let Some(outcome) = found else {
        rank_in_full(req, plan)?;
        plan.search = Some(report(false, 0, global.search.max_iterations));
        return Ok(());
    };
    let searched = report(true, outcome.nodes, outcome.iterations);
    // The first stage's candidates are spent: their memory holds the reseeded ones, made in
    // the first stage's waves (the first wave with a free row ends the reseeding too).
    let path = outcome.path;
    in_waves(
        exec,
        req,
        work,
        &mut plan.paths,
        req.waves_within_budget(),
        |wave_guides, (paths, eps, grads), checks| {
            let wave = req.with_guides(wave_guides);
            for x in paths.iter_mut() {
                *x = path;
                prior::diffuse(x, global.noise_step, rng, start, goal);
            }
            let strided = Sampler::Strided { steps: global.steps };
            for j in 0..usize::from(global.steps) {
                let step = Step::partial(global.noise_step, global.steps, j);
                req.network
                    .predict_noise_on(exec, paths, &req.network.time(step.t)?, scratches, eps)?;
                for (x, e) in paths.iter_mut().zip(eps.iter()) {
                    strided.update(step, x, e, rng, start, goal);
                }
                if step.t >= 5 {
                    guide_steps::<E, B, N, J>(exec, &wave, paths, grads, step.t, global.per_step)?;
                }
            }
            refine::<E, B, N, J>(exec, &wave, (paths, eps, grads), global.refine, checks)
        },
    )?;
    judge(req, plan, &work.checks)?;
    plan.search = Some(searched);
    if plan.is_free() {
        plan.stage = Stage::Reseeded;
        return Ok(());
    }
    // The last resort: the search path itself, judged like a candidate, in the chosen row.
    let own = select(req, [outcome.path], &RowChecks::NONE)?;
    if !own.is_free() {
        // The search checked every segment with the same checker, so only the checker's
        // carried-direction wrinkle near the margin could get here; a colliding path is never
        // passed off as a success.
        rank_in_full(req, plan)?;
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

/// The searches of the global stage, up to `attempts`, over one [`SegmentChecker`]: the path
/// found (if any), the searches run and the segments checked. Not inlined, so that the
/// checker's memory (per obstacle slot and robot shape a slack and a separating direction:
/// kilobytes) is off the stack before the prior reshapes the path.
#[inline(never)]
fn search_with_one_checker<const B: usize, const N: usize, const CAP: usize, const J: usize>(
    req: &Request<'_, N, J>,
    global: &GlobalConfig,
    rng: &mut Rng,
    work: &mut Workspace<B, CAP, J>,
    plan: &Plan<B, J>,
) -> Result<(Option<SearchOutcome<J>>, u8, u32), Error> {
    let (scene, [start, goal], check) = (req.scene, [req.start, req.goal], &req.config.check);
    let mut calls = 0u32;
    check.validate()?;
    let mut checker = SegmentChecker::validated(req.robot, scene, [start, goal], check);
    let mut edge_free = |a: &Joints<f32, J>, b: &Joints<f32, J>| {
        calls = calls.saturating_add(1);
        checker.free(a, b)
    };
    // The first stage's candidate with the lowest swept volume (first on ties): the one that
    // reaches least into the obstacles.
    let seed = if global.seeded {
        let mut best: Option<(f32, &Path<J>)> = None;
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
        found = search_from(
            req.robot,
            start,
            goal,
            seed,
            &global.search,
            &mut work.search,
            rng,
            &mut edge_free,
        )?;
    }
    Ok((found, attempts, calls))
}
