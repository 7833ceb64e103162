//! A std-only stand-in for the cargo-fuzz targets `ply`, `pcd`, `obj` and `stl` (fuzz/), for
//! machines without cargo-fuzz: each geometry reader over random and mutated bytes (the seeds
//! in fuzz/seeds/<target>/) for `EDMP_FUZZ_SECS` seconds (default 60) each. It checks what the
//! targets check: no panic, finite coordinates, indices in range, and a message on error. Run
//! with `cargo test -p edmp-host --lib formats::robustness -- --ignored --nocapture`.

use super::cloud::{parse_pcd, parse_ply_points};
use super::file_error::FileError;
use super::mesh_file::{TriangleMesh, parse_obj, parse_ply_mesh, parse_stl};
use core::time::Duration;
use std::time::Instant;

/// One reader with its checks.
type Target = fn(&[u8]);

/// A small xorshift generator: reproducible, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Words that steer the readers into their branches.
const WORDS: &[&[u8]] = &[
    b"\n",
    b" ",
    b"\r\n",
    b"0",
    b"1",
    b"3",
    b"-1",
    b"255",
    b"4294967295",
    b"99999999999999999999",
    b"nan",
    b"inf",
    b"1e39",
    b"-0.5",
    b"/",
    b"//",
    b"ply",
    b"end_header",
    b"element vertex ",
    b"element face ",
    b"property float x",
    b"property list uchar int vertex_indices",
    b"property double",
    b"format ascii 1.0",
    b"format binary_little_endian 1.0",
    b"DATA ascii",
    b"DATA binary",
    b"POINTS ",
    b"FIELDS x y z",
    b"SIZE 4 4 4",
    b"TYPE F F F",
    b"COUNT 1 1 1",
    b"v ",
    b"f ",
    b"solid",
    b"facet normal",
    b"outer loop",
    b"vertex ",
    b"endloop",
    b"endfacet",
    b"endsolid",
];

/// One mutation of `data`: flip, set, insert or delete bytes, splice a word, cut, or repeat.
fn mutate(rng: &mut Rng, data: &mut Vec<u8>) {
    let at = rng.below(data.len() + 1);
    let last = at.min(data.len().saturating_sub(1));
    match rng.below(8) {
        0 if !data.is_empty() => data[last] ^= 1 << rng.below(8),
        1 if !data.is_empty() => data[last] = [0, 0xff, 0x7f, 0x80, b'\n', b' '][rng.below(6)],
        2 => data.insert(at, rng.next() as u8),
        3 if at < data.len() => {
            let end = (at + 1 + rng.below(8)).min(data.len());
            data.drain(at..end);
        }
        4 | 5 => {
            let word = WORDS[rng.below(WORDS.len())];
            data.splice(at..at, word.iter().copied());
        }
        6 => data.truncate(at),
        _ if at < data.len() => {
            let end = (at + 1 + rng.below(64)).min(data.len());
            let chunk = data[at..end].to_vec();
            data.splice(at..at, chunk);
        }
        _ => data.push(rng.next() as u8),
    }
}

fn check_points(result: Result<Vec<[f32; 3]>, FileError>) {
    match result {
        Ok(points) => assert!(points.iter().flatten().all(|v| v.is_finite())),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

fn check_mesh(result: Result<TriangleMesh, FileError>) {
    match result {
        Ok(mesh) => {
            assert!(mesh.vertices.iter().flatten().all(|v| v.is_finite()));
            assert!(
                mesh.triangles
                    .iter()
                    .flatten()
                    .all(|&i| (i as usize) < mesh.vertices.len())
            );
            assert!(mesh.degenerate_count() <= mesh.triangles.len());
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// Runs `target` over random and mutated seeds until the time is up; returns the executions.
fn run(name: &str, seconds: u64, target: Target) -> u64 {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/seeds")
        .join(name);
    let mut seeds: Vec<Vec<u8>> = std::fs::read_dir(&dir)
        .map(|entries| entries.filter_map(|e| std::fs::read(e.ok()?.path()).ok()).collect())
        .unwrap_or_default();
    seeds.push(Vec::new());
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ name.len() as u64);
    let (start, mut executions) = (Instant::now(), 0u64);
    while start.elapsed() < Duration::from_secs(seconds) {
        let mut data = if rng.below(16) == 0 {
            (0..rng.below(512)).map(|_| rng.next() as u8).collect()
        } else {
            seeds[rng.below(seeds.len())].clone()
        };
        for _ in 0..1 + rng.below(8) {
            mutate(&mut rng, &mut data);
        }
        if std::panic::catch_unwind(|| target(&data)).is_err() {
            let path = std::env::temp_dir().join(format!("edmp-{name}-crash.bin"));
            let _ = std::fs::write(&path, &data);
            panic!("{name}: a panic on the input saved in {}", path.display());
        }
        executions += 1;
    }
    executions
}

#[test]
#[ignore = "runs for minutes; the cargo-fuzz targets do this better where cargo-fuzz is installed"]
fn readers_survive_random_and_mutated_bytes() {
    let seconds = std::env::var("EDMP_FUZZ_SECS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let targets: [(&str, Target); 4] = [
        ("ply", |d| {
            check_points(parse_ply_points(d));
            check_mesh(parse_ply_mesh(d));
        }),
        ("pcd", |d| check_points(parse_pcd(d))),
        ("obj", |d| check_mesh(parse_obj(d))),
        ("stl", |d| check_mesh(parse_stl(d))),
    ];
    for (name, target) in targets {
        let executions = run(name, seconds, target);
        println!("{name}: {executions} executions in {seconds} s");
    }
}
