//! Shortening the chosen path: what makes a free trajectory as short and even as a smoothed
//! RRT-Connect's without giving up the exact check.
//!
//! The guides buy clearance with detours and the refinement leaves uneven steps, so a free
//! winner is often longer and rougher than it needs to be. [`shorten`] treats it as a
//! polyline: a greedy pass that joins each kept waypoint to the farthest later one it can see
//! (a straight segment that passes the exact checker; found by bisection, so about log₂ 50
//! checks per kept waypoint), a few random shortcuts on what is left, resampling to [`HORIZON`] waypoints evenly by joint-space arc
//! length (or through every corner when even spacing cuts one), then a few Laplacian passes.
//! Every result is checked in full with the planner's own checker before it replaces the
//! path; when a check fails the path keeps its last checked form, so a free plan stays free.
//! The end of every pass is checked first (one check where most plans need no other); only
//! when it fails are the steps checked one by one.
//!
//! Work is bounded by counts: at most `greedy_checks + attempts` segment checks, then at most
//! `3 + smoothing` full trajectory checks. Randomness comes from the caller's [`Rng`]: deterministic.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::unreachable,
    clippy::arithmetic_side_effects
)]

use crate::collision::checker::{CheckConfig, SegmentChecker, check_trajectory};
use crate::error::Error;
use crate::path::{HORIZON, Path};
use crate::planner::search::{resample_even, resample_through_vertices, segment_length, shortcut_polyline};
use crate::rng::Rng;
use crate::robot::Robot;
use crate::robot::kinematics::Joints;
use crate::scene::Scene;

/// How hard [`shorten`] tries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShortcutConfig {
    /// Segment checks the greedy pass may spend; when they run out, the remaining waypoints
    /// are kept as they are (their segments already passed).
    pub greedy_checks: u32,
    /// Random shortcut attempts after the greedy pass (one segment check each).
    pub attempts: u32,
    /// Laplacian passes after resampling (`x ← x/2 + (prev + next)/4` on the interior), each
    /// kept only when the whole trajectory still passes the checker.
    pub smoothing: u8,
}

impl ShortcutConfig {
    /// The shipped setting: as many shortcut attempts as the RRT-Connect baseline.
    pub const DEFAULT: Self = Self {
        greedy_checks: 64,
        attempts: 8,
        smoothing: 2,
    };
}

impl Default for ShortcutConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What [`shorten`] did to the chosen path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShortcutReport {
    /// Joint-space length (sum of Euclidean steps, radians) before.
    pub length_before: f32,
    /// Joint-space length after (equal to `length_before` when nothing passed the checker).
    pub length_after: f32,
    /// Waypoints the shortcuts dropped (50 minus the shortened polyline's vertices).
    pub dropped: u8,
    /// Laplacian passes kept.
    pub smoothing: u8,
}

/// Shortens the free trajectory `path` from `start` to `goal` in `scene`, in place; `path`
/// changes only to trajectories that pass `check` in full (the same rule as the selection:
/// `end_margin` near the ends, `margin` elsewhere). Call it on a path that passed `check`.
pub fn shorten<const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    [start, goal]: [&Joints<f32, J>; 2],
    check: &CheckConfig,
    config: &ShortcutConfig,
    rng: &mut Rng,
    path: &mut Path<J>,
) -> Result<ShortcutReport, Error> {
    let length_before = length(path);
    let mut report = ShortcutReport {
        length_before,
        length_after: length_before,
        dropped: 0,
        smoothing: 0,
    };
    let free = |p: &Path<J>| -> Result<bool, Error> { Ok(check_trajectory(robot, scene, p, check, true)?.is_free()) };
    let mut polyline = *path;
    let n = shortcut_edges(robot, scene, [start, goal], check, config, rng, &mut polyline)?;
    let Some(corners) = polyline.get(..n) else {
        return Ok(report);
    };
    // An unchanged polyline is the checked path itself: nothing to resample.
    let even = (n < HORIZON).then(|| resample_even(corners));
    let dropped = u8::try_from(HORIZON.saturating_sub(n)).unwrap_or(u8::MAX);
    // Most plans keep every smoothing pass of the evenly resampled polyline (758 of the 800
    // suite plans): that end is checked first, one full check instead of one per
    // step. Only when it fails are the steps checked one by one, as below.
    if config.smoothing > 0 {
        let mut smoothed = even.unwrap_or(*path);
        for _ in 0..config.smoothing {
            smoothed = laplacian(&smoothed);
        }
        if free(&smoothed)? {
            *path = smoothed;
            report.dropped = dropped;
            report.smoothing = config.smoothing;
            report.length_after = length(path);
            return Ok(report);
        }
    }
    if let Some(even) = even {
        let candidate = if free(&even)? {
            Some(even)
        } else {
            match resample_through_vertices(corners) {
                Some(p) if free(&p)? => Some(p),
                _ => None,
            }
        };
        let Some(candidate) = candidate else {
            return Ok(report);
        };
        *path = candidate;
        report.dropped = dropped;
    }
    for _ in 0..config.smoothing {
        let smoothed = laplacian(path);
        if !free(&smoothed)? {
            break;
        }
        *path = smoothed;
        report.smoothing = report.smoothing.saturating_add(1);
    }
    report.length_after = length(path);
    Ok(report)
}

