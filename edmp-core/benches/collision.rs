//! Costs and the exact checker (issue targets on one core: cost + gradient for 12 × 50
//! waypoints in a 20-obstacle scene ≤ 1 ms; exact check of one 50-waypoint trajectory with
//! interpolation ≤ 0.5 ms). Run: `cargo bench -p edmp-core --bench collision`.

use core::hint::black_box;
use criterion::{Criterion, criterion_group, criterion_main};
use edmp_core::checker::{CheckConfig, check_trajectory};
use edmp_core::cost::{CostConfig, CostKind, trajectory_cost};
use edmp_core::geometry::{BoxFrame, CylinderBox, Inflation};
use edmp_core::rng::Rng;
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
fn scene(rng: &mut Rng, path: &[[f32; 7]; H]) -> Scene<64> {
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
        if check_trajectory(&trial, path, &CheckConfig::default(), true)
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
            .map(|t| trajectory_cost(&scene, t, &config, None).unwrap())
            .sum();
        assert!(total > 0.0, "the bench scene must make the {name} cost work");
        group.bench_function(format!("{name} cost+gradient, 12x50 waypoints, 20 obstacles"), |b| {
            let mut grad = [[0.0f32; 7]; H];
            b.iter(|| {
                let mut sum = 0.0;
                for t in black_box(&batch) {
                    sum += trajectory_cost(&scene, t, &config, Some(&mut grad)).unwrap();
                }
                sum
            })
        });
    }
    let report = check_trajectory(&scene, &batch[0], &CheckConfig::default(), false).unwrap();
    assert!(report.is_free());
    group.bench_function(
        format!("exact check, 50 waypoints ({} states), 20 obstacles", report.states),
        |b| b.iter(|| check_trajectory(&scene, black_box(&batch[0]), &CheckConfig::default(), true)),
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
