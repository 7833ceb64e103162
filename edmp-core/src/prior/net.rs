//! The int8 temporal UNet: ε̂ = net(x_t, t) for one trajectory.
//!
//! Weights are int8 with one float scale per output channel (frozen by `edmp-codegen` from
//! `weights/prior/`); activations stay f32. A convolution accumulates `Σ w_int · x` in f32 and
//! multiplies by the channel's scale once, so the result is the fake-quantized float model's up
//! to f32 rounding. The accumulation order is fixed (input channel, then tap, then position),
//! never fused into FMA, so every target gives the same bits.
//!
//! Activations are channel-major rows of `len + 2·PAD` floats whose pads are zero: the
//! "same" convolution reads past the ends without branches.

use super::generated::{ACTIVATION_FLOATS, DIMS, GROUPS, KERNEL, LENGTHS, LEVELS, NET, TIME_DIM, TIME_HIDDEN};
use crate::robot::JOINTS;
use crate::Error;

/// Zero columns on each side of an activation row.
const PAD: usize = KERNEL / 2;
/// The widest level.
const MAX_WIDTH: usize = max_of(&DIMS);
/// Floats the kept skip connections need (levels 1.., the first level's skip is never used).
const SKIP_FLOATS: usize = skip_floats();

const fn max_of(v: &[usize]) -> usize {
    let mut m = 0;
    let mut i = 0;
    while i < v.len() {
        if v[i] > m {
            m = v[i];
        }
        i += 1;
    }
    m
}

const fn skip_floats() -> usize {
    let mut total = 0;
    let mut i = 1;
    while i < LEVELS {
        total += DIMS[i] * (LENGTHS[i] + 2 * PAD);
        i += 1;
    }
    total
}

const fn stride(len: usize) -> usize {
    len + 2 * PAD
}

/// Keeps the weight blob at a 16-byte boundary (SIMD loads on the target).
#[repr(C, align(16))]
pub(crate) struct Aligned<B: ?Sized>(pub(crate) B);

/// `blob[offset..offset + len]` in a constant context (out of range fails the build).
pub(crate) const fn slice_of(blob: &'static [u8], offset: usize, len: usize) -> &'static [u8] {
    let (_, rest) = blob.split_at(offset);
    rest.split_at(len).0
}

/// A 1-D convolution, output-channel-major int8 weights `cout × cin × k`.
pub(crate) struct Conv {
    pub(crate) cin: usize,
    pub(crate) cout: usize,
    pub(crate) k: usize,
    pub(crate) weights: &'static [u8],
    pub(crate) scale: &'static [f32],
    pub(crate) bias: &'static [f32],
}

/// A dense layer, int8 weights `fout × fin`.
pub(crate) struct Linear {
    pub(crate) fin: usize,
    pub(crate) fout: usize,
    pub(crate) weights: &'static [u8],
    pub(crate) scale: &'static [f32],
    pub(crate) bias: &'static [f32],
}

/// Conv → GroupNorm → Mish.
pub(crate) struct ConvBlock {
    pub(crate) conv: Conv,
    pub(crate) gamma: &'static [f32],
    pub(crate) beta: &'static [f32],
}

/// Two conv blocks, the time embedding added after the first, residual 1×1 when widths differ.
pub(crate) struct ResBlock {
    pub(crate) block0: ConvBlock,
    pub(crate) block1: ConvBlock,
    pub(crate) time: Linear,
    pub(crate) residual: Option<Conv>,
}

/// A level of the contracting path; `sample` (stride 2) is absent on the last.
pub(crate) struct Down {
    pub(crate) res0: ResBlock,
    pub(crate) res1: ResBlock,
    pub(crate) sample: Option<Conv>,
}

/// A level of the expanding path; `sample` is a transposed convolution (k 4, stride 2, pad 1).
pub(crate) struct Up {
    pub(crate) res0: ResBlock,
    pub(crate) res1: ResBlock,
    pub(crate) sample: Conv,
}

/// The whole network.
pub(crate) struct Net {
    pub(crate) time_in: Linear,
    pub(crate) time_out: Linear,
    pub(crate) down: &'static [Down],
    pub(crate) mid0: ResBlock,
    pub(crate) mid1: ResBlock,
    pub(crate) up: &'static [Up],
    pub(crate) final_block: ConvBlock,
    pub(crate) out: Conv,
}

/// One trajectory, waypoint-major, raw joint angles in radians.
pub type Trajectory<const H: usize> = [[f32; JOINTS]; H];

/// Mish of the time embedding of step `t`: what every residual block projects.
/// Depends on `t` alone, so a batch computes it once per step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeEmbedding {
    t: u16,
    features: [f32; TIME_DIM],
}

