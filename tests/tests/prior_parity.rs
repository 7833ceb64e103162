//! The no_std int8 UNet against PyTorch (`tests/fixtures/prior_parity.json` for the Panda,
//! `prior_parity_NAME.json` for another arm, written by `weights/prior/parity.py` from the
//! committed weights).
//!
//! The fixture holds, per case, the fake-quantized model's ε (int8 weights × scale, float
//! activations: the same arithmetic as `edmp-core`, in another order) and the float model's.

use edmp_core::path::{HORIZON, Path};
use edmp_core::prior::{Network, Scratch, TimeEmbedding, predict_noise};
use serde::Deserialize;

/// Largest |rust − fake-quant| over a case, relative to the case's largest |ε|.
const PARITY_REL_TOL: f64 = 1e-3;

#[derive(Deserialize)]
struct Case {
    t: u16,
    x: Vec<Vec<f32>>,
    eps_float: Vec<Vec<f64>>,
    eps_fake_quant: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct Fixture {
    cases: Vec<Case>,
    int8_vs_float_max_relative: f64,
}

fn worst<const J: usize>(got: &Path<J>, want: &[Vec<f64>]) -> f64 {
    assert!(want.iter().all(|w| w.len() == J), "{J} joints per waypoint");
    let scale = want.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = got
        .iter()
        .flatten()
        .zip(want.iter().flatten())
        .fold(0.0f64, |m, (g, w)| m.max((f64::from(*g) - w).abs()));
    diff / scale
}

/// Runs every case of the fixture at `path` through `predict` (one trajectory at step `t`).
fn parity<const J: usize>(path: &str, predict: impl Fn(&Path<J>, u16) -> Path<J>) {
    let fixture: Fixture = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert!(fixture.cases.len() >= 8);
    let (mut worst_fq, mut worst_float) = (0.0f64, 0.0f64);
    for case in &fixture.cases {
        assert_eq!(case.x.len(), HORIZON);
        let x: Path<J> = core::array::from_fn(|w| case.x[w].clone().try_into().expect("J joints"));
        let eps = predict(&x, case.t);
        let (fq, float) = (worst(&eps, &case.eps_fake_quant), worst(&eps, &case.eps_float));
        assert!(
            fq <= PARITY_REL_TOL,
            "{path} t = {}: relative error {fq:.3e} against the fake-quantized model; \
             were the weights retrained without rerunning weights/prior/parity.py?",
            case.t
        );
        worst_fq = worst_fq.max(fq);
        worst_float = worst_float.max(float);
    }
    println!(
        "{path}: {} cases: rust vs fake-quant {worst_fq:.2e}, rust vs float {worst_float:.2e} \
         (fixture's fake-quant vs float {:.2e}), relative to each case's max |eps|",
        fixture.cases.len(),
        fixture.int8_vs_float_max_relative
    );
}

/// [`parity`] through an arm's [`Network`].
fn network_parity<const J: usize>(network: &Network<J>, path: &str) {
    parity::<J>(path, |x, t| {
        let mut scratch = Scratch::<1>::new();
        let time = network.time(t).unwrap();
        let mut eps = [[[0.0; J]; HORIZON]];
        network.predict_noise(&[*x], &time, &mut scratch, &mut eps).unwrap();
        eps[0]
    });
}

#[test]
fn int8_network_matches_the_fake_quantized_pytorch_model() {
    // The Panda's through the free functions the planner calls.
    parity::<7>(
        concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/prior_parity.json"),
        |x, t| {
            let mut scratch = Scratch::<1>::new();
            let time = TimeEmbedding::new(t).unwrap();
            let mut eps = [[[0.0; 7]; HORIZON]];
            predict_noise(&[*x], &time, &mut scratch, &mut eps).unwrap();
            eps[0]
        },
    );
}

#[test]
fn iiwa7_network_matches_its_pytorch_model() {
    let network = edmp_core::prior::arms::iiwa7::NETWORK.expect("weights/iiwa7 holds a trained prior");
    assert!(network.weights_intact());
    network_parity(
        network,
        concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/prior_parity_iiwa7.json"),
    );
}

#[test]
fn xarm6_network_matches_its_pytorch_model() {
    let network = edmp_core::prior::arms::xarm6::NETWORK.expect("weights/xarm6 holds a trained prior");
    assert!(network.weights_intact());
    network_parity(
        network,
        concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/prior_parity_xarm6.json"),
    );
}
