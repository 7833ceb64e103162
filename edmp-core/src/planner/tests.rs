//! The planner's unit tests. Compiled only for `cargo test` (`#[cfg(test)] mod tests;` in
//! `planner/mod.rs`), never into the library: the `unwrap`s here are test assertions on fixed
//! inputs, not panic paths of the planner.

use super::judge::clamp_for_judging;
use super::refine::refine;
use super::waves::{permute, wave_order};
use super::*;
use crate::collision::checker::{CheckConfig, check_trajectory};
use crate::cost::boxes::{BoxFrame, CylinderBox};
use crate::executor::Serial;
use crate::guidance::guides::EDMP_GUIDES;
use crate::guidance::guides::Guide;
use crate::path::{HORIZON, Path};
use crate::planner::search::SearchConfig;
use crate::prior::{Sampler, Scratch};
use crate::rng::Rng;
use crate::robot::kinematics::Joints;
use crate::robot::{JOINTS, PANDA};
use crate::scene::Obstacle;
use crate::scene::Scene;
use std::boxed::Box;

fn wall_scene() -> Scene<'static, 4> {
    let mut s = Scene::new();
    s.push(Obstacle::cuboid([0.5, 0.0, -0.01], [1.2, 1.6, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    s.push(Obstacle::cuboid([0.55, 0.0, 0.45], [0.3, 0.02, 0.5], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    s
}

const START: Joints<f32> = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
const GOAL: Joints<f32> = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];

/// The problem from [`START`] to [`GOAL`] in `scene` with EDMP's guides and `config`.
fn request<'a>(scene: &'a Scene<4>, config: &'a PlanConfig) -> Request<'a, 4> {
    Request {
        robot: &PANDA,
        network: crate::prior::PANDA,
        scene,
        start: &START,
        goal: &GOAL,
        guides: &EDMP_GUIDES,
        config,
    }
}

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
        first_stage_waves: u8::MAX,
        wave_budget: None,
    }
}

/// `plan` with EDMP's guides, the test config and seed 1.
fn plan_wall<const B: usize, const C: usize>(
    goal: &Joints<f32>,
    scratch: &mut Scratch<C>,
    work: &mut Workspace<B>,
) -> Result<Plan<B>, Error> {
    plan(
        &Request {
            robot: &PANDA,
            network: crate::prior::PANDA,
            scene: &wall_scene(),
            start: &START,
            goal,
            guides: &EDMP_GUIDES,
            config: &config(),
        },
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
    plan(&request(&wall_scene(), cfg), &mut Rng::new(1), &mut scratch, &mut work)
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
        !check_trajectory(&crate::robot::PANDA, &scene, &straight, &CheckConfig::default(), true)
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
    let none = select(&request(&scene, &cfg), [straight, straight], &RowChecks::NONE).unwrap();
    assert!(!none.is_free());
    assert!(none.verdicts.iter().all(|v| !v.free && v.colliding_states > 1));
    assert_eq!(none.best, 0);
    // One free: it wins, and the colliding one's check stopped at its first contact.
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let planned = plan_wall(&GOAL, &mut scratch, &mut work).unwrap();
    let free = planned.paths[planned.best];
    let one = select(&request(&scene, &cfg), [straight, free], &RowChecks::NONE).unwrap();
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
        &request(&wall_scene(), cfg),
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
    let bound =
        u64::from(GlobalConfig::DEFAULT.attempts) * GlobalConfig::DEFAULT.search.max_oracle_calls(DEFAULT_SEARCH_NODES);
    assert!(u64::from(report.segment_checks) <= bound, "{report:?} > {bound}");
    let best = &a.paths[a.best];
    assert_eq!((best[0], best[HORIZON - 1]), (START, GOAL));
    assert!(
        check_trajectory(&crate::robot::PANDA, &wall_scene(), best, &CheckConfig::default(), true)
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
    for attempts in 1..=MAX_ATTEMPTS {
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
    for attempts in [0, MAX_ATTEMPTS + 1] {
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
    refine::<_, 12, 4, 7>(
        &Serial,
        &request(scene, cfg),
        (&mut paths, &mut saved, &mut grads),
        steps,
        (&mut checks.free, &mut checks.touched),
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
    let plain = select(&request(&scene, &cfg), mixed_batch(), &RowChecks::NONE).unwrap();
    for first in [0u16, 7, 24, 48, 49, 200] {
        let hinted = RowChecks {
            free: [false; 12],
            touched: [Some(first); 12],
            skipped: [false; 12],
        };
        let judged = select(&request(&scene, &cfg), mixed_batch(), &hinted).unwrap();
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
    let all = select(&request(&scene, &every), mixed_batch(), &RowChecks::NONE).unwrap();
    let lazy = select(&request(&scene, &winner), mixed_batch(), &RowChecks::NONE).unwrap();
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
    let a = select(&request(&scene, &every), colliding, &RowChecks::NONE).unwrap();
    let b = select(&request(&scene, &winner), colliding, &RowChecks::NONE).unwrap();
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
        clamp_for_judging(&PANDA, &mut judged, &START, &GOAL);
        check_trajectory(&crate::robot::PANDA, &scene, &judged, &CheckConfig::default(), true)
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
fn blocked_scene() -> Scene<'static, 4> {
    let mut s = wall_scene();
    s.push(Obstacle::cuboid([0.0, 0.0, 0.45], [0.3, 0.3, 0.3], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    s
}

/// The test config in three waves, with few steps: cheap enough to run every wave.
fn three_short_waves() -> PlanConfig {
    PlanConfig {
        sampler: Sampler::Strided { steps: 3 },
        guidance: GuidanceSchedule::Every { per_step: 2 },
        refine: 4,
        waves: 3,
        ..config()
    }
}

#[test]
#[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
fn each_wave_is_the_plan_of_its_guides_alone_and_rows_keep_the_callers_order() {
    // Nothing is free: every wave runs. Wave w, run with one Rng carried on, is a batch of
    // 4 rows following guides w, w + 3, w + 6, w + 9; its rows land where the guides are.
    let scene = blocked_scene();
    let cfg = three_short_waves();
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let mut waved = [[[0.0f32; JOINTS]; HORIZON]; 12];
    let mut rng = Rng::new(9);
    denoise(&request(&scene, &cfg), &mut rng, &mut scratch, &mut work, &mut waved).unwrap();
    assert!(work.checks.skipped.iter().all(|&s| !s));
    let mut alone = Rng::new(9);
    let mut small = Box::new(Workspace::<4>::new());
    for w in 0..3 {
        let guides: [Guide; 4] = core::array::from_fn(|j| EDMP_GUIDES[w + 3 * j]);
        let mut paths = [[[0.0f32; JOINTS]; HORIZON]; 4];
        let single = PlanConfig { waves: 1, ..cfg };
        denoise(
            &Request {
                robot: &PANDA,
                network: crate::prior::PANDA,
                scene: &scene,
                start: &START,
                goal: &GOAL,
                guides: &guides,
                config: &single,
            },
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
    judge(&request(&scene, &cfg), &mut plan, &work.checks).unwrap();
    assert!(plan.verdicts.iter().all(|v| v.made && v.checked && !v.free));
}

#[test]
#[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
fn a_first_stage_limited_to_k_waves_runs_the_first_k_alone() {
    // Nothing is free: unlimited, all three waves run; limited to one, the first wave's rows
    // are the same bits and the other rows are never made; 0 waves are refused.
    let scene = blocked_scene();
    let cfg = three_short_waves();
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let mut run = |first_stage_waves: u8| {
        let mut paths = [[[0.0f32; JOINTS]; HORIZON]; 12];
        let cfg = PlanConfig {
            first_stage_waves,
            ..cfg
        };
        denoise(
            &request(&scene, &cfg),
            &mut Rng::new(9),
            &mut scratch,
            &mut work,
            &mut paths,
        )
        .map(|()| (paths, work.checks.skipped))
    };
    let (all, all_skipped) = run(u8::MAX).unwrap();
    assert!(all_skipped.iter().all(|&s| !s));
    let (one, one_skipped) = run(1).unwrap();
    for r in 0..12 {
        // Row r follows guide r; wave 0 holds guides 0, 3, 6, 9.
        let first_wave = r % 3 == 0;
        assert_eq!(one_skipped[r], !first_wave, "row {r}");
        if first_wave {
            assert_eq!(one[r], all[r], "row {r}: the first wave's bits");
        }
    }
    assert_eq!(run(3).unwrap().0, all, "a limit of all the waves is no limit");
    assert_eq!(run(0).unwrap_err(), Error::BadParameter);
}

#[test]
#[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
fn the_wave_budget_runs_as_many_waves_as_the_scenes_boxes_allow() {
    // Nothing is free, so every wave allowed runs: a budget of B boxes × waves in a scene of b
    // boxes runs max(1, B / b) waves, the same bits as that cap on the first stage.
    let scene = blocked_scene();
    let boxes = scene.guide_obstacles().len() as u16;
    let cfg = three_short_waves();
    // The Panda prior's own budget (24) would allow more than the three waves here; this
    // leaves no doubt.
    const NO_BOUND: Option<u16> = Some(u16::MAX);
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let mut run = |first_stage_waves: u8, wave_budget: Option<u16>| {
        let mut paths = [[[0.0f32; JOINTS]; HORIZON]; 12];
        let cfg = PlanConfig {
            first_stage_waves,
            wave_budget,
            ..cfg
        };
        denoise(
            &request(&scene, &cfg),
            &mut Rng::new(9),
            &mut scratch,
            &mut work,
            &mut paths,
        )
        .map(|()| (paths, work.checks.skipped))
        .unwrap()
    };
    assert_eq!(run(u8::MAX, Some(boxes)), run(1, NO_BOUND));
    assert_eq!(run(u8::MAX, Some(3 * boxes - 1)), run(2, NO_BOUND));
    assert_eq!(run(u8::MAX, Some(3 * boxes)), run(u8::MAX, NO_BOUND));
    // At least one wave runs, whatever the budget.
    assert_eq!(run(u8::MAX, Some(1)), run(1, NO_BOUND));
    assert_eq!(waves_within(None, 7), usize::MAX);
    assert_eq!(
        [12, 16, 17, 24, 25, 100, 0].map(|b| waves_within(Some(48), b)),
        [4, 3, 2, 2, 1, 1, 48]
    );
}

#[test]
#[cfg_attr(miri, ignore = "the whole planner: hours under Miri")]
fn a_free_wave_ends_the_plan_and_the_rows_not_made_are_never_picked() {
    let cfg = PlanConfig { waves: 3, ..config() };
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let mut run = |seed: u64| {
        plan(
            &request(&wall_scene(), &cfg),
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
            &request(&wall_scene(), &cfg),
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
