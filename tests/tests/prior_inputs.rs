//! The prior on arbitrary input: never a panic, never a NaN passed on as a result.

use edmp_core::Error;
use edmp_core::path::{HORIZON, Path};
use edmp_core::prior::{Sampler, Scratch, TimeEmbedding, predict_noise, sample};
use edmp_core::rng::Rng;
use proptest::prelude::*;

fn path_from(values: &[f32]) -> Path {
    core::array::from_fn(|w| core::array::from_fn(|j| values[(w * 7 + j) % values.len()]))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Any finite input (up to ±1e30, far past any joint angle) gives a finite ε or a typed
    /// overflow; a non-finite entry is refused by name.
    #[test]
    fn any_finite_input_gives_finite_noise_or_a_typed_error(
        values in prop::collection::vec(prop_oneof![-1e30f32..1e30, -10.0f32..10.0], 1..64),
        t in 1u16..=255,
        poison in prop::option::of((0usize..HORIZON, 0usize..7, prop_oneof![Just(f32::NAN), Just(f32::INFINITY)])),
    ) {
        let mut x = path_from(&values);
        if let Some((w, j, v)) = poison {
            x[w][j] = v;
        }
        let time = TimeEmbedding::new(t).unwrap();
        let mut eps = [[[0.0f32; 7]; HORIZON]];
        match predict_noise(&[x], &time, &mut Scratch::<1>::new(), &mut eps) {
            Ok(()) => prop_assert!(eps[0].iter().flatten().all(|v| v.is_finite())),
            Err(Error::NonFiniteJoint { joint }) => prop_assert_eq!(Some(usize::from(joint)), poison.map(|p| p.1)),
            Err(Error::Overflow) => prop_assert!(poison.is_none()),
            Err(e) => prop_assert!(false, "unexpected {e:?}"),
        }
    }

    /// Sampling between arbitrary finite ends with any step count stays finite or says why.
    #[test]
    fn sampling_any_ends_stays_finite(
        start in prop::array::uniform7(-4.0f32..4.0),
        goal in prop::array::uniform7(-4.0f32..4.0),
        steps in 1u16..=6,
        seed in any::<u64>(),
    ) {
        let mut out = [[[0.0f32; 7]; HORIZON]; 2];
        for sampler in [Sampler::Strided { steps }, Sampler::Ddim { steps }] {
            sample(sampler, &start, &goal, &mut Rng::new(seed), &mut Scratch::<2>::new(), &mut out).unwrap();
            prop_assert!(out.iter().flatten().flatten().all(|v| v.is_finite()));
            prop_assert_eq!(out[0][0], start);
            prop_assert_eq!(out[1][HORIZON - 1], goal);
        }
    }
}

#[test]
fn bad_sampler_settings_are_typed_errors() {
    let mut out = [[[0.0f32; 7]; HORIZON]; 1];
    let q = [0.0f32; 7];
    let mut scratch = Scratch::<1>::new();
    let mut rng = Rng::new(1);
    assert_eq!(
        sample(Sampler::Strided { steps: 0 }, &q, &q, &mut rng, &mut scratch, &mut out),
        Err(Error::BadParameter)
    );
    let mut nan = q;
    nan[5] = f32::NAN;
    assert_eq!(
        sample(Sampler::Ancestral, &q, &nan, &mut rng, &mut scratch, &mut out),
        Err(Error::NonFiniteJoint { joint: 5 })
    );
}
