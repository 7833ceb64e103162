//! Bit-identical sampling: a fixed unguided run hashes to the same value on every target and
//! build (x86_64 baseline, x86-64-v3, thumbv7em; scripts/firmware checks the last under QEMU). The
//! golden value changes only when the committed weights or the network's arithmetic do.

use edmp_core::path::{HORIZON, Path};
use edmp_core::prior::{Sampler, Scratch, sample};
use edmp_core::rng::Rng;

/// Hashes of the run below with the committed weights (DDIM K = 10, strided K = 10, ancestral).
const GOLDEN_DDIM_10: u64 = 0xde6d_4bac_6c29_f861;
const GOLDEN_STRIDED_10: u64 = 0xfc26_4565_df39_c315;
const GOLDEN_ANCESTRAL: u64 = 0x5e8e_f490_0830_addf;

/// FNV-1a over the f32 bit patterns, waypoint-major, trajectory by trajectory.
fn hash(paths: &[Path]) -> u64 {
    paths.iter().flatten().flatten().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
        v.to_bits()
            .to_le_bytes()
            .iter()
            .fold(h, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3))
    })
}

#[test]
fn a_fixed_sampling_run_hashes_to_its_golden_value() {
    let start = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    let goal = [0.9, 0.3, -0.2, -1.6, 0.1, 2.0, 0.3];
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut out: [Path; 4] = [[[0.0; 7]; HORIZON]; 4];
    let mut hashes = Vec::new();
    for sampler in [
        Sampler::Ddim { steps: 10 },
        Sampler::Strided { steps: 10 },
        Sampler::Ancestral,
    ] {
        sample(sampler, &start, &goal, &mut Rng::new(20261122), &mut scratch, &mut out).unwrap();
        hashes.push(hash(&out));
    }
    println!("sampling hashes: {hashes:#018x?}");
    assert_eq!(
        hashes,
        [GOLDEN_DDIM_10, GOLDEN_STRIDED_10, GOLDEN_ANCESTRAL],
        "the sampling bits changed: if weights/prior was retrained on purpose, update the golden values; \
         otherwise the arithmetic changed (an FMA, a reordered sum, a different libm)"
    );
}
