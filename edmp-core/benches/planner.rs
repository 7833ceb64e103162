//! One guided plan (EDMP's 12 guides, one row each) on the wall example, at a few step counts.
//! Run: `cargo bench -p edmp-core --bench planner`.

use criterion::{Criterion, criterion_group, criterion_main};
use edmp_core::guidance::guides::EDMP_GUIDES;
use edmp_core::planner::{GuidanceSchedule, PlanConfig, Request, Workspace, plan};
use edmp_core::prior::{Sampler, Scratch};
use edmp_core::rng::Rng;
use edmp_core::scene::{Obstacle, Scene};

fn bench(c: &mut Criterion) {
    println!(
        "planner memory, 12 rows: Workspace {} B + Plan {} B (its candidates) + network Scratch<1> {} B \
         (Scratch<4> {} B); stack frames aside",
        core::mem::size_of::<Workspace<12>>(),
        core::mem::size_of::<edmp_core::planner::Plan<12>>(),
        Scratch::<1>::BYTES,
        Scratch::<4>::BYTES,
    );
    let mut scene = Scene::<8>::new();
    scene
        .push(Obstacle::cuboid([0.5, 0.0, -0.01], [1.2, 1.6, 0.02], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    scene
        .push(Obstacle::cuboid([0.55, 0.0, 0.45], [0.3, 0.02, 0.5], [1.0, 0.0, 0.0, 0.0]).unwrap())
        .unwrap();
    let start = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    let goal = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let mut group = c.benchmark_group("planner");
    group.sample_size(10);
    let variant = |steps: u16, per_step: u8, refine: u8, step_limit: f32| PlanConfig {
        sampler: Sampler::Strided { steps },
        guidance: GuidanceSchedule::Every { per_step },
        refine,
        step_limit,
        ..PlanConfig::DEFAULT
    };
    let configs = [
        (
            "default (K=5, 8 gradient steps, 16 refinement steps)",
            PlanConfig::DEFAULT,
        ),
        (
            "K=10, 4 gradient steps, no refinement",
            variant(10, 4, 0, f32::INFINITY),
        ),
        (
            "K=25, 2 gradient steps, no refinement",
            variant(25, 2, 0, f32::INFINITY),
        ),
    ];
    for (label, config) in configs {
        group.bench_function(format!("wall, 12 guides, {label}"), |b| {
            b.iter(|| {
                plan(
                    &Request {
                        robot: &edmp_core::robot::PANDA,
                        network: edmp_core::prior::PANDA,
                        scene: &scene,
                        start: &start,
                        goal: &goal,
                        guides: &EDMP_GUIDES,
                        config: &config,
                    },
                    &mut Rng::new(1),
                    &mut scratch,
                    &mut work,
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
