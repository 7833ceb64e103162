//! Costs and the exact checker (issue targets on one core: cost + gradient for 12 × 50
//! waypoints in a 20-obstacle scene ≤ 1 ms; exact check of one 50-waypoint trajectory with
//! interpolation ≤ 0.5 ms), and guidance steps with and without the costs' memos (the same
//! bits; the ratio is the memo's worth). Run: `cargo bench -p edmp-core --bench collision`.

use core::hint::black_box;
use criterion::{Criterion, criterion_group, criterion_main};
use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::cost::boxes::{BoxFrame, CylinderBox, Inflation};
use edmp_core::cost::{CostConfig, CostKind, CostMemo, trajectory_cost};
use edmp_core::executor::Serial;
use edmp_core::guidance::guides::EDMP_GUIDES;
use edmp_core::guidance::{GuideStep, StepRule, guide_step_on};
use edmp_core::rng::Rng;
use edmp_core::robot::kinematics::forward;
use edmp_core::robot::{HAND_FRAME, PANDA};
use edmp_core::scene::{Obstacle, Scene};

const H: usize = 50;
const BATCH: usize = 12;

/// A smooth 50-waypoint arc between two configurations around the ready pose.
fn trajectory(rng: &mut Rng) -> [[f32; 7]; H] {
    let ready = [0.0f32, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    let a: [f32; 7] = core::array::from_fn(|j| ready[j] + rng.uniform_f32(-0.6, 0.6));
    let b: [f32; 7] = core::array::from_fn(|j| ready[j] + rng.uniform_f32(-0.6, 0.6));
    core::array::from_fn(|w| {
        let t = w as f32 / (H - 1) as f32;
        core::array::from_fn(|j| a[j] + (b[j] - a[j]) * t)
    })
}

/// 20 obstacles around the arm, none touching `path` (so the checker walks every state).
fn scene(rng: &mut Rng, path: &[[f32; 7]; H]) -> Scene<'static, 64> {
    let mut scene = Scene::<64>::new();
    scene
        .push(Obstacle::cuboid([0.5, 0.0, -0.02], [1.0, 1.2, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    while scene.obstacles().len() < 20 {
        let r = rng.uniform_f32(0.3, 0.9);
        let phi = rng.uniform_f32(-3.1, 3.1);
        let center = [r * phi.cos(), r * phi.sin(), rng.uniform_f32(0.0, 0.9)];
        let o = match scene.obstacles().len() % 3 {
            0 => Obstacle::cuboid(
                center,
                [
                    rng.uniform_f32(0.05, 0.3),
                    rng.uniform_f32(0.05, 0.3),
                    rng.uniform_f32(0.05, 0.3),
                ],
                [1.0, 0.0, 0.0, 0.0],
            ),
            1 => Obstacle::cylinder(
                center,
                rng.uniform_f32(0.03, 0.1),
                rng.uniform_f32(0.1, 0.4),
                [1.0, 0.0, 0.0, 0.0],
            ),
            _ => Obstacle::sphere(center, rng.uniform_f32(0.03, 0.12)),
        }
        .unwrap();
        let mut trial = scene.clone();
        trial.push(o).unwrap();
        if check_trajectory(&edmp_core::robot::PANDA, &trial, path, &CheckConfig::default(), true)
            .unwrap()
            .is_free()
        {
            scene = trial;
        }
    }
    scene
}

fn bench(c: &mut Criterion) {
    let mut rng = Rng::new(7);
    let batch: [[[f32; 7]; H]; BATCH] = core::array::from_fn(|_| trajectory(&mut rng));
    let scene = scene(&mut rng, &batch[0]);
    let mut group = c.benchmark_group("collision");
    for (name, kind) in [("intersection", CostKind::Intersection), ("swept", CostKind::Swept)] {
        let config = CostConfig {
            kind,
            inflation: Inflation {
                clearance: 0.05,
                expansion: 0.2,
            },
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
        };
        let total: f32 = batch
            .iter()
            .map(|t| trajectory_cost(&PANDA, &scene, t, &config, None).unwrap())
            .sum();
        assert!(total > 0.0, "the bench scene must make the {name} cost work");
        group.bench_function(format!("{name} cost+gradient, 12x50 waypoints, 20 obstacles"), |b| {
            let mut grad = [[0.0f32; 7]; H];
            b.iter(|| {
                let mut sum = 0.0;
                for t in black_box(&batch) {
                    sum += trajectory_cost(&PANDA, &scene, t, &config, Some(&mut grad)).unwrap();
                }
                sum
            })
        });
    }
    // The planner's gradient steps at one t (4 after a denoising step at t = 100, a 24-step
    // stretch of the refinement at t = 1), with and without a memo per row: the same rows
    // (asserted), less work where a row touches an obstacle along a few of its segments and not
    // the others. "one cube": every row is the first arc, whose hand passes through a 12 cm cube
    // at its middle waypoint (as after denoising, when most of a candidate is free); in the
    // 20-obstacle scene above most segments of most rows touch something.
    let mut cube = Scene::<64>::new();
    let hand = forward(&PANDA, &batch[0][H / 2]).unwrap().frames[HAND_FRAME].translation;
    cube.push(Obstacle::cuboid(hand.into(), [0.12; 3], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    let first = [batch[0]; BATCH];
    let rule = StepRule {
        step_limit: 0.1,
        cylinder: CylinderBox::Enclosing,
        frame: BoxFrame::Obstacle,
    };
    let count = |t: u16| if t == 1 { 24 } else { 4 };
    let steps = |scene: &Scene<64>, rows: &[[[f32; 7]; H]; BATCH], t: u16, with_memos: bool| {
        let mut rows = *rows;
        let mut grads = [[[0.0f32; 7]; H]; BATCH];
        let mut settled = [false; BATCH];
        let mut memos = [CostMemo::NONE; BATCH];
        let memos = if with_memos { &mut memos[..] } else { &mut [][..] };
        for _ in 0..count(t) {
            guide_step_on(
                &Serial,
                &PANDA,
                scene,
                &mut rows,
                &mut grads,
                &GuideStep {
                    guides: &EDMP_GUIDES,
                    t,
                    rule,
                },
                &mut settled,
                memos,
            )
            .unwrap();
        }
        rows
    };
    for (scene_name, scene, rows) in [("one cube", &cube, &first), ("20 obstacles", &scene, &batch)] {
        for t in [1, 100] {
            assert!(
                steps(scene, rows, t, true) == steps(scene, rows, t, false),
                "the memos changed the rows at t = {t}, {scene_name}"
            );
            for with_memos in [false, true] {
                let name = format!(
                    "{} guidance steps of the 12 guides, {scene_name}, t = {t}, {}",
                    count(t),
                    if with_memos { "with memos" } else { "without" }
                );
                group.bench_function(name, |b| b.iter(|| steps(scene, rows, black_box(t), with_memos)));
            }
        }
    }
    let report = check_trajectory(
        &edmp_core::robot::PANDA,
        &scene,
        &batch[0],
        &CheckConfig::default(),
        false,
    )
    .unwrap();
    assert!(report.is_free());
    group.bench_function(
        format!("exact check, 50 waypoints ({} states), 20 obstacles", report.states),
        |b| {
            b.iter(|| {
                check_trajectory(
                    &edmp_core::robot::PANDA,
                    &scene,
                    black_box(&batch[0]),
                    &CheckConfig::default(),
                    true,
                )
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
