//! The diffusion prior: reads the trained float32 safetensors and its JSON, quantizes every
//! convolution and linear weight to int8 (symmetric, one scale per output channel), and emits
//! the network description, the schedule tables and an `include_bytes!` blob of the weights.
//!
//! The quantization is the float32 arithmetic of `weights/prior/model.py::quantize`, step for
//! step (`scale = max|w| / 127`, `q = round_half_even(w / scale)`), so the integers here and the
//! fake-quantized PyTorch model that writes the parity fixture agree exactly.

use core::fmt::Write as _;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

/// One float32 tensor of the safetensors file.
#[derive(Clone, Debug)]
pub struct Tensor {
    /// Shape, outermost first.
    pub shape: Vec<usize>,
    /// Row-major values.
    pub data: Vec<f32>,
}

/// Reads a safetensors file (8-byte little-endian header length, JSON header, raw data).
/// Only float32 tensors are accepted: that is what the trainer writes.
pub fn read_safetensors(path: &Path) -> Result<BTreeMap<String, Tensor>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = |what: &str| format!("{}: not a safetensors file: {what}", path.display());
    let len_bytes: [u8; 8] = bytes
        .get(..8)
        .ok_or_else(|| bad("shorter than 8 bytes"))?
        .try_into()
        .unwrap();
    let header_len = usize::try_from(u64::from_le_bytes(len_bytes)).map_err(|_| bad("header length"))?;
    let header = bytes.get(8..8 + header_len).ok_or_else(|| bad("header past the end"))?;
    let data = &bytes[8 + header_len..];
    let header: BTreeMap<String, Value> = serde_json::from_slice(header).map_err(|e| bad(&e.to_string()))?;
    let mut out = BTreeMap::new();
    for (name, info) in header {
        if name == "__metadata__" {
            continue;
        }
        let dtype = info["dtype"].as_str().unwrap_or("");
        if dtype != "F32" {
            return Err(bad(&format!("{name} has dtype {dtype}, expected F32")));
        }
        let shape: Vec<usize> = info["shape"]
            .as_array()
            .ok_or_else(|| bad(&format!("{name}: shape")))?
            .iter()
            .map(|d| {
                d.as_u64()
                    .map(|d| d as usize)
                    .ok_or_else(|| bad(&format!("{name}: shape")))
            })
            .collect::<Result<_, _>>()?;
        let offsets = info["data_offsets"]
            .as_array()
            .ok_or_else(|| bad(&format!("{name}: offsets")))?;
        let (begin, end) = match (
            offsets.first().and_then(Value::as_u64),
            offsets.get(1).and_then(Value::as_u64),
        ) {
            (Some(b), Some(e)) => (b as usize, e as usize),
            _ => return Err(bad(&format!("{name}: offsets"))),
        };
        let raw = data
            .get(begin..end)
            .ok_or_else(|| bad(&format!("{name}: data past the end")))?;
        if raw.len() != 4 * shape.iter().product::<usize>() {
            return Err(bad(&format!("{name}: {} bytes for shape {shape:?}", raw.len())));
        }
        let values = raw
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        out.insert(name, Tensor { shape, data: values });
    }
    Ok(out)
}

/// Per-output-channel symmetric int8 of `rows` rows of equal length (row = output channel).
/// Returns the integers, row-major, and one scale per row.
pub fn quantize_rows(values: &[f32], rows: usize) -> (Vec<i8>, Vec<f32>) {
    let per_row = values.len() / rows;
    let mut q = Vec::with_capacity(values.len());
    let mut scales = Vec::with_capacity(rows);
    for row in values.chunks_exact(per_row) {
        let maxabs = row.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let scale = if maxabs > 0.0 { maxabs / 127.0 } else { 1.0 };
        for v in row {
            q.push((v / scale).round_ties_even().clamp(-127.0, 127.0) as i8);
        }
        scales.push(scale);
    }
    (q, scales)
}

/// 64-bit FNV-1a, the checksum the generated tables carry for their weight blob.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// What [`generate_prior`] produces: the Rust source and the weight blob it `include_bytes!`s.
#[derive(Clone, Debug)]
pub struct GeneratedPrior {
    /// Rust source to `include!`; it reads the blob from `OUT_DIR/` under the name given.
    pub source: String,
    /// The int8 weights, in the order the source's offsets name.
    pub blob: Vec<u8>,
    /// Every file read, for `cargo:rerun-if-changed`.
    pub inputs: Vec<PathBuf>,
}