/// The greedy joins, then the random shortcuts, of `polyline` (in place) over one
/// [`SegmentChecker`]: the number of waypoints kept. Not inlined, so that the checker's memory
/// is off the stack before the smoothing's checks.
#[inline(never)]
fn shortcut_edges<const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    ends: [&Joints<f32, J>; 2],
    check: &CheckConfig,
    config: &ShortcutConfig,
    rng: &mut Rng,
    polyline: &mut Path<J>,
) -> Result<usize, Error> {
    check.validate()?;
    let mut checker = SegmentChecker::validated(robot, scene, ends, check);
    let mut edge_free = |a: &Joints<f32, J>, b: &Joints<f32, J>| checker.free(a, b);
    let n = greedy(polyline, config.greedy_checks, &mut edge_free)?;
    Ok(match polyline.get_mut(..n) {
        Some(kept) => shortcut_polyline(kept, config.attempts, rng, &mut edge_free)?.0,
        None => n,
    })
}

/// Joins each kept waypoint of `path` to the farthest later waypoint it sees (bisection over
/// the later waypoints: the last one first, then halves; visibility is not monotone, so this
/// finds a far free one, not always the farthest), in place. Returns the number kept. The
/// segment to the next waypoint is never asked: the path passed the checker.
fn greedy<const J: usize>(
    path: &mut Path<J>,
    budget: u32,
    edge_free: &mut impl FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
) -> Result<usize, Error> {
    let last = HORIZON.saturating_sub(1);
    let (mut kept, mut i, mut checks) = (0usize, 0usize, 0u32);
    while i < last {
        let Some(from) = path.get(i).copied() else { break };
        let (mut lo, mut hi) = (i.saturating_add(1), last);
        let mut probe = hi;
        while lo < hi && checks < budget {
            let Some(to) = path.get(probe).copied() else { break };
            checks = checks.saturating_add(1);
            if edge_free(&from, &to)? {
                lo = probe;
                if probe == hi {
                    break;
                }
            } else {
                hi = probe.saturating_sub(1);
            }
            probe = lo.saturating_add(hi.saturating_sub(lo).saturating_add(1) / 2);
        }
        kept = kept.saturating_add(1);
        if let Some(q) = path.get(lo).copied()
            && let Some(slot) = path.get_mut(kept)
        {
            *slot = q;
        }
        i = lo;
    }
    Ok(kept.saturating_add(1))
}

/// One Laplacian pass over the interior waypoints (the ends stay exact).
fn laplacian<const J: usize>(path: &Path<J>) -> Path<J> {
    let mut out = *path;
    for (slot, w) in out.iter_mut().skip(1).zip(path.windows(3)) {
        if let [a, b, c] = w {
            for (v, ((x, y), z)) in slot.iter_mut().zip(a.iter().zip(b).zip(c)) {
                *v = 0.5 * y + 0.25 * (x + z);
            }
        }
    }
    out
}

