//! One guidance step of EDMP: every row of the batch moves down its guide's cost gradient.
//!
//! Rows `g·k … g·k + k − 1` follow guide `g` (k = rows / guides, as the original lays out its
//! batch). Each gradient is taken at the row clipped to the hard joint limits and applied to the
//! unclipped row, interior waypoints only (the original implementation, vishal-2000/EDMP). Normalized guides
//! divide by the norm of their own k rows' gradient and skip the step when it is zero: the
//! original's batch-wide norm couples guides and turns an all-zero gradient into NaN. A step
//! limit per joint keeps the unnormalized guides (whose step is the raw gradient times ~2)
//! from throwing a waypoint across the workspace where the costs are steep.

pub mod guides;

use crate::cost::boxes::{BoxFrame, CylinderBox};
use crate::cost::{CostConfig, CostMemo, trajectory_cost_memo};
use crate::error::Error;
use crate::executor::{Executor, MAX_PARTS, split};
use crate::guidance::guides::Guide;
use crate::robot::Robot;
use crate::robot::kinematics::Joints;
use crate::scene::Scene;

/// Applies every row's guide once at diffusion step `t`, no joint of a waypoint moving more
/// than `step_limit` radians (`f32::INFINITY`: the original's unlimited step). `grads` is
/// working memory, one entry per row. `cylinder` and `frame` choose how the costs box
/// things ([`CostConfig`]). Fails with [`Error::BadParameter`] if the rows do not split evenly over the guides or
/// `grads` has another length; non-finite joints and overflowing results are typed errors too,
/// and then `rows` may be partly updated.
///
/// `settled` is empty (every guide steps) or holds one flag per guide: a guide whose flag is set
/// is skipped, and a guide none of whose rows changed a bit in this step gets its flag set. At
/// a fixed `t` a guide's step depends only on its rows, so the next step of a settled guide would
/// be the same no-op: skipping it saves the work and changes no bit. Clear the flags whenever
/// `t` (or the scene) changes. Any other length is [`Error::BadParameter`].
pub fn guide_step<const H: usize, const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    rows: &mut [[Joints<f32, J>; H]],
    grads: &mut [[Joints<f32, J>; H]],
    step: &GuideStep<'_>,
    settled: &mut [bool],
) -> Result<(), Error> {
    step_rows(robot, scene, rows, grads, step, settled, &mut [], None)
}

/// [`guide_step`] with the guides cut into groups run by `exec` (each group steps its own
/// rows: the same bits as one call).
///
/// `memos` is empty or holds one [`CostMemo`] per row, which lets a row's cost skip the
/// segments that reached nothing at the last step and have not moved since (the same bits).
/// Keep them for the steps at one `t` and start them at [`CostMemo::NONE`] whenever the rows
/// change otherwise (a denoising step) or the scene does.
#[allow(clippy::too_many_arguments)] // the arm, the scene, the batch and its working memory, the step
pub fn guide_step_on<E: Executor, const H: usize, const N: usize, const J: usize>(
    exec: &E,
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    rows: &mut [[Joints<f32, J>; H]],
    grads: &mut [[Joints<f32, J>; H]],
    step: &GuideStep<'_>,
    settled: &mut [bool],
    memos: &mut [CostMemo],
) -> Result<(), Error> {
    if exec.parts() <= 1 {
        return step_rows(robot, scene, rows, grads, step, settled, memos, None);
    }
    let guides = step.guides;
    check_batch(rows.len(), grads.len(), guides.len(), settled.len(), memos.len())?;
    struct Part<'a, const H: usize, const J: usize> {
        guides: &'a [Guide],
        rows: &'a mut [[Joints<f32, J>; H]],
        grads: &'a mut [[Joints<f32, J>; H]],
        settled: &'a mut [bool],
        memos: &'a mut [CostMemo],
    }
    let per_guide = rows.len() / guides.len();
    let mut parts: heapless::Vec<Part<'_, H, J>, MAX_PARTS> = heapless::Vec::new();
    let (mut g_rest, mut r_rest, mut d_rest, mut s_rest, mut m_rest) = (guides, rows, grads, settled, memos);
    for &len in split(guides.len(), 1, exec.parts()).iter().filter(|&&l| l > 0) {
        let (rows_len, settled_len) = ((len * per_guide).min(r_rest.len()), len.min(s_rest.len()));
        let memos_len = rows_len.min(m_rest.len());
        let (Some((g, gr)), Some((r, rr)), Some((d, dr)), Some((s, sr)), Some((m, mr))) = (
            g_rest.split_at_checked(len),
            core::mem::take(&mut r_rest).split_at_mut_checked(rows_len),
            core::mem::take(&mut d_rest).split_at_mut_checked(rows_len),
            core::mem::take(&mut s_rest).split_at_mut_checked(settled_len),
            core::mem::take(&mut m_rest).split_at_mut_checked(memos_len),
        ) else {
            return Err(Error::BadParameter);
        };
        (g_rest, r_rest, d_rest, s_rest, m_rest) = (gr, rr, dr, sr, mr);
        let part = Part {
            guides: g,
            rows: r,
            grads: d,
            settled: s,
            memos: m,
        };
        if parts.push(part).is_err() {
            return Err(Error::BadParameter);
        }
    }
    exec.each(&mut parts, |p| {
        step_rows(
            robot,
            scene,
            p.rows,
            p.grads,
            &step.with_guides(p.guides),
            p.settled,
            p.memos,
            None,
        )
    })
}

