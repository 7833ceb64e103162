//! The first stage, EDMP's Algorithm 2: the rows start from noise, every denoising step of the
//! prior is followed by their guides' gradient steps, and the refinement at t = 1 follows,
//! in the ensemble's waves.

use crate::error::Error;
use crate::executor::{Executor, Serial};
use crate::path::Path;
use crate::planner::refine::{guide_steps, refine};
use crate::planner::request::Request;
use crate::planner::waves::in_waves;
use crate::planner::workspace::Workspace;
use crate::planner::workspace::{WaveChecks, WaveRows};
use crate::prior::{Scratch, check_joints, free_ends, initial_noise, inpaint};
use crate::rng::Rng;

/// Copies row `r mod draws` into every row `r ≥ draws`.
fn spread_draws<const J: usize>(rows: &mut [Path<J>], draws: usize) {
    for r in draws.max(1)..rows.len() {
        if let Some(&from) = rows.get(r % draws.max(1))
            && let Some(to) = rows.get_mut(r)
        {
            *to = from;
        }
    }
}

/// The guided reverse diffusion: `paths` end as the `B` candidates (not yet clamped or judged).
pub fn denoise<const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    work: &mut Workspace<B, CAP, J>,
    paths: &mut [Path<J>; B],
) -> Result<(), Error> {
    let scratches = core::slice::from_mut(scratch);
    denoise_on(&Serial, req, rng, scratches, work, paths)
}

/// [`denoise`] with its work run by `exec` ([`plan_on`](crate::planner::plan_on)).
pub fn denoise_on<E: Executor, const B: usize, const N: usize, const C: usize, const CAP: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    work: &mut Workspace<B, CAP, J>,
    paths: &mut [Path<J>; B],
) -> Result<(), Error> {
    req.config.sampler.validate()?;
    check_joints(req.start)?;
    check_joints(req.goal)?;
    let limit = usize::from(req.config.first_stage_waves).min(req.waves_within_budget());
    in_waves(exec, req, work, paths, limit, |wave_guides, rows, checks| {
        denoise_wave::<E, B, N, C, J>(exec, &req.with_guides(wave_guides), rng, scratches, rows, checks)
    })
}

/// One wave of [`denoise_on`]: `rows` (paths, noise predictions, gradients) follow
/// `req.guides` through the denoising steps and the refinement; `checks` (certified, touched)
/// are what the refinement's checks learn of them.
fn denoise_wave<E: Executor, const B: usize, const N: usize, const C: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    rng: &mut Rng,
    scratches: &mut [Scratch<C>],
    (paths, eps, grads): WaveRows<'_, J>,
    checks: WaveChecks<'_>,
) -> Result<(), Error> {
    let Request {
        start, goal, config, ..
    } = *req;
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
        let time = req.network.time(step.t)?;
        if j == 0 && draws < rows {
            // Row r holds row r mod draws: so does its noise, bit for bit (a trajectory's
            // result does not depend on its batch).
            let (Some(drawn), Some(drawn_eps)) = (paths.get(..draws), eps.get_mut(..draws)) else {
                return Err(Error::BadParameter);
            };
            req.network.predict_noise_on(exec, drawn, &time, scratches, drawn_eps)?;
            spread_draws(eps, draws);
        } else {
            req.network.predict_noise_on(exec, paths, &time, scratches, eps)?;
        }
        for (x, e) in paths.iter_mut().zip(eps.iter()) {
            if config.condition {
                config.sampler.update(step, x, e, rng, start, goal);
            } else {
                config.sampler.advance(step, x, e, rng);
            }
        }
        let steps = config.guidance.steps_at(step.t);
        guide_steps::<E, B, N, J>(exec, req, paths, grads, step.t, steps)?;
    }
    if !config.condition {
        for x in paths.iter_mut() {
            inpaint(x, start, goal);
        }
    }
    refine::<E, B, N, J>(exec, req, (paths, eps, grads), config.refine, checks)
}
