//! RRT-Connect on the exact checker: the classical baseline, the filter that makes generated
//! problems solvable, and the source of training trajectories.
//!
//! Bidirectional RRT (Kuffner & LaValle 2000) in joint space within the soft limits; every edge
//! is validated by `edmp_core::collision::checker` at the spec's 0.01 rad interpolation. The raw path is
//! shortcut (random pairs joined when the straight segment is free), resampled to `H`
//! waypoints evenly by joint-space arc length, and smoothed (a few Laplacian passes, each kept
//! only if the whole trajectory stays free). Deterministic for a seed.

use core::cell::RefCell;
use core::time::Duration;
use edmp_core::collision::checker::{CheckConfig, SegmentChecker, check_end, check_trajectory};
use edmp_core::path::HORIZON;
use edmp_core::rng::Rng;
use edmp_core::robot::Robot;
use edmp_core::scene::Scene;
use std::time::Instant;

/// Settings of the planner.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RrtConfig {
    /// Largest joint change of one tree edge (max-norm, radians).
    pub step: f32,
    /// Give up after this long.
    pub budget: Duration,
    /// Shortcut attempts on the raw path.
    pub shortcuts: u32,
    /// Laplacian smoothing passes on the resampled trajectory.
    pub smoothing: u32,
}

impl Default for RrtConfig {
    fn default() -> Self {
        Self {
            step: 0.3,
            budget: Duration::from_secs(1),
            shortcuts: 100,
            smoothing: 20,
        }
    }
}

/// Why no trajectory came back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RrtError {
    /// The start is in collision (or outside the limits).
    InvalidStart,
    /// The goal is in collision (or outside the limits).
    InvalidGoal,
    /// No path within the time budget.
    Timeout,
    /// The path, resampled to the horizon, cut a corner into an obstacle.
    Resample,
    /// The checker refused an input.
    Checker(edmp_core::Error),
}

/// A planned trajectory.
#[derive(Clone, Debug)]
pub(crate) struct RrtPlan<const H: usize, const J: usize> {
    /// `H` waypoints from start to goal, collision-free with interpolation.
    pub waypoints: [[f32; J]; H],
    /// Tree nodes grown.
    pub nodes: usize,
    /// Wall-clock planning time.
    pub elapsed: Duration,
}

struct Tree<const J: usize> {
    nodes: Vec<[f32; J]>,
    parent: Vec<usize>,
}

impl<const J: usize> Tree<J> {
    fn new(root: [f32; J]) -> Self {
        Self {
            nodes: vec![root],
            parent: vec![0],
        }
    }

    fn nearest(&self, q: &[f32; J]) -> usize {
        let mut best = (f32::INFINITY, 0);
        for (i, n) in self.nodes.iter().enumerate() {
            let d = distance2(n, q);
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }

    fn path_to_root(&self, mut i: usize) -> Vec<[f32; J]> {
        let mut path = vec![self.nodes[i]];
        while i != 0 {
            i = self.parent[i];
            path.push(self.nodes[i]);
        }
        path
    }
}

fn distance2<const J: usize>(a: &[f32; J], b: &[f32; J]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

fn distance<const J: usize>(a: &[f32; J], b: &[f32; J]) -> f32 {
    distance2(a, b).sqrt()
}

/// `from` moved towards `to` by at most `step` on every joint.
fn steer<const J: usize>(from: &[f32; J], to: &[f32; J], step: f32) -> [f32; J] {
    let widest = from.iter().zip(to).map(|(a, b)| (b - a).abs()).fold(0.0, f32::max);
    if widest <= step {
        return *to;
    }
    let t = step / widest;
    core::array::from_fn(|j| from[j] + (to[j] - from[j]) * t)
}

struct Planner<'a, const J: usize, const N: usize> {
    robot: &'static Robot<f32, J>,
    scene: &'a Scene<'a, N>,
    check: CheckConfig,
    /// Every edge and shortcut, checked by one checker that carries what it learned (the
    /// core's global stage does the same).
    edges: RefCell<SegmentChecker<'a, J, N>>,
}

impl<const J: usize, const N: usize> Planner<'_, J, N> {
    /// A valid end (docs/formats.md): inside the limits and free by PyBullet's own rule.
    fn valid_end(&self, q: &[f32; J]) -> Result<bool, RrtError> {
        let ok = self.robot.within_soft_limits(q, 0.0);
        Ok(ok
            && check_end(self.robot, self.scene, q, &self.check)
                .map_err(RrtError::Checker)?
                .is_none())
    }

    fn edge_free(&self, a: &[f32; J], b: &[f32; J]) -> Result<bool, RrtError> {
        self.edges.borrow_mut().free(a, b).map_err(RrtError::Checker)
    }

