//! The prior generator: safetensors reading, the int8 quantization (the same integers as the
//! PyTorch side), and the committed weights turned into tables.

use edmp_codegen::prior::{fnv1a, generate_prior, quantize_rows, read_safetensors};
use std::path::{Path, PathBuf};

fn prior_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../weights/prior")
}

/// A safetensors file of the given F32 tensors.
fn safetensors(tensors: &[(&str, &[usize], &[f32])]) -> Vec<u8> {
    let mut header = String::from("{");
    let mut data = Vec::new();
    for (i, (name, shape, values)) in tensors.iter().enumerate() {
        let begin = data.len();
        for v in *values {
            data.extend_from_slice(&v.to_le_bytes());
        }
        if i > 0 {
            header.push(',');
        }
        header.push_str(&format!(
            "\"{name}\":{{\"dtype\":\"F32\",\"shape\":{shape:?},\"data_offsets\":[{begin},{}]}}",
            data.len()
        ));
    }
    header.push('}');
    let mut out = (header.len() as u64).to_le_bytes().to_vec();
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(&data);
    out
}

#[test]
fn quantization_is_symmetric_per_row_and_rounds_half_to_even() {
    // Row 0: max |w| = 1.27, scale 0.01; 0.025 / 0.01 = 2.5 rounds to 2, -0.035 → -3.5 → -4.
    // Row 1: all zero, scale 1 (no division by zero). Row 2: a single extreme value → ±127.
    let w = [1.27f32, 0.025, -0.035, 0.0, 0.0, 0.0, 0.0, 0.0, -3.0, 0.0, 1.0, 0.0];
    let (q, scale) = quantize_rows(&w, 3);
    assert_eq!(scale[1], 1.0);
    assert_eq!(scale[2], 3.0 / 127.0);
    assert_eq!(
        &q[0..4],
        &[
            127,
            (0.025f32 / scale[0]).round_ties_even() as i8,
            (-0.035f32 / scale[0]).round_ties_even() as i8,
            0
        ]
    );
    assert_eq!(&q[4..8], &[0, 0, 0, 0]);
    assert_eq!(q[8], -127);
    assert_eq!(q[10], (1.0f32 / scale[2]).round_ties_even() as i8);
    // Dequantized values stay within half a step of the float weights.
    for (i, (v, qv)) in w.iter().zip(&q).enumerate() {
        let s = scale[i / 4];
        assert!((f32::from(*qv) * s - v).abs() <= 0.5 * s + 1e-7, "{i}");
    }
}

#[test]
fn safetensors_round_trip_and_refusals() {
    let dir = std::env::temp_dir().join(format!("edmp-codegen-prior-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("t.safetensors");
    std::fs::write(
        &path,
        safetensors(&[
            ("a.weight", &[2, 3], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
            ("b", &[1], &[-1.5]),
        ]),
    )
    .unwrap();
    let t = read_safetensors(&path).unwrap();
    assert_eq!(t["a.weight"].shape, vec![2, 3]);
    assert_eq!(t["a.weight"].data[5], 6.0);
    assert_eq!(t["b"].data, vec![-1.5]);

    let mut truncated = safetensors(&[("a", &[4], &[1.0, 2.0, 3.0, 4.0])]);
    truncated.truncate(truncated.len() - 3);
    std::fs::write(&path, truncated).unwrap();
    let err = read_safetensors(&path).unwrap_err();
    assert!(err.contains("past the end"), "{err}");

    let half = safetensors(&[("a", &[1], &[1.0])]);
    let text = String::from_utf8_lossy(&half).replace("F32", "F16");
    std::fs::write(&path, text.as_bytes()).unwrap();
    let err = read_safetensors(&path).unwrap_err();
    assert!(err.contains("dtype F16"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn committed_weights_generate_tables_whose_blob_requantizes_exactly() {
    let generated = generate_prior(&prior_dir(), "weights/prior", "prior.bin").expect("the committed prior generates");
    let tensors = read_safetensors(&prior_dir().join("prior.safetensors")).unwrap();
    // Every conv/linear weight is in the blob once, as int8.
    let quantized: usize = tensors
        .iter()
        .filter(|(k, t)| k.ends_with(".weight") && t.shape.len() >= 2)
        .map(|(_, t)| t.data.len())
        .sum();
    assert_eq!(generated.blob.len(), quantized);
    assert!(generated.blob.len() <= 1 << 20, "int8 weights must fit 1 MiB");
    assert!(
        generated
            .source
            .contains(&format!("WEIGHTS_FNV1A: u64 = {:#018x}", fnv1a(&generated.blob)))
    );
    // The first tensor the emitter writes is `time_in.weight` (fout × fin): its integers open the blob.
    let time_in = &tensors["time_in.weight"];
    let (q, _) = quantize_rows(&time_in.data, time_in.shape[0]);
    assert_eq!(
        &generated.blob[..q.len()],
        q.iter().map(|v| *v as u8).collect::<Vec<_>>().as_slice()
    );
}

#[test]
fn a_network_that_disagrees_with_its_json_is_refused() {
    let dir = std::env::temp_dir().join(format!("edmp-codegen-prior-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(prior_dir().join("prior.safetensors"), dir.join("prior.safetensors")).unwrap();
    let json = std::fs::read_to_string(prior_dir().join("prior.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let dims = v["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap())
        .collect::<Vec<_>>();
    let mut bad = v.clone();
    bad["dims"] = serde_json::json!(dims.iter().map(|d| d * 2).collect::<Vec<_>>());
    std::fs::write(dir.join("prior.json"), bad.to_string()).unwrap();
    let err = generate_prior(&dir, "tmp", "prior.bin").unwrap_err();
    assert!(err.contains("has shape"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