/// The batch's shape: rows split evenly over the guides, one gradient per row, one settled
/// flag per guide or none, one memo per row or none.
fn check_batch(rows: usize, grads: usize, guides: usize, settled: usize, memos: usize) -> Result<(), Error> {
    let even = guides > 0 && rows.is_multiple_of(guides) && grads == rows;
    if even && (settled == 0 || settled == guides) && (memos == 0 || memos == rows) {
        Ok(())
    } else {
        Err(Error::BadParameter)
    }
}

/// One guidance step's settings: the guides (one per `rows.len() / guides.len()` rows), the
/// diffusion step `t` their schedules are read at, and how rows move ([`StepRule`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideStep<'a> {
    /// The guides; rows `g·k … g·k + k − 1` follow guide `g`.
    pub guides: &'a [Guide],
    /// The diffusion step (1 in the refinement).
    pub t: u16,
    /// The step limit and how the costs box things.
    pub rule: StepRule,
}

impl<'a> GuideStep<'a> {
    /// The same step for another set of guides (a part of the batch).
    pub fn with_guides(&self, guides: &'a [Guide]) -> Self {
        Self { guides, ..*self }
    }
}

/// How [`guide_step`] moves rows: the per-joint step limit and how the costs box things.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRule {
    /// Largest move of one joint of one waypoint, radians.
    pub step_limit: f32,
    /// How cylinders are boxed.
    pub cylinder: CylinderBox,
    /// The frame the costs box each pair in.
    pub frame: BoxFrame,
}

/// Step-size control for gradient steps at a fixed `t` (the refinement; an ablation, not
/// EDMP's, docs/benchmark.md): each guide remembers its rows where its cost was last lowest.
/// A step after which the cost rose is undone and the guide's step halves; a guide whose step
/// has halved [`MIN_STEP_SCALE`]'s worth is settled (it has converged as far as these steps
/// can tell). EDMP's fixed normalized steps never converge: near a minimum they bounce across
/// it at full length.
#[derive(Debug)]
pub struct StepControl<'a, const H: usize, const J: usize = { crate::robot::JOINTS }> {
    /// Each row where its guide's cost was last lowest (written by the control).
    pub saved: &'a mut [[Joints<f32, J>; H]],
    /// Each guide's cost, summed over its rows, at `saved` (`+∞`: nothing accepted yet).
    pub best: &'a mut [f32],
    /// Each guide's step multiplier (1: the guide's own step).
    pub scale: &'a mut [f32],
}

/// The step multiplier below which [`StepControl`] settles a guide.
pub const MIN_STEP_SCALE: f32 = 1.0 / 64.0;

/// [`guide_step`] with step-size control ([`StepControl`], one entry per guide in `best` and
/// `scale`, one saved row per row; other lengths are [`Error::BadParameter`]).
pub fn guide_step_controlled<const H: usize, const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    rows: &mut [[Joints<f32, J>; H]],
    grads: &mut [[Joints<f32, J>; H]],
    step: &GuideStep<'_>,
    settled: &mut [bool],
    control: &mut StepControl<'_, H, J>,
) -> Result<(), Error> {
    let guides = step.guides.len();
    if control.saved.len() != rows.len() || control.best.len() != guides || control.scale.len() != guides {
        return Err(Error::BadParameter);
    }
    step_rows(robot, scene, rows, grads, step, settled, &mut [], Some(control))
}

