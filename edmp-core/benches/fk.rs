//! FK and FK + adjoint timings (issue targets: FK ≤ 0.5 µs, FK + adjoint ≤ 1.5 µs per
//! configuration on one core), and inverse kinematics. Run: `cargo bench -p edmp-core --bench fk`.

use core::hint::black_box;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use edmp_core::rng::Rng;
use edmp_core::robot::ik::{IkConfig, solve};
use edmp_core::robot::kinematics::{CORNERS, CornerGradient, forward};
use edmp_core::robot::{JOINTS, MAX_BODIES, PANDA};
use edmp_core::scene::Scene;
use nalgebra::Vector3;

/// A fixed pseudo-random sequence in [0, 1), so the bench inputs are stable.
fn unit_sequence(seed: u64, n: usize) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| rng.unit_f32()).collect()
}

fn configurations(n: usize) -> Vec<[f32; JOINTS]> {
    let u = unit_sequence(1, n * JOINTS);
    (0..n)
        .map(|c| {
            core::array::from_fn(|j| {
                PANDA.soft_lower[j] + u[c * JOINTS + j] * (PANDA.soft_upper[j] - PANDA.soft_lower[j])
            })
        })
        .collect()
}

fn gradient() -> CornerGradient<f32> {
    // A corner gradient has a slot for every body of the largest arm compiled in (the Panda's
    // adjoint reads its own).
    let u = unit_sequence(2, MAX_BODIES * CORNERS * 3);
    core::array::from_fn(|b| {
        core::array::from_fn(|c| {
            let i = (b * CORNERS + c) * 3;
            Vector3::new(u[i] - 0.5, u[i + 1] - 0.5, u[i + 2] - 0.5)
        })
    })
}

fn bench(c: &mut Criterion) {
    let qs = configurations(600);
    let g = gradient();
    let mut group = c.benchmark_group("kinematics");
    group.throughput(Throughput::Elements(1));
    group.bench_function("fk/1", |b| {
        b.iter(|| forward(&edmp_core::robot::PANDA, black_box(&qs[0])))
    });
    group.bench_function("fk+corners/1", |b| {
        b.iter(|| forward(&edmp_core::robot::PANDA, black_box(&qs[0])).map(|k| k.all_corners()))
    });
    group.bench_function("fk+adjoint/1", |b| {
        b.iter(|| forward(&edmp_core::robot::PANDA, black_box(&qs[0])).and_then(|k| k.adjoint(black_box(&g))))
    });
    group.throughput(Throughput::Elements(qs.len() as u64));
    group.bench_function("fk+adjoint/600 (12 trajectories x 50 waypoints)", |b| {
        b.iter(|| {
            let mut acc = [0.0f32; JOINTS];
            for q in black_box(&qs) {
                if let Ok(dq) = forward(&edmp_core::robot::PANDA, q).and_then(|k| k.adjoint(&g)) {
                    for (a, d) in acc.iter_mut().zip(dq) {
                        *a += d;
                    }
                }
            }
            acc
        })
    });
    // Inverse kinematics of reachable TCP poses (FK of the first 100 configurations), from the
    // ready pose: the time of one solve, averaged over the 100.
    let targets: Vec<_> = qs
        .iter()
        .take(100)
        .map(|q| *forward(&edmp_core::robot::PANDA, q).unwrap().tcp())
        .collect();
    let ready = [0.0f32, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    let scene = Scene::<1>::new();
    group.throughput(Throughput::Elements(targets.len() as u64));
    group.bench_function("ik/100 reachable poses (self-collision checked)", |b| {
        b.iter(|| {
            targets
                .iter()
                .filter(|t| solve(&edmp_core::robot::PANDA, t, &ready, &scene, &IkConfig::default()).is_ok())
                .count()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
