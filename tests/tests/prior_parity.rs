//! The no_std int8 UNet against PyTorch (`tests/fixtures/prior_parity.json`, written by
//! `weights/prior/parity.py` from the committed weights).
//!
//! The fixture holds, per case, the fake-quantized model's ε (int8 weights × scale, float
//! activations: the same arithmetic as `edmp-core`, in another order) and the float model's.

use edmp_core::path::{HORIZON, Path};
use edmp_core::prior::{Scratch, TimeEmbedding, predict_noise};
use serde::Deserialize;

/// Largest |rust − fake-quant| over a case, relative to the case's largest |ε|.
const PARITY_REL_TOL: f64 = 1e-3;

#[derive(Deserialize)]
struct Case {
    t: u16,
    x: Vec<[f32; 7]>,
    eps_float: Vec<[f64; 7]>,
    eps_fake_quant: Vec<[f64; 7]>,
}

#[derive(Deserialize)]
struct Fixture {
    cases: Vec<Case>,
    int8_vs_float_max_relative: f64,
}

fn worst(got: &Path, want: &[[f64; 7]]) -> f64 {
    let scale = want.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = got
        .iter()
        .flatten()
        .zip(want.iter().flatten())
        .fold(0.0f64, |m, (g, w)| m.max((f64::from(*g) - w).abs()));
    diff / scale
}

#[test]
fn int8_network_matches_the_fake_quantized_pytorch_model() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/prior_parity.json");
    let fixture: Fixture = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert!(fixture.cases.len() >= 8);
    let mut scratch = Scratch::<1>::new();
    let (mut worst_fq, mut worst_float) = (0.0f64, 0.0f64);
    for case in &fixture.cases {
        assert_eq!(case.x.len(), HORIZON);
        let x: Path = case.x.clone().try_into().unwrap();
        let time = TimeEmbedding::new(case.t).unwrap();
        let mut eps = [[[0.0; 7]; HORIZON]];
        predict_noise(&[x], &time, &mut scratch, &mut eps).unwrap();
        let eps = eps[0];
        let (fq, float) = (worst(&eps, &case.eps_fake_quant), worst(&eps, &case.eps_float));
        assert!(
            fq <= PARITY_REL_TOL,
            "t = {}: relative error {fq:.3e} against the fake-quantized model; \
             were the weights retrained without rerunning weights/prior/parity.py?",
            case.t
        );
        worst_fq = worst_fq.max(fq);
        worst_float = worst_float.max(float);
    }
    println!(
        "{} cases: rust vs fake-quant {worst_fq:.2e}, rust vs float {worst_float:.2e} \
         (fixture's fake-quant vs float {:.2e}), relative to each case's max |eps|",
        fixture.cases.len(),
        fixture.int8_vs_float_max_relative
    );
}