#[inline(never)] // one symbol for profiles (benchmarks/stage_instructions.py); it is large anyway
#[allow(clippy::too_many_arguments)] // the public entry points each pass a subset
fn step_rows<const H: usize, const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    rows: &mut [[Joints<f32, J>; H]],
    grads: &mut [[Joints<f32, J>; H]],
    step: &GuideStep<'_>,
    settled: &mut [bool],
    memos: &mut [CostMemo],
    mut control: Option<&mut StepControl<'_, H, J>>,
) -> Result<(), Error> {
    let GuideStep { guides, t, ref rule } = *step;
    let step_limit = rule.step_limit;
    if step_limit.is_nan() || step_limit <= 0.0 {
        return Err(Error::BadParameter);
    }
    check_batch(rows.len(), grads.len(), guides.len(), settled.len(), memos.len())?;
    // Step-size control moves rows back: its steps are not reported to the memos.
    let memos = if control.is_some() { &mut [][..] } else { memos };
    if H < 3 {
        return Err(Error::BadParameter);
    }
    if guides.iter().any(|g| !(g.smooth.is_finite() && g.smooth >= 0.0)) {
        return Err(Error::BadParameter);
    }
    let per_guide = rows.len() / guides.len();
    if per_guide == 0 {
        return Ok(());
    }
    let mut memos = memos.chunks_mut(per_guide);
    for (g, ((guide, rows), grads)) in guides
        .iter()
        .zip(rows.chunks_mut(per_guide))
        .zip(grads.chunks_mut(per_guide))
        .enumerate()
    {
        let memos = memos.next().unwrap_or(&mut []);
        if settled.get(g).copied().unwrap_or(false) {
            continue;
        }
        let config = CostConfig {
            kind: guide.cost,
            inflation: guide.inflation(t),
            cylinder: rule.cylinder,
            frame: rule.frame,
        };
        let mut norm2 = 0.0f32;
        let mut cost = 0.0f32;
        for (r, (row, grad)) in rows.iter().zip(grads.iter_mut()).enumerate() {
            let clipped = row
                .map(|q| core::array::from_fn(|j| crate::float::clamp(q[j], robot.hard_lower[j], robot.hard_upper[j])));
            cost += trajectory_cost_memo(robot, scene, &clipped, &config, Some(grad), memos.get_mut(r))?;
            norm2 += grad[1..H - 1].iter().flatten().map(|g| g * g).sum::<f32>();
        }
        let mut multiplier = 1.0f32;
        if let Some(c) = control.as_deref_mut() {
            let (Some(best), Some(scale)) = (c.best.get_mut(g), c.scale.get_mut(g)) else {
                return Err(Error::BadParameter);
            };
            let saved = c.saved.chunks_mut(per_guide).nth(g).unwrap_or(&mut []);
            if cost > *best {
                // The last step made things worse: undo it and try half as far next time.
                for (row, kept) in rows.iter_mut().zip(saved.iter()) {
                    *row = *kept;
                }
                *scale *= 0.5;
                if *scale < MIN_STEP_SCALE
                    && let Some(flag) = settled.get_mut(g)
                {
                    *flag = true;
                }
                continue;
            }
            *best = cost;
            for (kept, row) in saved.iter_mut().zip(rows.iter()) {
                *kept = *row;
            }
            multiplier = *scale;
        }
        let step = guide.step.at(t) * multiplier;
        let scale = if !guide.normalize {
            step
        } else if norm2 > 0.0 && norm2.is_finite() {
            step / crate::float::sqrt(norm2)
        } else if norm2 == 0.0 {
            if let Some(flag) = settled.get_mut(g) {
                *flag = true;
            }
            continue;
        } else {
            return Err(Error::Overflow);
        };
        let smooth = guide.smooth * multiplier;
        let mut moved = false;
        for (r, (row, grad)) in rows.iter_mut().zip(grads.iter()).enumerate() {
            // The smoothness term acts only where the collision cost pulls: a row it leaves
            // alone stays put (and its guide can settle).
            let pulled = smooth > 0.0 && grad[1..H - 1].iter().flatten().any(|&v| v != 0.0);
            let bend = if pulled { bending_gradient(row) } else { [[0.0; J]; H] };
            let mut waypoints_moved = 0u64;
            for (w, ((q, gq), bq)) in row[1..H - 1]
                .iter_mut()
                .zip(&grad[1..H - 1])
                .zip(&bend[1..H - 1])
                .enumerate()
            {
                let mut here = false;
                for ((qj, gj), bj) in q.iter_mut().zip(gq).zip(bq) {
                    let next = *qj - (scale * gj + smooth * bj).clamp(-step_limit, step_limit);
                    here |= next.to_bits() != qj.to_bits();
                    *qj = next;
                }
                // Waypoint w + 1; a row longer than 64 waypoints is never skipped by its memo.
                waypoints_moved |= u64::from(here).checked_shl(w as u32 + 1).unwrap_or(0);
                moved |= here;
            }
            if let Some(memo) = memos.get_mut(r) {
                memo.moved(waypoints_moved);
            }
            if row.iter().flatten().any(|v| !v.is_finite()) {
                return Err(Error::Overflow);
            }
        }
        if let Some(flag) = settled.get_mut(g) {
            *flag = !moved;
        }
    }
    Ok(())
}

