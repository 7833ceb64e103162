//! Guidance between and after the denoising steps: the guides' gradient steps at one diffusion
//! step, and the refinement at t = 1 that the exact checker may end early. Shared by the first
//! stage and the global stage's reseeding.

use crate::cost::CostMemo;
use crate::error::Error;
use crate::executor::Executor;
use crate::guidance::guides::Guide;
use crate::guidance::{GuideStep, StepControl, StepRule, guide_step_controlled, guide_step_on};
use crate::path::Path;
use crate::planner::config::{PlanConfig, STALL_RATIO};
use crate::planner::judge::certify;
use crate::planner::request::Request;
use crate::planner::workspace::{WaveChecks, WaveRows};

/// `steps` gradient steps of every row's guide at diffusion step `t`, with the plan's step limit
/// and boxes (the first stage's and the global stage's guidance alike). A guide whose rows stop
/// moving is settled and skipped for the rest of the steps: at a fixed `t` its next step would
/// be the same no-op, so this saves work and changes no bit
/// ([`guide_step`](crate::guidance::guide_step)). `paths` holds at most `B` rows (a wave of
/// them, [`PlanConfig::waves`](crate::planner::PlanConfig::waves)), following `req.guides`.
pub(crate) fn guide_steps<E: Executor, const B: usize, const N: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    paths: &mut [Path<J>],
    grads: &mut [Path<J>],
    t: u16,
    steps: u8,
) -> Result<(), Error> {
    let mut settled = [false; B];
    let settled = settled.get_mut(..req.guides.len()).ok_or(Error::BadParameter)?;
    let mut memos = [CostMemo::NONE; B];
    let memos = memos.get_mut(..paths.len()).ok_or(Error::BadParameter)?;
    for _ in 0..steps {
        guide_once(exec, req, paths, grads, t, settled, memos)?;
        if settled.iter().all(|&s| s) {
            break;
        }
    }
    Ok(())
}

/// One guidance step of `req.guides` at `t` with the plan's step limit and boxes, its guides
/// run by `exec`.
fn guide_once<E: Executor, const N: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    paths: &mut [Path<J>],
    grads: &mut [Path<J>],
    t: u16,
    settled: &mut [bool],
    memos: &mut [CostMemo],
) -> Result<(), Error> {
    let step = GuideStep {
        guides: req.guides,
        t,
        rule: step_rule(req.config),
    };
    guide_step_on(exec, req.robot, req.scene, paths, grads, &step, settled, memos)
}

/// How the plan's guidance moves rows: its step limit and how its costs box things.
fn step_rule(config: &PlanConfig) -> StepRule {
    StepRule {
        step_limit: config.step_limit,
        cylinder: config.cylinder,
        frame: config.frame,
    }
}

/// The refinement: `steps` gradient steps of every row's guide at t = 1 (or of
/// `config.refine_guide`, with step-size control if `config.step_control`), ended early by
/// `config.refine_stop` ([`RefineStop`](crate::planner::RefineStop)); shared by the first stage and the global stage.
/// `rows` holds at most `B` rows (a wave of them, [`PlanConfig::waves`]), following
/// `req.guides`; their noise predictions are spent, and serve as working memory for the
/// step-size control. `checks` (certified, touched) are what its checks learn of each row
/// ([`RowChecks`](crate::planner::RowChecks)).
pub(crate) fn refine<E: Executor, const B: usize, const N: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    (paths, saved, grads): WaveRows<'_, J>,
    steps: u8,
    (certified, touched): WaveChecks<'_>,
) -> Result<(), Error> {
    let config = req.config;
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
        None => req.guides,
    };
    let req = req.with_guides(guides);
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
    let step = GuideStep {
        guides,
        t: 1,
        rule: step_rule(config),
    };
    for s in 0..steps {
        // `every` is not zero (checked above); `checked_rem` says so to the compiler, which
        // keeps a panic path out of the firmware.
        if let Some(stop) = config.refine_stop
            && s.checked_rem(stop.every) == Some(0)
        {
            let free = certify::<E, B, N, J>(exec, &req, paths, certified, touched, stop.free)?;
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
            guide_step_controlled(req.robot, req.scene, paths, grads, &step, settled, &mut control)?;
        } else {
            guide_once(exec, &req, paths, grads, 1, settled, memos)?;
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