    /// One step of `tree` towards `target`; the new node's index if the edge is free.
    fn extend(&self, tree: &mut Tree<J>, target: &[f32; J], step: f32) -> Result<Option<usize>, RrtError> {
        let near = tree.nearest(target);
        let q = steer(&tree.nodes[near], target, step);
        if !self.edge_free(&tree.nodes[near], &q)? {
            return Ok(None);
        }
        tree.nodes.push(q);
        tree.parent.push(near);
        Ok(Some(tree.nodes.len() - 1))
    }

    /// Extends `tree` towards `target` until it arrives (its index) or is blocked.
    fn connect(&self, tree: &mut Tree<J>, target: &[f32; J], step: f32) -> Result<Option<usize>, RrtError> {
        loop {
            match self.extend(tree, target, step)? {
                None => return Ok(None),
                Some(i) if distance(&tree.nodes[i], target) <= 1e-6 => return Ok(Some(i)),
                Some(_) => {}
            }
        }
    }

    fn shortcut(&self, path: &mut Vec<[f32; J]>, attempts: u32, rng: &mut Rng) -> Result<(), RrtError> {
        for _ in 0..attempts {
            if path.len() < 3 {
                break;
            }
            let i = rng.below(path.len() as u32 - 2) as usize;
            let j = i + 2 + rng.below((path.len() - i - 2) as u32) as usize;
            if j < path.len() && self.edge_free(&path[i], &path[j])? {
                path.drain(i + 1..j);
            }
        }
        Ok(())
    }
}