/// Joint-space length: the sum of the Euclidean steps.
fn length<const J: usize>(path: &Path<J>) -> f32 {
    path.windows(2).map(segment_length).sum()
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::arithmetic_side_effects
)]
mod tests {
    use super::*;
    use crate::collision::checker::check_segment;
    use crate::robot::PANDA;
    use crate::scene::Obstacle;

    const START: Joints<f32> = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    const GOAL: Joints<f32> = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];

    /// A detour through a raised joint 2 and 4: free in an empty scene, twice as long as needed.
    fn detour() -> Path {
        let mut path: Path = core::array::from_fn(|i| {
            let s = i as f32 / (HORIZON - 1) as f32;
            let bump = libm::sinf(core::f32::consts::PI * s);
            let mut q = [0.0; 7];
            for (j, v) in q.iter_mut().enumerate() {
                *v = START[j] + (GOAL[j] - START[j]) * s;
            }
            q[1] -= 0.6 * bump;
            q[3] += 0.5 * bump;
            q
        });
        path[0] = START;
        path[HORIZON - 1] = GOAL;
        path
    }

    fn floor() -> Scene<'static, 4> {
        let mut s = Scene::new();
        s.push(Obstacle::cuboid([0.5, 0.0, -0.01], [1.2, 1.6, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        s
    }

    #[test]
    fn a_free_detour_becomes_shorter_and_stays_free() {
        let scene = floor();
        let check = CheckConfig::default();
        let mut path = detour();
        assert!(
            check_trajectory(&crate::robot::PANDA, &scene, &path, &check, true)
                .unwrap()
                .is_free()
        );
        let report = shorten(
            &PANDA,
            &scene,
            [&START, &GOAL],
            &check,
            &ShortcutConfig::DEFAULT,
            &mut Rng::new(1),
            &mut path,
        )
        .unwrap();
        assert!(report.length_after < 0.8 * report.length_before, "{report:?}");
        assert!(
            check_trajectory(&crate::robot::PANDA, &scene, &path, &check, true)
                .unwrap()
                .is_free()
        );
        assert_eq!(path[0], START);
        assert_eq!(path[HORIZON - 1], GOAL);
        assert!((report.length_after - length(&path)).abs() < 1e-6);
    }

    #[test]
    fn a_wall_keeps_the_detour_that_passes_it() {
        // A wall across the straight line: shortcuts through it are refused by the checker.
        let mut scene = floor();
        scene
            .push(Obstacle::cuboid([0.55, 0.0, 0.45], [0.3, 0.02, 0.5], [1.0, 0.0, 0.0, 0.0]).unwrap())
            .unwrap();
        let check = CheckConfig::default();
        let straight: Path = core::array::from_fn(|i| {
            let s = i as f32 / (HORIZON - 1) as f32;
            core::array::from_fn(|j| START[j] + (GOAL[j] - START[j]) * s)
        });
        assert!(
            !check_trajectory(&crate::robot::PANDA, &scene, &straight, &check, true)
                .unwrap()
                .is_free()
        );
        let mut path = detour();
        assert!(
            check_trajectory(&crate::robot::PANDA, &scene, &path, &check, true)
                .unwrap()
                .is_free(),
            "the detour passes the wall"
        );
        shorten(
            &PANDA,
            &scene,
            [&START, &GOAL],
            &check,
            &ShortcutConfig::DEFAULT,
            &mut Rng::new(2),
            &mut path,
        )
        .unwrap();
        assert!(
            check_trajectory(&crate::robot::PANDA, &scene, &path, &check, true)
                .unwrap()
                .is_free()
        );
    }

    #[test]
    fn deterministic_for_a_seed() {
        let scene = floor();
        let check = CheckConfig::default();
        let run = |seed| {
            let mut path = detour();
            shorten(
                &PANDA,
                &scene,
                [&START, &GOAL],
                &check,
                &ShortcutConfig::DEFAULT,
                &mut Rng::new(seed),
                &mut path,
            )
            .unwrap();
            path
        };
        assert_eq!(run(7), run(7));
    }

    /// The shortening as it was before the end of the passes was checked first: every step
    /// checked in turn.
    fn step_by_step(scene: &Scene<4>, check: &CheckConfig, config: &ShortcutConfig, seed: u64, path: &mut Path) -> u8 {
        let free = |p: &Path| {
            check_trajectory(&crate::robot::PANDA, scene, p, check, true)
                .unwrap()
                .is_free()
        };
        let mut rng = Rng::new(seed);
        let mut edge_free =
            |a: &Joints<f32>, b: &Joints<f32>| check_segment(&crate::robot::PANDA, scene, a, b, [&START, &GOAL], check);
        let mut polyline = *path;
        let n = greedy(&mut polyline, config.greedy_checks, &mut edge_free).unwrap();
        let (n, _) = shortcut_polyline(&mut polyline[..n], config.attempts, &mut rng, &mut edge_free).unwrap();
        if n < HORIZON {
            let even = resample_even(&polyline[..n]);
            if free(&even) {
                *path = even;
            } else {
                match resample_through_vertices(&polyline[..n]) {
                    Some(p) if free(&p) => *path = p,
                    _ => return 0,
                }
            }
        }
        let mut kept = 0;
        for _ in 0..config.smoothing {
            let smoothed = laplacian(path);
            if !free(&smoothed) {
                break;
            }
            *path = smoothed;
            kept += 1;
        }
        kept
    }

    #[test]
    fn checking_the_end_of_the_passes_first_keeps_what_the_steps_keep() {
        // Detours of random height past a post beside the straight line: the passes either all
        // stay free (then one check decides), or one of them cuts into the post (then the steps
        // are checked one by one, and the last free one stands).
        let check = CheckConfig::default();
        let config = ShortcutConfig::DEFAULT;
        let (mut at_once, mut by_steps) = (0, 0);
        let mut rng = Rng::new(11);
        for case in 0..40u64 {
            let mut scene = floor();
            let x = rng.uniform_f32(0.45, 0.65);
            let z = rng.uniform_f32(0.35, 0.65);
            scene
                .push(Obstacle::cuboid([x, 0.0, z], [0.04, 0.04, 0.3], [1.0, 0.0, 0.0, 0.0]).unwrap())
                .unwrap();
            let lift = rng.uniform_f32(0.3, 0.9);
            let mut path = detour();
            for (i, q) in path.iter_mut().enumerate() {
                let bump = libm::sinf(core::f32::consts::PI * i as f32 / (HORIZON - 1) as f32);
                q[1] -= lift * bump;
            }
            if !check_trajectory(&crate::robot::PANDA, &scene, &path, &check, true)
                .unwrap()
                .is_free()
            {
                continue;
            }
            let mut reference = path;
            let kept = step_by_step(&scene, &check, &config, case, &mut reference);
            let report = shorten(
                &PANDA,
                &scene,
                [&START, &GOAL],
                &check,
                &config,
                &mut Rng::new(case),
                &mut path,
            )
            .unwrap();
            assert!(
                check_trajectory(&crate::robot::PANDA, &scene, &path, &check, true)
                    .unwrap()
                    .is_free()
            );
            if kept == config.smoothing {
                assert_eq!(path, reference, "case {case}");
                at_once += 1;
            } else {
                // The end of the passes collided: the steps were checked as before.
                assert_eq!((path, report.smoothing), (reference, kept), "case {case}");
                by_steps += 1;
            }
        }
        assert!(
            at_once > 0 && by_steps > 0,
            "{at_once} plans kept every pass, {by_steps} not"
        );
    }

    #[test]
    fn laplacian_keeps_the_ends_and_a_straight_line() {
        let straight: Path = core::array::from_fn(|i| [i as f32 * 0.01; 7]);
        let s = laplacian(&straight);
        assert_eq!(s[0], straight[0]);
        assert_eq!(s[HORIZON - 1], straight[HORIZON - 1]);
        for (a, b) in s.iter().zip(&straight) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() < 1e-6);
            }
        }
    }
}