struct Emitter<'a> {
    tensors: &'a BTreeMap<String, Tensor>,
    blob: Vec<u8>,
    macs: usize,
    used: Vec<String>,
}

impl Emitter<'_> {
    fn tensor(&mut self, name: &str, shape: &[usize]) -> Result<&Tensor, String> {
        let t = self
            .tensors
            .get(name)
            .ok_or_else(|| format!("prior: missing tensor {name}"))?;
        if t.shape != shape {
            return Err(format!("prior: {name} has shape {:?}, expected {shape:?}", t.shape));
        }
        self.used.push(name.to_owned());
        Ok(t)
    }

    fn floats(values: &[f32]) -> String {
        let mut s = String::from("&[");
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                s.push_str(", ");
            }
            // `{:?}` prints the shortest text that parses back to the same f32.
            let _ = write!(s, "{v:?}");
        }
        s.push(']');
        s
    }

    fn weights(&mut self, q: &[i8]) -> String {
        let offset = self.blob.len();
        self.blob.extend(q.iter().map(|v| *v as u8));
        format!("part({offset}, {})", q.len())
    }

    /// A Conv1d `cout × cin × k`, or (`transposed`) a ConvTranspose1d stored `cin × cout × k`,
    /// emitted output-channel-major either way. `out_len` counts MACs.
    fn conv(
        &mut self,
        name: &str,
        cin: usize,
        cout: usize,
        k: usize,
        mac_len: usize,
        transposed: bool,
    ) -> Result<String, String> {
        let shape = if transposed { [cin, cout, k] } else { [cout, cin, k] };
        let w = self.tensor(&format!("{name}.weight"), &shape)?.data.clone();
        let bias = self.tensor(&format!("{name}.bias"), &[cout])?.data.clone();
        let rows: Vec<f32> = if transposed {
            let mut r = Vec::with_capacity(w.len());
            for o in 0..cout {
                for i in 0..cin {
                    r.extend_from_slice(&w[(i * cout + o) * k..(i * cout + o + 1) * k]);
                }
            }
            r
        } else {
            w
        };
        let (q, scale) = quantize_rows(&rows, cout);
        self.macs += mac_len * cin * cout * k;
        Ok(format!(
            "Conv {{ cin: {cin}, cout: {cout}, k: {k}, weights: {}, scale: {}, bias: {} }}",
            self.weights(&q),
            Self::floats(&scale),
            Self::floats(&bias)
        ))
    }

    fn linear(&mut self, name: &str, fin: usize, fout: usize) -> Result<String, String> {
        let w = self.tensor(&format!("{name}.weight"), &[fout, fin])?.data.clone();
        let bias = self.tensor(&format!("{name}.bias"), &[fout])?.data.clone();
        let (q, scale) = quantize_rows(&w, fout);
        self.macs += fin * fout;
        Ok(format!(
            "Linear {{ fin: {fin}, fout: {fout}, weights: {}, scale: {}, bias: {} }}",
            self.weights(&q),
            Self::floats(&scale),
            Self::floats(&bias)
        ))
    }

    fn block(&mut self, name: &str, cin: usize, cout: usize, k: usize, len: usize) -> Result<String, String> {
        let conv = self.conv(&format!("{name}.conv"), cin, cout, k, len, false)?;
        let gamma = self.tensor(&format!("{name}.norm.weight"), &[cout])?.data.clone();
        let beta = self.tensor(&format!("{name}.norm.bias"), &[cout])?.data.clone();
        Ok(format!(
            "ConvBlock {{ conv: {conv}, gamma: {}, beta: {} }}",
            Self::floats(&gamma),
            Self::floats(&beta)
        ))
    }

    fn res(&mut self, name: &str, cin: usize, cout: usize, cfg: &Config, len: usize) -> Result<String, String> {
        let block0 = self.block(&format!("{name}.block0"), cin, cout, cfg.kernel, len)?;
        let block1 = self.block(&format!("{name}.block1"), cout, cout, cfg.kernel, len)?;
        let time = self.linear(&format!("{name}.time"), cfg.time_dim, cout)?;
        let residual = if cin != cout {
            format!(
                "Some({})",
                self.conv(&format!("{name}.residual"), cin, cout, 1, len, false)?
            )
        } else {
            "None".to_owned()
        };
        Ok(format!(
            "ResBlock {{\n        block0: {block0},\n        block1: {block1},\n        time: {time},\n        residual: {residual},\n    }}"
        ))
    }
}