impl TimeEmbedding {
    /// The embedding of step `t` (1 ..= `STEPS`, as the network was trained).
    pub fn new(t: u16) -> Result<Self, Error> {
        if t == 0 || usize::from(t) > super::STEPS {
            return Err(Error::BadParameter);
        }
        let half = TIME_DIM / 2;
        let mut sinusoid = [0.0f32; TIME_DIM];
        let factor = libm::logf(10000.0) / (half - 1) as f32;
        for i in 0..half {
            let arg = f32::from(t) * libm::expf(-(i as f32) * factor);
            sinusoid[i] = libm::sinf(arg);
            sinusoid[half + i] = libm::cosf(arg);
        }
        let mut hidden = [0.0f32; TIME_HIDDEN];
        linear(&NET.time_in, &sinusoid, &mut hidden);
        hidden.iter_mut().for_each(|h| *h = mish(*h));
        let mut features = [0.0f32; TIME_DIM];
        linear(&NET.time_out, &hidden, &mut features);
        features.iter_mut().for_each(|h| *h = mish(*h));
        Ok(Self { t, features })
    }

    /// The step this embedding is for.
    pub fn step(&self) -> u16 {
        self.t
    }
}

/// Working memory of one forward, sized at compile time from the generated shapes.
#[derive(Clone)]
pub struct Scratch {
    bufs: [[f32; ACTIVATION_FLOATS]; 3],
    skips: [f32; SKIP_FLOATS],
}

impl core::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Scratch({SCRATCH_BYTES} bytes)")
    }
}

impl Default for Scratch {
    fn default() -> Self {
        Self::new()
    }
}

impl Scratch {
    /// Zeroed scratch (`const`: it can live in a `static`).
    pub const fn new() -> Self {
        Self { bufs: [[0.0; ACTIVATION_FLOATS]; 3], skips: [0.0; SKIP_FLOATS] }
    }
}

/// Bytes of [`Scratch`]: the network's whole working memory.
pub const SCRATCH_BYTES: usize = core::mem::size_of::<Scratch>();

