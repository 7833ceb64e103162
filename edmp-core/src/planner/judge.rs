//! Judging candidates: the exact checker's word on each (clamped into the soft limits, ends
//! exact), the uninflated swept volume, and the choice of the winner. The refinement's early
//! stop and the waves ask the same question of their rows ([`certify`]), so that the judge
//! need not ask it again.

use crate::collision::checker::{check_trajectory, check_trajectory_from};
use crate::cost::boxes::Inflation;
use crate::cost::{CostConfig, CostKind, trajectory_cost};
use crate::error::Error;
use crate::executor::Executor;
use crate::path::{HORIZON, Path};
use crate::planner::config::Judging;
use crate::planner::plan::{Plan, Stage, Verdict};
use crate::planner::request::Request;
use crate::planner::workspace::RowChecks;
use crate::robot::Robot;
use crate::robot::kinematics::Joints;

/// The exact checker's word on the rows of `paths` not yet `certified`, judged as [`judge`]
/// will judge them (clamped into the soft limits, ends exact), each walked from where it last
/// `touched`: the number of certified rows after it. Each row's check is its own: `exec` may
/// run them at once. Under [`Judging::Winner`] a group of `exec.parts()` rows at a time, until
/// `need` are certified.
pub(crate) fn certify<E: Executor, const B: usize, const N: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    paths: &[Path<J>],
    certified: &mut [bool],
    touched: &mut [Option<u16>],
    need: u8,
) -> Result<usize, Error> {
    let mut free = certified.iter().filter(|&&c| c).count();
    let mut rows: heapless::Vec<(&Path<J>, &mut bool, &mut Option<u16>), B> = heapless::Vec::new();
    for ((x, done), touched) in paths.iter().zip(certified.iter_mut()).zip(touched.iter_mut()) {
        if !*done && rows.push((x, done, touched)).is_err() {
            return Err(Error::BadParameter);
        }
    }
    let Request {
        scene,
        start,
        goal,
        config,
        ..
    } = *req;
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
            clamp_for_judging(req.robot, &mut judged, start, goal);
            let from = touched.map_or(0, usize::from);
            let report = check_trajectory_from(req.robot, scene, &judged, &config.check, from)?;
            **done = report.is_free();
            **touched = report.first_contact.map(|c| c.segment);
            Ok(())
        })?;
        free += group.iter().filter(|(_, done, _)| **done).count();
    }
    Ok(free)
}

/// A candidate as the judge sees it: every joint clamped into the soft limits, the ends exact.
pub(crate) fn clamp_for_judging<const J: usize>(
    robot: &Robot<f32, J>,
    x: &mut Path<J>,
    start: &Joints<f32, J>,
    goal: &Joints<f32, J>,
) {
    for q in x.iter_mut() {
        for (j, v) in q.iter_mut().enumerate() {
            *v = crate::float::clamp(*v, robot.soft_lower[j], robot.soft_upper[j]);
        }
    }
    x[0] = *start;
    x[HORIZON - 1] = *goal;
}

/// Clamps every candidate into the soft limits (ends exact), judges it with the exact checker
/// and the uninflated swept volume, and picks the winner.
///
/// The check of a colliding candidate stops at its first contact; only when no candidate is
/// free are the colliding states counted in full, to rank the fallback ([`rank_in_full`]) —
/// unless the global stage is to run, which counts them only if it too finds nothing. A free
/// candidate is checked state by state to the end either way, unless `checks` says the
/// refinement's early stop already did (`Workspace::checks` after [`denoise`](crate::planner::denoise);
/// [`RowChecks::NONE`]: check every candidate).
pub fn select<const B: usize, const N: usize, const J: usize>(
    req: &Request<'_, N, J>,
    paths: [Path<J>; B],
    checks: &RowChecks<B>,
) -> Result<Plan<B, J>, Error> {
    let mut plan = Plan { paths, ..Plan::empty() };
    judge(req, &mut plan, checks)?;
    Ok(plan)
}

/// [`select`] on the candidates already in `plan.paths`, in place (no copy of the batch: what
/// keeps the firmware's stack small).
pub fn judge<const B: usize, const N: usize, const J: usize>(
    req: &Request<'_, N, J>,
    plan: &mut Plan<B, J>,
    checks: &RowChecks<B>,
) -> Result<(), Error> {
    if B == 0 {
        return Err(Error::BadParameter);
    }
    let Request {
        scene,
        start,
        goal,
        config,
        ..
    } = *req;
    let Plan { paths, verdicts, .. } = plan;
    let swept = CostConfig {
        kind: CostKind::Swept,
        inflation: Inflation::default(),
        cylinder: config.cylinder,
        frame: config.frame,
    };
    for ((x, verdict), &skipped) in paths.iter_mut().zip(verdicts.iter_mut()).zip(&checks.skipped) {
        if skipped {
            *x = [[0.0; J]; HORIZON];
            *verdict = Verdict {
                swept: f32::INFINITY,
                checked: false,
                free: false,
                colliding_states: u32::MAX,
                made: false,
            };
            continue;
        }
        clamp_for_judging(req.robot, x, start, goal);
        *verdict = Verdict {
            swept: trajectory_cost(req.robot, scene, x, &swept, None)?,
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
            check_trajectory_from(req.robot, scene, x, &config.check, from)?.colliding_states
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
        rank_in_full(req, plan)?;
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
pub fn rank_in_full<const B: usize, const N: usize, const J: usize>(
    req: &Request<'_, N, J>,
    plan: &mut Plan<B, J>,
) -> Result<(), Error> {
    let Request { scene, config, .. } = *req;
    if plan.is_free() {
        return Ok(());
    }
    for (x, verdict) in plan.paths.iter().zip(plan.verdicts.iter_mut()) {
        if verdict.made {
            verdict.colliding_states = check_trajectory(req.robot, scene, x, &config.check, false)?.colliding_states;
        }
    }
    plan.best = pick(&plan.verdicts);
    Ok(())
}