struct Config {
    dims: Vec<usize>,
    time_dim: usize,
    time_hidden: usize,
    kernel: usize,
    groups: usize,
    horizon: usize,
    joints: usize,
    steps: usize,
    beta_max: f64,
    macs: usize,
    top_skip: bool,
}

fn read_config(path: &Path) -> Result<Config, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let uint = |key: &str| {
        v[key]
            .as_u64()
            .map(|x| x as usize)
            .ok_or_else(|| format!("{}: `{key}` must be an integer", path.display()))
    };
    let dims = v["dims"]
        .as_array()
        .ok_or_else(|| format!("{}: `dims` must be a list", path.display()))?
        .iter()
        .map(|d| {
            d.as_u64()
                .map(|d| d as usize)
                .ok_or_else(|| format!("{}: `dims` entries", path.display()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let beta_max = v["beta_schedule"]["beta_max"]
        .as_f64()
        .ok_or_else(|| format!("{}: `beta_schedule.beta_max`", path.display()))?;
    if v["format"] != "edmp-prior/1" || v["prediction"] != "epsilon" || v["beta_schedule"]["kind"] != "linear" {
        return Err(format!(
            "{}: expected format edmp-prior/1, epsilon prediction, linear betas",
            path.display()
        ));
    }
    Ok(Config {
        dims,
        time_dim: uint("time_dim")?,
        time_hidden: uint("time_hidden")?,
        kernel: uint("kernel")?,
        groups: uint("groups")?,
        horizon: uint("horizon")?,
        joints: uint("joints")?,
        steps: uint("steps")?,
        beta_max,
        macs: uint("macs_per_trajectory")?,
        top_skip: v["top_skip"].as_bool().unwrap_or(false),
    })
}

/// Reads `dir/prior.safetensors` and `dir/prior.json` and returns the generated prior.
/// `display` names the directory in the generated comments.
/// The source `include_bytes!`s the blob from `OUT_DIR/{blob}`.
pub fn generate_prior(dir: &Path, display: &str, blob: &str) -> Result<GeneratedPrior, String> {
    let json = dir.join("prior.json");
    let weights = dir.join("prior.safetensors");
    let cfg = read_config(&json)?;
    let tensors = read_safetensors(&weights)?;
    if cfg.dims.is_empty() || cfg.dims.iter().any(|d| d % cfg.groups != 0) || cfg.kernel % 2 == 0 {
        return Err(format!(
            "prior: dims {:?} must be non-empty multiples of {} groups, odd kernel",
            cfg.dims, cfg.groups
        ));
    }
    let levels = cfg.dims.len();
    let mut lengths = vec![cfg.horizon];
    for _ in 1..levels {
        lengths.push((lengths.last().unwrap() - 1) / 2 + 1);
    }
    let widths: Vec<usize> = core::iter::once(cfg.joints).chain(cfg.dims.iter().copied()).collect();
    let mut e = Emitter {
        tensors: &tensors,
        blob: Vec::new(),
        macs: 0,
        used: Vec::new(),
    };

    let time_in = e.linear("time_in", cfg.time_dim, cfg.time_hidden)?;
    let time_out = e.linear("time_out", cfg.time_hidden, cfg.time_dim)?;
    let mut down = Vec::new();
    for i in 0..levels {
        let (cin, cout, len) = (widths[i], widths[i + 1], lengths[i]);
        let res0 = e.res(&format!("down.{i}.res0"), cin, cout, &cfg, len)?;
        let res1 = e.res(&format!("down.{i}.res1"), cout, cout, &cfg, len)?;
        let sample = if i + 1 < levels {
            format!(
                "Some({})",
                e.conv(&format!("down.{i}.sample"), cout, cout, 3, lengths[i + 1], false)?
            )
        } else {
            "None".to_owned()
        };
        down.push(format!(
            "Down {{\n    res0: {res0},\n    res1: {res1},\n    sample: {sample},\n}}"
        ));
    }
    let mid = cfg.dims[levels - 1];
    let mid0 = e.res("mid0", mid, mid, &cfg, lengths[levels - 1])?;
    let mid1 = e.res("mid1", mid, mid, &cfg, lengths[levels - 1])?;
    let mut up = Vec::new();
    for (j, i) in (1..levels).rev().enumerate() {
        let (din, dout, len) = (widths[i], widths[i + 1], lengths[i]);
        let res0 = e.res(&format!("up.{j}.res0"), 2 * dout, din, &cfg, len)?;
        let res1 = e.res(&format!("up.{j}.res1"), din, din, &cfg, len)?;
        let sample = e.conv(&format!("up.{j}.sample"), din, din, 4, len, true)?;
        up.push(format!(
            "Up {{\n    res0: {res0},\n    res1: {res1},\n    sample: {sample},\n}}"
        ));
    }
    let final_in = if cfg.top_skip { 2 * cfg.dims[0] } else { cfg.dims[0] };
    let final_block = e.block("final", final_in, cfg.dims[0], cfg.kernel, cfg.horizon)?;
    let out = e.conv("out", cfg.dims[0], cfg.joints, 1, cfg.horizon, false)?;

    if let Some(extra) = tensors.keys().find(|k| !e.used.contains(k)) {
        return Err(format!(
            "prior: tensor {extra} is not part of the network the JSON describes"
        ));
    }
    if e.macs != cfg.macs {
        return Err(format!(
            "prior: {} MAC counted here, {} in {}",
            e.macs,
            cfg.macs,
            json.display()
        ));
    }
    let parameters: usize = tensors.values().map(|t| t.data.len()).sum();

    // Schedule in f64, stored as f32: beta_t = beta_max * t / steps, t = 1..steps.
    let mut alpha_bar = 1.0f64;
    let (mut beta, mut alpha_bar_v) = (Vec::new(), Vec::new());
    for t in 1..=cfg.steps {
        let b = cfg.beta_max * t as f64 / cfg.steps as f64;
        alpha_bar *= 1.0 - b;
        beta.push(b);
        alpha_bar_v.push(alpha_bar);
    }
    let f32s = |v: Vec<f64>| Emitter::floats(&v.into_iter().map(|x| x as f32).collect::<Vec<_>>());
    let sqrt_recip_alpha = f32s(beta.iter().map(|b| 1.0 / (1.0 - b).sqrt()).collect());
    let eps_coef = f32s(
        beta.iter()
            .zip(&alpha_bar_v)
            .map(|(b, ab)| b / (1.0 - ab).sqrt())
            .collect(),
    );
    let sqrt_ab = f32s(alpha_bar_v.iter().map(|ab| ab.sqrt()).collect());
    let sqrt_1mab = f32s(alpha_bar_v.iter().map(|ab| (1.0 - ab).sqrt()).collect());
    let betas = f32s(beta.clone());

    let blob_len = e.blob.len();
    let checksum = fnv1a(&e.blob);
    let macs = e.macs;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "// Generated by edmp-codegen from {display}/prior.safetensors and prior.json. Do not edit."
    );
    let _ = writeln!(
        s,
        "// {parameters} parameters; {blob_len} int8 weights; {macs} MAC per trajectory per step."
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "/// Levels of the UNet (resolutions).");
    let _ = writeln!(s, "pub const LEVELS: usize = {levels};");
    let _ = writeln!(s, "/// Channel width of each level.");
    let _ = writeln!(s, "pub const DIMS: [usize; LEVELS] = {:?};", cfg.dims);
    let _ = writeln!(
        s,
        "/// Sequence length of each level (50, 25, 13: stride-2 convs, crops on the way up)."
    );
    let _ = writeln!(s, "pub const LENGTHS: [usize; LEVELS] = {lengths:?};");
    let _ = writeln!(s, "/// Joints the network was trained on (input and output channels).");
    let _ = writeln!(s, "pub const JOINTS: usize = {};", cfg.joints);
    let _ = writeln!(s, "/// Convolution kernel of the residual blocks.");
    let _ = writeln!(s, "pub const KERNEL: usize = {};", cfg.kernel);
    let _ = writeln!(s, "/// GroupNorm groups.");
    let _ = writeln!(s, "pub const GROUPS: usize = {};", cfg.groups);
    let _ = writeln!(
        s,
        "/// Width of the sinusoidal time features and of the time embedding."
    );
    let _ = writeln!(s, "pub const TIME_DIM: usize = {};", cfg.time_dim);
    let _ = writeln!(s, "/// Hidden width of the time MLP.");
    let _ = writeln!(s, "pub const TIME_HIDDEN: usize = {};", cfg.time_hidden);
    let _ = writeln!(
        s,
        "/// Whether the final block also reads the first level's full-resolution skip (our fix;"
    );
    let _ = writeln!(s, "/// the original leaves it unused).");
    let _ = writeln!(s, "pub const TOP_SKIP: bool = {};", cfg.top_skip);
    let _ = writeln!(s, "/// Trained diffusion steps T.");
    let _ = writeln!(s, "pub const STEPS: usize = {};", cfg.steps);
    let _ = writeln!(s, "/// Parameters of the float model.");
    let _ = writeln!(s, "pub const PARAMETERS: usize = {parameters};");
    let _ = writeln!(s, "/// Multiply-accumulates of one forward for one trajectory.");
    let _ = writeln!(s, "pub const MACS: usize = {macs};");
    let _ = writeln!(s, "/// Bytes of int8 weights.");
    let _ = writeln!(s, "pub const WEIGHT_BYTES: usize = {blob_len};");
    let _ = writeln!(s, "/// FNV-1a of the weight blob, checked by `weights_intact`.");
    let _ = writeln!(s, "pub const WEIGHTS_FNV1A: u64 = {checksum:#018x};");
    let _ = writeln!(s, "/// β_t, index t − 1.");
    let _ = writeln!(s, "pub const BETA: [f32; STEPS] = *{betas};");
    let _ = writeln!(s, "/// 1 / sqrt(α_t).");
    let _ = writeln!(s, "pub const SQRT_RECIP_ALPHA: [f32; STEPS] = *{sqrt_recip_alpha};");
    let _ = writeln!(
        s,
        "/// β_t / sqrt(1 − ᾱ_t), the noise coefficient of the posterior mean."
    );
    let _ = writeln!(s, "pub const EPS_COEF: [f32; STEPS] = *{eps_coef};");
    let _ = writeln!(s, "/// sqrt(ᾱ_t).");
    let _ = writeln!(s, "pub const SQRT_ALPHA_BAR: [f32; STEPS] = *{sqrt_ab};");
    let _ = writeln!(s, "/// sqrt(1 − ᾱ_t).");
    let _ = writeln!(s, "pub const SQRT_ONE_MINUS_ALPHA_BAR: [f32; STEPS] = *{sqrt_1mab};");
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "static WEIGHTS: Aligned<[u8; WEIGHT_BYTES]> = Aligned(*include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{blob}\")));"
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "/// The weight blob (int8 stored as bytes).");
    let _ = writeln!(s, "pub static WEIGHT_BLOB: &[u8] = &WEIGHTS.0;");
    let _ = writeln!(s);
    let _ = writeln!(s, "const fn part(offset: usize, len: usize) -> &'static [u8] {{");
    let _ = writeln!(s, "    slice_of(&WEIGHTS.0, offset, len)");
    let _ = writeln!(s, "}}");
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "static DOWN: [Down; LEVELS] = [\n{}];",
        down.iter().map(|d| format!("{d},\n")).collect::<String>()
    );
    let _ = writeln!(
        s,
        "static UP: [Up; LEVELS - 1] = [\n{}];",
        up.iter().map(|d| format!("{d},\n")).collect::<String>()
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "/// The trained network.");
    let _ = writeln!(
        s,
        "pub static NET: Net = Net {{\n    time_in: {time_in},\n    time_out: {time_out},\n    down: &DOWN,\n    mid0: {mid0},\n    mid1: {mid1},\n    up: &UP,\n    final_block: {final_block},\n    out: {out},\n}};"
    );
    Ok(GeneratedPrior {
        source: s,
        blob: e.blob,
        inputs: vec![json, weights],
    })
}