/// Points evenly spaced by joint-space arc length along the polyline `path`.
fn resample<const H: usize, const J: usize>(path: &[[f32; J]]) -> [[f32; J]; H] {
    let lengths: Vec<f32> = path.windows(2).map(|w| distance(&w[0], &w[1])).collect();
    let total: f32 = lengths.iter().sum();
    let mut out = [path[0]; H];
    let (mut segment, mut before) = (0usize, 0.0f32);
    for (k, slot) in out.iter_mut().enumerate() {
        let s = total * k as f32 / (H - 1).max(1) as f32;
        while segment + 1 < lengths.len() && before + lengths[segment] < s {
            before += lengths[segment];
            segment += 1;
        }
        let len = lengths.get(segment).copied().unwrap_or(0.0);
        let t = if len > 0.0 {
            ((s - before) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (path[segment], path[(segment + 1).min(path.len() - 1)]);
        *slot = core::array::from_fn(|j| a[j] + (b[j] - a[j]) * t);
    }
    out[H - 1] = path[path.len() - 1];
    out
}

/// Plans from `start` to `goal` in `scene` for the arm `robot`.
pub(crate) fn plan<const H: usize, const J: usize, const N: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    start: &[f32; J],
    goal: &[f32; J],
    config: &RrtConfig,
    seed: u64,
) -> Result<RrtPlan<H, J>, RrtError> {
    let began = Instant::now();
    let check = CheckConfig::default();
    let planner = Planner {
        robot,
        scene,
        check,
        edges: RefCell::new(SegmentChecker::new(robot, scene, [start, goal], &check).map_err(RrtError::Checker)?),
    };
    if !planner.valid_end(start)? {
        return Err(RrtError::InvalidStart);
    }
    if !planner.valid_end(goal)? {
        return Err(RrtError::InvalidGoal);
    }
    let mut rng = Rng::new(seed);
    let (mut a, mut b) = (Tree::new(*start), Tree::new(*goal));
    let mut a_is_start = true;
    let mut raw = if planner.edge_free(start, goal)? {
        Some(vec![*start, *goal])
    } else {
        None
    };
    while raw.is_none() {
        if began.elapsed() > config.budget {
            return Err(RrtError::Timeout);
        }
        let sample: [f32; J] = core::array::from_fn(|j| rng.uniform_f32(robot.soft_lower[j], robot.soft_upper[j]));
        if let Some(new) = planner.extend(&mut a, &sample, config.step)? {
            let target = a.nodes[new];
            if let Some(meet) = planner.connect(&mut b, &target, config.step)? {
                let (from_a, from_b) = (a.path_to_root(new), b.path_to_root(meet));
                let mut path: Vec<_> = from_a.into_iter().rev().collect();
                path.extend(from_b.into_iter().skip(1));
                if !a_is_start {
                    path.reverse();
                }
                raw = Some(path);
            }
        }
        core::mem::swap(&mut a, &mut b);
        a_is_start = !a_is_start;
    }
    let mut path = raw.unwrap_or_default();
    planner.shortcut(&mut path, config.shortcuts, &mut rng)?;
    let mut waypoints = resample::<H, J>(&path);
    let free = |w: &[[f32; J]; H]| -> Result<bool, RrtError> {
        Ok(check_trajectory(robot, scene, w, &planner.check, true)
            .map_err(RrtError::Checker)?
            .is_free())
    };
    if !free(&waypoints)? {
        // Even spacing cut a corner: keep every vertex of the shortcut path instead (the
        // core's resampling, for the core's horizon).
        let through = edmp_core::planner::search::resample_through_vertices(&path).filter(|_| H == HORIZON);
        let Some(through) = through else {
            return Err(RrtError::Resample);
        };
        waypoints = core::array::from_fn(|i| through.get(i).copied().unwrap_or(*goal));
        if !free(&waypoints)? {
            return Err(RrtError::Resample);
        }
    }
    for _ in 0..config.smoothing {
        let mut smoothed = waypoints;
        for w in 1..H - 1 {
            smoothed[w] =
                core::array::from_fn(|j| 0.5 * waypoints[w][j] + 0.25 * (waypoints[w - 1][j] + waypoints[w + 1][j]));
        }
        if !free(&smoothed)? {
            break;
        }
        waypoints = smoothed;
    }
    Ok(RrtPlan {
        waypoints,
        nodes: a.nodes.len() + b.nodes.len(),
        elapsed: began.elapsed(),
    })
}

/// Joint-space length of a trajectory (sum of Euclidean steps, radians).
pub(crate) fn path_length<const J: usize>(waypoints: &[[f32; J]]) -> f32 {
    waypoints.windows(2).map(|w| distance(&w[0], &w[1])).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use edmp_core::robot::PANDA;
    use edmp_core::scene::Obstacle;

    fn wall_scene() -> Scene<'static, 8> {
        let mut scene = Scene::<8>::new();
        // A wall in front of the robot, between a left and a right reach.
        scene
            .push(Obstacle::cuboid([0.55, 0.0, 0.45], [0.3, 0.02, 0.5], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        scene
            .push(Obstacle::cuboid([0.5, 0.0, -0.01], [1.2, 1.6, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        scene
    }

    const LEFT: [f32; 7] = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    const RIGHT: [f32; 7] = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];

    #[test]
    fn finds_a_free_path_around_a_wall() {
        let scene = wall_scene();
        assert!(
            !check_trajectory(
                &edmp_core::robot::PANDA,
                &scene,
                &[LEFT, RIGHT],
                &CheckConfig::default(),
                true
            )
            .unwrap()
            .is_free()
        );
        let plan = plan::<50, 7, 8>(&PANDA, &scene, &LEFT, &RIGHT, &RrtConfig::default(), 3).expect("a path exists");
        assert_eq!(plan.waypoints[0], LEFT);
        assert_eq!(plan.waypoints[49], RIGHT);
        assert!(
            check_trajectory(
                &edmp_core::robot::PANDA,
                &scene,
                &plan.waypoints,
                &CheckConfig::default(),
                false
            )
            .unwrap()
            .is_free()
        );
        assert!(plan.waypoints.iter().all(|q| PANDA.within_soft_limits(q, 0.0)));
        assert!(path_length(&plan.waypoints) >= distance(&LEFT, &RIGHT));
    }

    #[test]
    fn same_seed_same_trajectory() {
        let scene = wall_scene();
        let cfg = RrtConfig {
            budget: Duration::from_secs(10),
            ..RrtConfig::default()
        };
        let a = plan::<50, 7, 8>(&PANDA, &scene, &LEFT, &RIGHT, &cfg, 11).unwrap();
        let b = plan::<50, 7, 8>(&PANDA, &scene, &LEFT, &RIGHT, &cfg, 11).unwrap();
        assert_eq!(a.waypoints, b.waypoints);
    }

    #[test]
    fn invalid_ends_are_reported() {
        let scene = wall_scene();
        let inside = [0.0, 0.3, 0.0, -1.2, 0.0, 1.5, 0.785];
        assert!(
            edmp_core::collision::checker::check_state(
                &edmp_core::robot::PANDA,
                &scene,
                &inside,
                &CheckConfig::default()
            )
            .unwrap()
            .is_some()
        );
        assert_eq!(
            plan::<50, 7, 8>(&PANDA, &scene, &inside, &RIGHT, &RrtConfig::default(), 1).err(),
            Some(RrtError::InvalidStart)
        );
        assert_eq!(
            plan::<50, 7, 8>(&PANDA, &scene, &LEFT, &inside, &RrtConfig::default(), 1).err(),
            Some(RrtError::InvalidGoal)
        );
    }
}