/// Predicts the noise in `x` (horizon `LENGTHS[0]`) at the step `time` was made for.
///
/// Refuses non-finite input; an output that overflowed is [`Error::Overflow`].
pub fn predict_noise(
    x: &Trajectory<{ LENGTHS[0] }>,
    time: &TimeEmbedding,
    scratch: &mut Scratch,
    eps: &mut Trajectory<{ LENGTHS[0] }>,
) -> Result<(), Error> {
    for waypoint in x {
        if let Some(joint) = waypoint.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteJoint { joint: joint as u8 });
        }
    }
    let temb = &time.features;
    let Scratch { bufs, skips } = scratch;
    let [b0, b1, b2] = bufs;
    let (mut x_buf, h_buf, mut y_buf) = (b0, b1, b2);

    // Input: channels first, zero pads.
    let len0 = LENGTHS[0];
    let s0 = stride(len0);
    x_buf[..JOINTS * s0].fill(0.0);
    for (l, waypoint) in x.iter().enumerate() {
        for (j, v) in waypoint.iter().enumerate() {
            x_buf[j * s0 + PAD + l] = *v;
        }
    }

    let mut skip_offset = 0;
    let mut channels = JOINTS;
    for (i, level) in NET.down.iter().enumerate() {
        let len = LENGTHS[i];
        res_block(&level.res0, x_buf, len, temb, h_buf, y_buf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        res_block(&level.res1, x_buf, len, temb, h_buf, y_buf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        channels = DIMS[i];
        if i >= 1 {
            let n = channels * stride(len);
            skips[skip_offset..skip_offset + n].copy_from_slice(&x_buf[..n]);
            skip_offset += n;
        }
        if let Some(sample) = &level.sample {
            conv_down(sample, x_buf, len, y_buf, LENGTHS[i + 1]);
            core::mem::swap(&mut x_buf, &mut y_buf);
        }
    }
    let deepest = LENGTHS[LEVELS - 1];
    res_block(&NET.mid0, x_buf, deepest, temb, h_buf, y_buf);
    core::mem::swap(&mut x_buf, &mut y_buf);
    res_block(&NET.mid1, x_buf, deepest, temb, h_buf, y_buf);
    core::mem::swap(&mut x_buf, &mut y_buf);

    for (j, level) in NET.up.iter().enumerate() {
        let i = LEVELS - 1 - j;
        let len = LENGTHS[i];
        // Concatenate [x, skip_i] on channels: the skip's rows follow x's.
        let n = channels * stride(len);
        skip_offset -= n;
        x_buf[n..2 * n].copy_from_slice(&skips[skip_offset..skip_offset + n]);
        res_block(&level.res0, x_buf, len, temb, h_buf, y_buf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        res_block(&level.res1, x_buf, len, temb, h_buf, y_buf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        conv_up(&level.sample, x_buf, len, y_buf, LENGTHS[i - 1]);
        core::mem::swap(&mut x_buf, &mut y_buf);
        channels = level.sample.cout;
    }
    conv_block(&NET.final_block, x_buf, len0, y_buf);
    conv_same(&NET.out, y_buf, len0, h_buf, Accumulate::Overwrite);
    for (l, waypoint) in eps.iter_mut().enumerate() {
        for (j, v) in waypoint.iter_mut().enumerate() {
            *v = h_buf[j * s0 + PAD + l];
        }
    }
    if eps.iter().flatten().all(|v| v.is_finite()) { Ok(()) } else { Err(Error::Overflow) }
}

/// Mish, x·tanh(softplus(x)), with one `expf`: tanh(ln(1 + u)) = n / (n + 2), n = u(u + 2).
/// Above 20 it is x (PyTorch's softplus threshold), so `u²` never overflows.
#[inline]
fn mish(x: f32) -> f32 {
    if x > 20.0 {
        return x;
    }
    let u = libm::expf(x);
    let n = u * (u + 2.0);
    x * n / (n + 2.0)
}

fn linear(layer: &Linear, input: &[f32], out: &mut [f32]) {
    for (o, y) in out.iter_mut().enumerate().take(layer.fout) {
        let row = &layer.weights[o * layer.fin..(o + 1) * layer.fin];
        let acc = row.iter().zip(input).fold(0.0f32, |acc, (w, x)| acc + f32::from(*w as i8) * x);
        *y = acc * layer.scale[o] + layer.bias[o];
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Accumulate {
    Overwrite,
    Add,
}

/// "Same" convolution (odd k ≤ 2·PAD + 1, stride 1) on padded rows; writes zero pads.
fn conv_same(conv: &Conv, input: &[f32], len: usize, out: &mut [f32], mode: Accumulate) {
    let s = stride(len);
    let shift = PAD - conv.k / 2;
    let mut acc = [0.0f32; LENGTHS[0]];
    let acc = &mut acc[..len];
    for co in 0..conv.cout {
        acc.fill(0.0);
        for ci in 0..conv.cin {
            let row = &input[ci * s..(ci + 1) * s];
            let taps = &conv.weights[(co * conv.cin + ci) * conv.k..(co * conv.cin + ci + 1) * conv.k];
            for (kk, w) in taps.iter().enumerate() {
                let w = f32::from(*w as i8);
                let x = &row[shift + kk..shift + kk + len];
                for (a, v) in acc.iter_mut().zip(x) {
                    *a += w * v;
                }
            }
        }
        let (scale, bias) = (conv.scale[co], conv.bias[co]);
        let dst = &mut out[co * s..(co + 1) * s];
        match mode {
            Accumulate::Overwrite => {
                dst[..PAD].fill(0.0);
                dst[PAD + len..].fill(0.0);
                for (d, a) in dst[PAD..PAD + len].iter_mut().zip(acc.iter()) {
                    *d = *a * scale + bias;
                }
            }
            Accumulate::Add => {
                for (d, a) in dst[PAD..PAD + len].iter_mut().zip(acc.iter()) {
                    *d += *a * scale + bias;
                }
            }
        }
    }
}

/// Stride-2 convolution, k 3, pad 1: `len` → `out_len` = ⌈len / 2⌉.
fn conv_down(conv: &Conv, input: &[f32], len: usize, out: &mut [f32], out_len: usize) {
    let (s, so) = (stride(len), stride(out_len));
    let mut acc = [0.0f32; LENGTHS[0]];
    let acc = &mut acc[..out_len];
    for co in 0..conv.cout {
        acc.fill(0.0);
        for ci in 0..conv.cin {
            let row = &input[ci * s..(ci + 1) * s];
            let taps = &conv.weights[(co * conv.cin + ci) * conv.k..(co * conv.cin + ci + 1) * conv.k];
            for (kk, w) in taps.iter().enumerate() {
                let w = f32::from(*w as i8);
                // Output l reads input 2l + kk − 1, at padded index PAD − 1 + kk + 2l.
                let x = row[PAD - 1 + kk..].iter().step_by(2);
                for (a, v) in acc.iter_mut().zip(x) {
                    *a += w * v;
                }
            }
        }
        write_row(&mut out[co * so..(co + 1) * so], acc, conv.scale[co], conv.bias[co]);
    }
}

/// Transposed convolution, k 4, stride 2, pad 1: `len` → 2·len, cropped to `out_len`.
fn conv_up(conv: &Conv, input: &[f32], len: usize, out: &mut [f32], out_len: usize) {
    let (s, so) = (stride(len), stride(out_len));
    let mut acc = [0.0f32; LENGTHS[0]];
    let acc = &mut acc[..out_len];
    for co in 0..conv.cout {
        acc.fill(0.0);
        for ci in 0..conv.cin {
            let row = &input[ci * s + PAD..ci * s + PAD + len];
            let taps = &conv.weights[(co * conv.cin + ci) * conv.k..(co * conv.cin + ci + 1) * conv.k];
            for (kk, w) in taps.iter().enumerate() {
                let w = f32::from(*w as i8);
                // Input i lands on output 2i + kk − 1.
                for (i, v) in row.iter().enumerate() {
                    let o = 2 * i + kk;
                    if o >= 1 && o - 1 < out_len {
                        acc[o - 1] += w * v;
                    }
                }
            }
        }
        write_row(&mut out[co * so..(co + 1) * so], acc, conv.scale[co], conv.bias[co]);
    }
}

fn write_row(dst: &mut [f32], acc: &[f32], scale: f32, bias: f32) {
    let len = acc.len();
    dst[..PAD].fill(0.0);
    dst[PAD + len..].fill(0.0);
    for (d, a) in dst[PAD..PAD + len].iter_mut().zip(acc) {
        *d = *a * scale + bias;
    }
}

/// GroupNorm (biased variance, ε 1e-5, two passes) then Mish, in place on the data columns.
fn norm_mish(x: &mut [f32], channels: usize, len: usize, gamma: &[f32], beta: &[f32]) {
    let s = stride(len);
    let per_group = channels / GROUPS;
    let count = (per_group * len) as f32;
    for g in 0..GROUPS {
        let rows = g * per_group..(g + 1) * per_group;
        let mut sum = 0.0f32;
        for c in rows.clone() {
            sum += x[c * s + PAD..c * s + PAD + len].iter().fold(0.0f32, |a, v| a + v);
        }
        let mean = sum / count;
        let mut var = 0.0f32;
        for c in rows.clone() {
            var += x[c * s + PAD..c * s + PAD + len].iter().fold(0.0f32, |a, v| a + (v - mean) * (v - mean));
        }
        let inv = 1.0 / libm::sqrtf(var / count + 1e-5);
        for c in rows {
            let (ga, be) = (gamma[c] * inv, beta[c]);
            for v in &mut x[c * s + PAD..c * s + PAD + len] {
                *v = mish((*v - mean) * ga + be);
            }
        }
    }
}

fn conv_block(block: &ConvBlock, input: &[f32], len: usize, out: &mut [f32]) {
    conv_same(&block.conv, input, len, out, Accumulate::Overwrite);
    norm_mish(out, block.conv.cout, len, block.gamma, block.beta);
}

/// `out = block1(block0(x) + time) + residual(x)`, `h` is scratch.
fn res_block(block: &ResBlock, x: &[f32], len: usize, temb: &[f32; TIME_DIM], h: &mut [f32], out: &mut [f32]) {
    let s = stride(len);
    let cout = block.block0.conv.cout;
    conv_block(&block.block0, x, len, h);
    let mut shift = [0.0f32; MAX_WIDTH];
    linear(&block.time, temb, &mut shift[..cout]);
    for (c, add) in shift[..cout].iter().enumerate() {
        for v in &mut h[c * s + PAD..c * s + PAD + len] {
            *v += add;
        }
    }
    conv_block(&block.block1, h, len, out);
    match &block.residual {
        Some(res) => conv_same(res, x, len, out, Accumulate::Add),
        None => {
            for c in 0..cout {
                for (o, v) in out[c * s + PAD..c * s + PAD + len].iter_mut().zip(&x[c * s + PAD..c * s + PAD + len]) {
                    *o += v;
                }
            }
        }
    }
}
