//! Building a surface and fitting its guide boxes, for a 200,000-point cloud (issue 33's size:
//! the host does this once per plan, so it is part of every cloud plan's time). The cloud is
//! a shelf's surfaces sampled every 4 mm, in shuffled order as a camera's merge leaves it.
//! The splits alone are timed on one thread and on two (`split_on`, the host's way; the same
//! tree). Run: `cargo bench -p edmp-core --bench surface`.

use core::hint::black_box;
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use edmp_core::Error;
use edmp_core::cost::cover::covers;
use edmp_core::executor::Executor;
use edmp_core::rng::Rng;
use edmp_core::scene::Obstacle;
use edmp_core::surface::Surface;
use edmp_core::surface::bvh::{Key, Node, build, nodes_for, split, split_on};
use edmp_core::surface::element::Element;

/// Points on the faces of a few boards (a shelf's walls and levels), shuffled.
fn shelf_cloud(count: usize) -> Vec<Element> {
    // Boards as (centre, half extents); each sampled on its two largest faces.
    let boards: [([f32; 3], [f32; 3]); 6] = [
        ([0.6, 0.0, 0.5], [0.2, 0.4, 0.01]),
        ([0.6, 0.0, 0.8], [0.2, 0.4, 0.01]),
        ([0.6, -0.4, 0.6], [0.2, 0.01, 0.3]),
        ([0.6, 0.4, 0.6], [0.2, 0.01, 0.3]),
        ([0.8, 0.0, 0.6], [0.01, 0.4, 0.3]),
        ([0.6, 0.0, 0.3], [0.2, 0.4, 0.01]),
    ];
    let mut rng = Rng::new(7);
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        for (c, h) in &boards {
            let thin = (0..3).min_by(|&a, &b| h[a].total_cmp(&h[b])).unwrap_or(0);
            let mut p: [f32; 3] = core::array::from_fn(|k| c[k] + rng.uniform_f32(-h[k], h[k]));
            p[thin] = c[thin]
                + if rng.uniform_f32(0.0, 1.0) < 0.5 {
                    -h[thin]
                } else {
                    h[thin]
                };
            if let Ok(e) = Element::ball(p, 0.0075, 0) {
                out.push(e);
            }
        }
    }
    out.truncate(count);
    out
}

/// Two threads: the first half of the items on a scoped thread, the rest on the caller's.
struct TwoThreads;

impl Executor for TwoThreads {
    fn parts(&self) -> usize {
        2
    }

    fn each<T: Send, F: Fn(&mut T) -> Result<(), Error> + Sync>(&self, items: &mut [T], task: F) -> Result<(), Error> {
        let (first, rest) = items.split_at_mut(items.len() / 2);
        std::thread::scope(|s| {
            let other = s.spawn(|| first.iter_mut().try_for_each(&task));
            let here = rest.iter_mut().try_for_each(&task);
            other.join().unwrap_or(Err(Error::BadParameter)).and(here)
        })
    }
}

fn bench(c: &mut Criterion) {
    const N: usize = 200_000;
    let cloud = shelf_cloud(N);
    let mut pieces = cloud.clone();
    let mut nodes = vec![Node::EMPTY; nodes_for(N)];
    let mut keys = vec![Key::EMPTY; N];
    c.bench_function("bvh build, 200k balls", |b| {
        b.iter(|| black_box(build(&cloud, &mut pieces, &mut nodes, &mut keys).ok()))
    });
    let fresh: Vec<Key> = cloud
        .iter()
        .enumerate()
        .map(|(i, e)| Key::new(e.centroid().into(), i as u32))
        .collect();
    c.bench_function("bvh split, 200k keys, one thread", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |keys| black_box(split(keys, &mut nodes).ok()),
            BatchSize::LargeInput,
        )
    });
    c.bench_function("bvh split_on, 200k keys, two threads", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |keys| black_box(split_on(&TwoThreads, keys, &mut nodes).ok()),
            BatchSize::LargeInput,
        )
    });
    let used = build(&cloud, &mut pieces, &mut nodes, &mut keys).unwrap_or(0);
    let surface = Surface::new(&pieces, &nodes[..used]).expect("a tree build made");
    let mut boxes = [Obstacle::PLACEHOLDER; 24];
    c.bench_function("covers, 24 boxes, 200k balls", |b| {
        b.iter(|| black_box(covers(&surface, &mut boxes)))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