/// The gradient of the bending energy `½ Σ_{i=1}^{H−2} |q_{i−1} − 2 q_i + q_{i+1}|²` with respect
/// to every waypoint (the ends' entries are not used): the smoothness term of a guide
/// ([`Guide::smooth`]). An explicit step of weight `w` on it is stable for `w < 1/8`.
pub fn bending_gradient<const H: usize, const J: usize>(row: &[Joints<f32, J>; H]) -> [Joints<f32, J>; H] {
    let mut accel = [[0.0f32; J]; H];
    for i in 1..H.saturating_sub(1) {
        accel[i] = core::array::from_fn(|j| row[i - 1][j] - 2.0 * row[i][j] + row[i + 1][j]);
    }
    let mut grad = [[0.0f32; J]; H];
    for (k, gk) in grad.iter_mut().enumerate() {
        let at = |i: usize| accel.get(i).copied().unwrap_or([0.0; J]);
        let (before, here, after) = (k.checked_sub(1).map_or([0.0; J], at), at(k), at(k + 1));
        *gk = core::array::from_fn(|j| before[j] - 2.0 * here[j] + after[j]);
    }
    grad
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::PANDA;

    /// One step of `guides` at `t`, joints limited to `step_limit`, enclosing boxes compared in
    /// the obstacle's frame.
    fn step(guides: &[Guide], t: u16, step_limit: f32) -> GuideStep<'_> {
        GuideStep {
            guides,
            t,
            rule: StepRule {
                step_limit,
                cylinder: CylinderBox::Enclosing,
                frame: BoxFrame::Obstacle,
            },
        }
    }
    use crate::cost::{CostKind, trajectory_cost};
    use crate::guidance::guides::EDMP_GUIDES;
    use crate::scene::Obstacle;

    const H: usize = 12;

    fn line(a: Joints<f32>, b: Joints<f32>) -> [Joints<f32>; H] {
        core::array::from_fn(|w| {
            let s = w as f32 / (H - 1) as f32;
            core::array::from_fn(|j| a[j] + s * (b[j] - a[j]))
        })
    }

    /// A box in front of the robot that a sweep of joint 1 passes through.
    fn scene() -> Scene<'static, 4> {
        let mut s = Scene::new();
        let wall = Obstacle::cuboid([0.55, 0.0, 0.45], [0.1, 0.1, 0.3], [1.0, 0.0, 0.0, 0.0]);
        s.push(wall.unwrap()).unwrap();
        s
    }

    fn cost(scene: &Scene<4>, x: &[Joints<f32>; H], guide: &Guide, t: u16) -> f32 {
        let config = CostConfig {
            kind: guide.cost,
            inflation: guide.inflation(t),
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
        };
        trajectory_cost(&PANDA, scene, x, &config, None).unwrap()
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn every_guide_lowers_its_own_cost_and_keeps_the_ends() {
        let scene = scene();
        let a = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let b = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        for guide in &EDMP_GUIDES {
            let t = 30;
            let mut rows = [line(a, b)];
            let before = cost(&scene, &rows[0], guide, t);
            assert!(before > 0.0, "guide {} sees the wall", guide.id);
            let mut grads = [[[0.0; 7]; H]];
            // Small steps: the same direction, scaled down so the first-order decrease shows.
            let small = Guide {
                step: crate::guidance::guides::Schedule::Constant(1e-3),
                ..*guide
            };
            guide_step(
                &PANDA,
                &scene,
                &mut rows,
                &mut grads,
                &step(&[small], t, f32::INFINITY),
                &mut [],
            )
            .unwrap();
            let after = cost(&scene, &rows[0], guide, t);
            assert!(after < before, "guide {}: {before} → {after}", guide.id);
            assert_eq!(rows[0][0], a);
            assert_eq!(rows[0][H - 1], b);
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn guides_in_parts_and_with_memos_step_the_same_bits() {
        let scene = scene();
        let a = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let b = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let rule = StepRule {
            step_limit: 0.1,
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
        };
        let mut whole = [line(a, b); 24];
        let mut grads = [[[0.0; 7]; H]; 24];
        let mut settled = [false; 12];
        // Without memos: every segment of every row costed at every step.
        for _ in 0..6 {
            step_rows(
                &PANDA,
                &scene,
                &mut whole,
                &mut grads,
                &GuideStep {
                    guides: &EDMP_GUIDES,
                    t: 30,
                    rule,
                },
                &mut settled,
                &mut [],
                None,
            )
            .unwrap();
        }
        assert!(whole != [line(a, b); 24], "the guides moved the rows");
        for parts in [1, 2, 3, 5, 8] {
            for with_memos in [false, true] {
                let mut rows = [line(a, b); 24];
                let mut flags = [false; 12];
                let mut memos = [CostMemo::NONE; 24];
                let memos = if with_memos { &mut memos[..] } else { &mut [][..] };
                for _ in 0..6 {
                    guide_step_on(
                        &crate::executor::Reversed(parts),
                        &PANDA,
                        &scene,
                        &mut rows,
                        &mut grads,
                        &GuideStep {
                            guides: &EDMP_GUIDES,
                            t: 30,
                            rule,
                        },
                        &mut flags,
                        memos,
                    )
                    .unwrap();
                }
                let rows_bits = |r: &[[Joints<f32>; H]; 24]| r.map(|x| x.map(|q| q.map(f32::to_bits)));
                assert!(
                    rows_bits(&rows) == rows_bits(&whole) && flags == settled,
                    "{parts} parts, memos: {with_memos}"
                );
            }
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn a_zero_gradient_is_no_step_not_nan() {
        let empty = Scene::<4>::new();
        let a = [0.0, -0.5, 0.0, -2.0, 0.0, 1.6, 0.7];
        let b = [0.5, -0.2, 0.1, -1.8, 0.0, 1.8, 0.7];
        let mut rows = [line(a, b); 24];
        let before = rows;
        let mut grads = [[[0.0; 7]; H]; 24];
        guide_step(
            &PANDA,
            &empty,
            &mut rows,
            &mut grads,
            &step(&EDMP_GUIDES, 100, f32::INFINITY),
            &mut [],
        )
        .unwrap();
        assert_eq!(rows, before);
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn the_gradient_is_taken_at_the_clipped_state() {
        // Joint 7 far above its limit: the clipped row is what the cost sees.
        let scene = scene();
        let guide = Guide {
            id: 0,
            cost: CostKind::Swept,
            clearance: crate::guidance::guides::Schedule::Constant(0.0),
            expansion: crate::guidance::guides::Schedule::Constant(0.0),
            normalize: true,
            step: crate::guidance::guides::Schedule::Constant(0.01),
            smooth: 0.0,
        };
        let a = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let b = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let mut wild = line(a, b);
        for q in &mut wild[1..H - 1] {
            q[6] = 10.0;
        }
        let mut clipped = wild;
        for q in &mut clipped {
            q[6] = q[6].min(PANDA.hard_upper[6]);
        }
        let (mut g1, mut g2) = ([[[0.0; 7]; H]], [[[0.0; 7]; H]]);
        let (mut r1, mut r2) = ([wild], [clipped]);
        guide_step(
            &PANDA,
            &scene,
            &mut r1,
            &mut g1,
            &step(&[guide], 50, f32::INFINITY),
            &mut [],
        )
        .unwrap();
        guide_step(
            &PANDA,
            &scene,
            &mut r2,
            &mut g2,
            &step(&[guide], 50, f32::INFINITY),
            &mut [],
        )
        .unwrap();
        assert_eq!(g1, g2);
        assert!(
            g1[0][1..H - 1].iter().flatten().any(|g| *g != 0.0),
            "the clipped sweep touches the wall"
        );
        // Applied to the unclipped state.
        assert!((r1[0][5][6] - (10.0 - (clipped[5][6] - r2[0][5][6]))).abs() < 1e-5);
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn settled_guides_are_skipped_without_changing_a_bit() {
        // Two guides: one row through the wall (keeps moving), one far from it (settles at once).
        let scene = scene();
        let through = line(
            [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8],
            [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8],
        );
        let away = line(
            [2.0, -1.0, 0.0, -2.5, 0.0, 1.5, 0.8],
            [2.5, -1.0, 0.0, -2.5, 0.0, 1.5, 0.8],
        );
        let guides = [EDMP_GUIDES[0], EDMP_GUIDES[5]];
        let run = |tracked: bool| {
            let mut rows = [through, away];
            let mut grads = [[[0.0; 7]; H]; 2];
            let mut settled = [false; 2];
            for _ in 0..6 {
                let flags: &mut [bool] = if tracked { &mut settled } else { &mut [] };
                guide_step(&PANDA, &scene, &mut rows, &mut grads, &step(&guides, 1, 0.1), flags).unwrap();
            }
            (rows, settled)
        };
        let (plain, _) = run(false);
        let (tracked, settled) = run(true);
        let bits = |r: &[[Joints<f32>; H]; 2]| r.map(|x| x.map(|q| q.map(f32::to_bits)));
        assert_eq!(bits(&plain), bits(&tracked));
        assert_eq!(
            settled,
            [false, true],
            "the row through the wall moves, the far one settles"
        );
        assert_eq!(tracked[1], away);
        // One flag per guide or none.
        let mut rows = [through, away];
        let mut grads = [[[0.0; 7]; H]; 2];
        let err = guide_step(
            &PANDA,
            &scene,
            &mut rows,
            &mut grads,
            &step(&guides, 1, 0.1),
            &mut [false; 3],
        );
        assert_eq!(err, Err(Error::BadParameter));
    }

    #[test]
    fn uneven_batches_are_refused() {
        let mut rows = [[[0.0f32; 7]; H]; 5];
        let mut grads = [[[0.0f32; 7]; H]; 5];
        let err = guide_step(
            &PANDA,
            &Scene::<4>::new(),
            &mut rows,
            &mut grads,
            &step(&EDMP_GUIDES, 10, f32::INFINITY),
            &mut [],
        );
        assert_eq!(err, Err(Error::BadParameter));
        let mut short = [[[0.0f32; 7]; H]; 11];
        let mut twelve = [[[0.0f32; 7]; H]; 12];
        let err = guide_step(
            &PANDA,
            &Scene::<4>::new(),
            &mut twelve,
            &mut short,
            &step(&EDMP_GUIDES, 10, f32::INFINITY),
            &mut [],
        );
        assert_eq!(err, Err(Error::BadParameter));
    }

    #[test]
    fn the_step_limit_bounds_every_joint_move_and_must_be_positive() {
        // Guide 10 (unnormalized swept volume, step ≈ 1.4) through a wall: long raw steps.
        let scene = scene();
        let guide = *EDMP_GUIDES.iter().find(|g| g.id == 10).unwrap();
        let a = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let b = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let mut grads = [[[0.0; 7]; H]];
        let mut free = [line(a, b)];
        guide_step(
            &PANDA,
            &scene,
            &mut free,
            &mut grads,
            &step(&[guide], 200, f32::INFINITY),
            &mut [],
        )
        .unwrap();
        let moved = |rows: &[[Joints<f32>; H]; 1]| {
            let start = line(a, b);
            rows[0]
                .iter()
                .zip(&start)
                .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
                .fold(0.0f32, f32::max)
        };
        assert!(moved(&free) > 0.02, "the raw step is long: {}", moved(&free));
        let mut limited = [line(a, b)];
        guide_step(
            &PANDA,
            &scene,
            &mut limited,
            &mut grads,
            &step(&[guide], 200, 0.02),
            &mut [],
        )
        .unwrap();
        assert!(moved(&limited) <= 0.02 + 1e-6, "{}", moved(&limited));
        assert!(moved(&limited) > 0.0);
        for bad in [0.0, -1.0, f32::NAN] {
            let err = guide_step(
                &PANDA,
                &scene,
                &mut limited,
                &mut grads,
                &step(&[guide], 200, bad),
                &mut [],
            );
            assert_eq!(err, Err(Error::BadParameter));
        }
    }

    fn bending(x: &[Joints<f32>; H]) -> f32 {
        (1..H - 1)
            .map(|i| {
                (0..7)
                    .map(|j| (x[i - 1][j] - 2.0 * x[i][j] + x[i + 1][j]).powi(2))
                    .sum::<f32>()
            })
            .sum::<f32>()
            * 0.5
    }

    #[test]
    fn the_bending_gradient_matches_finite_differences() {
        let x: [Joints<f32>; H] = core::array::from_fn(|w| {
            core::array::from_fn(|j| 0.3 * libm::sinf(0.7 * w as f32 + j as f32) + 0.01 * (w * w) as f32)
        });
        let g = bending_gradient(&x);
        for w in 1..H - 1 {
            for j in 0..7 {
                let h = 1e-2;
                let (mut up, mut down) = (x, x);
                up[w][j] += h;
                down[w][j] -= h;
                let fd = (bending(&up) - bending(&down)) / (2.0 * h);
                assert!(
                    (fd - g[w][j]).abs() <= 1e-3 * fd.abs().max(1.0),
                    "w {w} j {j}: {fd} vs {}",
                    g[w][j]
                );
            }
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn a_smoothness_term_bends_the_path_less_and_leaves_free_rows_alone() {
        let scene = scene();
        let a = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let b = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let guide = EDMP_GUIDES[6];
        let run = |smooth: f32, scene: &Scene<4>| {
            let mut rows = [line(a, b)];
            let mut grads = [[[0.0; 7]; H]];
            let g = Guide { smooth, ..guide };
            for _ in 0..20 {
                guide_step(&PANDA, scene, &mut rows, &mut grads, &step(&[g], 1, 0.1), &mut []).unwrap();
            }
            rows[0]
        };
        let (rough, smooth) = (run(0.0, &scene), run(0.1, &scene));
        assert!(
            bending(&smooth) < bending(&rough),
            "{} vs {}",
            bending(&smooth),
            bending(&rough)
        );
        // Nothing to avoid: the smoothness term alone does not move a row.
        assert_eq!(run(0.1, &Scene::new()), line(a, b));
    }

    #[test]
    #[cfg_attr(miri, ignore = "guidance steps over a batch: too slow under Miri")]
    fn step_control_never_keeps_a_worse_row_and_settles_within_its_bound() {
        let scene = scene();
        let a = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let b = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.8];
        let guides = [EDMP_GUIDES[0], EDMP_GUIDES[6]];
        let rule = StepRule {
            step_limit: 0.1,
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
        };
        let mut rows = [line(a, b); 2];
        let mut grads = [[[0.0; 7]; H]; 2];
        let mut saved = rows;
        let (mut best, mut scale) = ([f32::INFINITY; 2], [1.0; 2]);
        let mut settled = [false; 2];
        let mut last = [f32::INFINITY; 2];
        let mut steps = 0;
        while !settled.iter().all(|&s| s) {
            let mut control = StepControl {
                saved: &mut saved,
                best: &mut best,
                scale: &mut scale,
            };
            guide_step_controlled(
                &PANDA,
                &scene,
                &mut rows,
                &mut grads,
                &GuideStep {
                    guides: &guides,
                    t: 1,
                    rule,
                },
                &mut settled,
                &mut control,
            )
            .unwrap();
            for g in 0..2 {
                assert!(best[g] <= last[g], "guide {g}: {} after {}", best[g], last[g]);
                last[g] = best[g];
            }
            steps += 1;
            // Each guide halves at most 7 times before it settles; between halvings it only
            // descends, which ends too (no test runs forever: the bound is generous).
            assert!(steps < 2000, "still stepping");
        }
        assert!(scale.iter().any(|&s| s < 1.0), "some step was undone");
        let err = guide_step_controlled(
            &PANDA,
            &scene,
            &mut rows,
            &mut grads,
            &GuideStep {
                guides: &guides,
                t: 1,
                rule,
            },
            &mut settled,
            &mut StepControl {
                saved: &mut saved[..1],
                best: &mut best,
                scale: &mut scale,
            },
        );
        assert_eq!(err, Err(Error::BadParameter));
    }
}
