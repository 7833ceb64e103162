//! One global search (RRT-Connect, shortcuts, resampling, verification) on the planner bench's
//! wall scene, every edge judged by the exact checker. Run: `cargo bench -p edmp-core --bench search`.

use criterion::{Criterion, criterion_group, criterion_main};
use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::planner::search::{SearchConfig, SearchSpace, search};
use edmp_core::rng::Rng;
use edmp_core::robot::PANDA;
use edmp_core::robot::kinematics::Joints;
use edmp_core::scene::{Obstacle, Scene};

fn bench(c: &mut Criterion) {
    println!(
        "search memory: SearchSpace<512> {} B, SearchSpace<2048> {} B",
        SearchSpace::<512>::BYTES,
        SearchSpace::<2048>::BYTES
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
    let check = CheckConfig::DEFAULT;
    let mut edge_free = |a: &Joints<f32>, b: &Joints<f32>| {
        Ok(check_trajectory(&edmp_core::robot::PANDA, &scene, &[*a, *b], &check, true)?.is_free())
    };
    let config = SearchConfig::DEFAULT;
    let mut space = Box::new(SearchSpace::<2048>::new());
    for seed in 1..=4 {
        let o = search(
            &PANDA,
            &start,
            &goal,
            &config,
            &mut space,
            &mut Rng::new(seed),
            &mut edge_free,
        )
        .unwrap()
        .unwrap();
        println!(
            "seed {seed}: {} iterations, {} nodes, {} corners, {} oracle calls (bound {})",
            o.iterations,
            o.nodes,
            o.corners,
            o.oracle_calls,
            config.max_oracle_calls(2048)
        );
    }
    let mut group = c.benchmark_group("search");
    group.sample_size(10);
    for seed in [1u64, 2] {
        group.bench_function(format!("wall, exact checker, SearchSpace<2048>, seed {seed}"), |b| {
            b.iter(|| {
                search(
                    &PANDA,
                    &start,
                    &goal,
                    &config,
                    &mut space,
                    &mut Rng::new(seed),
                    &mut edge_free,
                )
            })
        });
    }
    // The search's own cost (nearest-node scans, shortcuts, resampling) without the checker:
    // a joint-space wall on joint 0 with a gap in joint 1, judged analytically.
    let mut wall = |a: &Joints<f32>, b: &Joints<f32>| Ok(gapped_wall(a, b));
    let (s, g) = (
        [-1.0, -1.0, 0.0, -1.5, 0.0, 1.5, 0.0],
        [1.0, -1.0, 0.0, -1.5, 0.0, 1.5, 0.0],
    );
    group.bench_function("joint-space wall with a gap, analytic oracle, seed 1", |b| {
        b.iter(|| search(&PANDA, &s, &g, &config, &mut space, &mut Rng::new(1), &mut wall))
    });
    group.finish();
}

/// The slab -0.2 <= q0 <= 0.2, open where 0.6 <= q1 <= 1.0 (exact for segments).
fn gapped_wall(a: &Joints<f32>, b: &Joints<f32>) -> bool {
    let d = b[0] - a[0];
    let (t0, t1) = if d == 0.0 {
        if a[0].abs() > 0.2 {
            return true;
        }
        (0.0, 1.0)
    } else {
        let (ta, tb) = ((-0.2 - a[0]) / d, (0.2 - a[0]) / d);
        (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
    };
    let inside = |t: f32| (0.6..=1.0).contains(&(a[1] + (b[1] - a[1]) * t));
    t0 > t1 || (inside(t0) && inside(t1))
}

criterion_group!(benches, bench);
criterion_main!(benches);
