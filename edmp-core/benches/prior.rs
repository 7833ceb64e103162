//! The int8 UNet: one forward per trajectory (issue target ≤ 0.5 ms on one core) and a full
//! unguided sampling of 12 trajectories at several step counts K. Run:
//! `cargo bench -p edmp-core --bench prior`. The sizes (MACs, weight bytes, scratch) print first.

use core::hint::black_box;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use edmp_core::path::{HORIZON, Path};
use edmp_core::prior::{
    MACS, PARAMETERS, Sampler, Scratch, TimeEmbedding, WEIGHT_BYTES, initial_noise, predict_noise, sample,
};
use edmp_core::rng::Rng;

const START: [f32; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
const GOAL: [f32; 7] = [0.9, 0.3, -0.2, -1.6, 0.1, 2.0, 0.3];

fn bench(c: &mut Criterion) {
    println!(
        "prior: {PARAMETERS} parameters, {WEIGHT_BYTES} bytes of int8 weights, {MACS} MAC per forward; \
         scratch {} bytes for 1 trajectory, {} for 12",
        Scratch::<1>::BYTES,
        Scratch::<12>::BYTES
    );
    let mut rng = Rng::new(1);
    let mut x: [Path; 12] = [[[0.0; 7]; HORIZON]; 12];
    for x in &mut x {
        initial_noise(x, &mut rng, &START, &GOAL);
    }
    let mut one = Box::new(Scratch::<1>::new());
    let mut two = Box::new(Scratch::<2>::new());
    let mut four = Box::new(Scratch::<4>::new());
    let mut scratch = Box::new(Scratch::<12>::new());
    let mut eps: [Path; 12] = [[[0.0; 7]; HORIZON]; 12];
    let time = TimeEmbedding::new(128).unwrap();
    let mut group = c.benchmark_group("prior");
    group.throughput(Throughput::Elements(1));
    group.bench_function("forward/batch of 1", |b| {
        b.iter(|| predict_noise(black_box(&[x[0]]), &time, &mut one, &mut [eps[0]]))
    });
    group.throughput(Throughput::Elements(12));
    group.bench_function("forward/batch of 12, 1 at a time", |b| {
        b.iter(|| predict_noise(black_box(&x), &time, &mut one, &mut eps))
    });
    group.bench_function("forward/batch of 12, 2 at a time", |b| {
        b.iter(|| predict_noise(black_box(&x), &time, &mut two, &mut eps))
    });
    group.bench_function("forward/batch of 12, 4 at a time", |b| {
        b.iter(|| predict_noise(black_box(&x), &time, &mut four, &mut eps))
    });
    group.bench_function("forward/batch of 12, 12 at a time", |b| {
        b.iter(|| predict_noise(black_box(&x), &time, &mut scratch, &mut eps))
    });
    group.throughput(Throughput::Elements(1));
    group.bench_function("time embedding", |b| b.iter(|| TimeEmbedding::new(black_box(128))));
    group.sample_size(10);
    for k in [5u16, 10, 25, 50] {
        group.bench_function(format!("sample 12 trajectories/strided K={k}"), |b| {
            let mut out = [[[0.0f32; 7]; HORIZON]; 12];
            b.iter(|| {
                sample(
                    Sampler::Strided { steps: k },
                    &START,
                    &GOAL,
                    &mut Rng::new(2),
                    &mut scratch,
                    &mut out,
                )
            })
        });
    }
    group.bench_function("sample 12 trajectories/ancestral K=255", |b| {
        let mut out = [[[0.0f32; 7]; HORIZON]; 12];
        b.iter(|| {
            sample(
                Sampler::Ancestral,
                &START,
                &GOAL,
                &mut Rng::new(2),
                &mut scratch,
                &mut out,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
