//! The int8 temporal UNet: ε̂ = net(x_t, t) for a batch of trajectories.
//!
//! Weights are int8 with one float scale per output channel (frozen by `edmp-codegen` from
//! `weights/prior/`); activations stay f32. A convolution accumulates `Σ w_int · x` in f32 and
//! multiplies by the channel's scale once, so the result is the fake-quantized float model's up
//! to f32 rounding. The accumulation order is fixed (input channel, then tap, then position),
//! never fused into FMA, so every target gives the same bits.
//!
//! A batch runs together: activations are channel-major rows holding every trajectory's
//! segment (data plus zero pads) side by side, so a "same" convolution sweeps a whole row in
//! register tiles of 4 channels × 8 positions without branches, and only the row's end wastes
//! work.

use super::layers::{Conv, ConvBlock, Linear, Net, ResBlock};
use super::weights::{DIMS, GROUPS, KERNEL, LENGTHS, LEVELS, NETWORK, STEPS, TIME_DIM, TIME_HIDDEN, TOP_SKIP};
use crate::Error;
use crate::executor::{Executor, MAX_PARTS, split};
use crate::path::Trajectory;
use crate::robot::JOINTS;

/// One arm's trained network: its layer table and weight blob, for trajectories of `J` joints.
/// Every arm's network has the Panda's shape but for the input and output channels (checked
/// where each is declared), so one [`Scratch`] serves them all.
pub struct Network<const J: usize> {
    /// The scene format's `robot` name of the arm it was trained for.
    pub name: &'static str,
    pub(crate) net: &'static Net,
    pub(crate) blob: &'static [u8],
    pub(crate) fnv1a: u64,
    /// The wave budget this prior ships with ([`PlanConfig::wave_budget`](crate::planner::PlanConfig::wave_budget)
    /// when the config names none): how soon its ensemble hands a scene of many boxes to the
    /// global stage, measured per arm (docs/benchmark.md, "Bounding the waves"). `None`: every
    /// wave runs.
    pub wave_budget: Option<u16>,
}

impl<const J: usize> core::fmt::Debug for Network<J> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Network<{J}>({}, {} weight bytes)", self.name, self.blob.len())
    }
}

impl<const J: usize> Network<J> {
    /// The weight blob the build embedded: `include_bytes!` of the codegen output.
    pub fn weight_blob(&self) -> &'static [u8] {
        self.blob
    }

    /// Whether the embedded weights still hash to the checksum codegen computed (flash check).
    pub fn weights_intact(&self) -> bool {
        let h = self.blob.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
        });
        h == self.fnv1a
    }

    /// This network's embedding of step `t` (1 ..= `STEPS`, as the network was trained).
    pub fn time(&self, t: u16) -> Result<TimeEmbedding, Error> {
        TimeEmbedding::of(self.net, t)
    }

    /// [`predict_noise`] with this network; `time` must come from [`Self::time`].
    pub fn predict_noise<const B: usize, const C: usize>(
        &self,
        x: &[[[f32; J]; LENGTHS[0]]; B],
        time: &TimeEmbedding,
        scratch: &mut Scratch<C>,
        eps: &mut [[[f32; J]; LENGTHS[0]]; B],
    ) -> Result<(), Error> {
        check_finite(x)?;
        if C == 0 || J > JOINTS {
            return Err(Error::BadParameter);
        }
        for (x, eps) in x.chunks(C).zip(eps.chunks_mut(C)) {
            forward(self.net, x, time, scratch, eps);
        }
        finite_or_overflow(eps)
    }

    /// [`predict_noise_on`] with this network; `time` must come from [`Self::time`].
    pub fn predict_noise_on<E: Executor, const C: usize>(
        &self,
        exec: &E,
        x: &[[[f32; J]; LENGTHS[0]]],
        time: &TimeEmbedding,
        scratches: &mut [Scratch<C>],
        eps: &mut [[[f32; J]; LENGTHS[0]]],
    ) -> Result<(), Error> {
        check_finite(x)?;
        if C == 0 || J > JOINTS || scratches.is_empty() || x.len() != eps.len() {
            return Err(Error::BadParameter);
        }
        struct Part<'a, const J: usize, const C: usize> {
            x: &'a [[[f32; J]; LENGTHS[0]]],
            eps: &'a mut [[[f32; J]; LENGTHS[0]]],
            scratch: &'a mut Scratch<C>,
        }
        let lens = split(x.len(), C, exec.parts().min(scratches.len()));
        let mut parts: heapless::Vec<Part<'_, J, C>, MAX_PARTS> = heapless::Vec::new();
        let (mut x_rest, mut eps_rest) = (x, &mut eps[..]);
        for (&len, scratch) in lens.iter().zip(scratches.iter_mut()) {
            if len == 0 {
                break;
            }
            let (Some((xp, xr)), Some((ep, er))) = (
                x_rest.split_at_checked(len),
                core::mem::take(&mut eps_rest).split_at_mut_checked(len),
            ) else {
                return Err(Error::BadParameter);
            };
            (x_rest, eps_rest) = (xr, er);
            if parts
                .push(Part {
                    x: xp,
                    eps: ep,
                    scratch,
                })
                .is_err()
            {
                return Err(Error::BadParameter);
            }
        }
        let net = self.net;
        exec.each(&mut parts, |part| {
            for (x, eps) in part.x.chunks(C).zip(part.eps.chunks_mut(C)) {
                forward(net, x, time, part.scratch, eps);
            }
            Ok(())
        })?;
        drop(parts);
        finite_or_overflow(eps)
    }
}

/// A non-finite input is an error naming its joint.
fn check_finite<const J: usize, const L: usize>(x: &[[[f32; J]; L]]) -> Result<(), Error> {
    for waypoint in x.iter().flatten() {
        if let Some(joint) = waypoint.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteJoint { joint: joint as u8 });
        }
    }
    Ok(())
}

/// An output that overflowed is [`Error::Overflow`].
fn finite_or_overflow<const J: usize, const L: usize>(eps: &[[[f32; J]; L]]) -> Result<(), Error> {
    if eps.iter().flatten().flatten().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::Overflow)
    }
}

/// Zero columns on each side of an activation row.
const PAD: usize = KERNEL / 2;
/// The widest level.
const MAX_WIDTH: usize = max_of(&DIMS);
/// Floats per trajectory of the kept skip connections (levels 1.., and the first level's when
/// the network reads it: `TOP_SKIP`; the original never does).
const SKIP_FLOATS: usize = skip_floats();

/// Whether level `i`'s output is kept for the way up.
const fn keeps_skip(i: usize) -> bool {
    i >= 1 || TOP_SKIP
}

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
    let mut i = 0;
    while i < LEVELS {
        if keeps_skip(i) {
            total += DIMS[i] * (segment(LENGTHS[i]) + TILE);
        }
        i += 1;
    }
    total
}

/// Floats one trajectory occupies in a row: its data with `PAD` zeros on each side.
const fn segment(len: usize) -> usize {
    len + 2 * PAD
}

/// Floats per trajectory of the widest activation any stage holds (an up level's concatenated
/// input), with room for a tile's overrun at the end of each row.
const ACTIVATION_FLOATS: usize = activation_floats();

const fn activation_floats() -> usize {
    let mut m = JOINTS * (segment(LENGTHS[0]) + TILE);
    let mut i = 0;
    while i < LEVELS {
        let f = 2 * DIMS[i] * (segment(LENGTHS[i]) + TILE);
        if f > m {
            m = f;
        }
        i += 1;
    }
    m
}

/// Where a batch's activation lives: channel-major rows, each row the `batch` trajectories'
/// segments side by side, then `TILE` zeros so a tile never reads past its row. Pads are zero.
#[derive(Clone, Copy)]
struct Layout {
    batch: usize,
    len: usize,
}

impl Layout {
    const fn seg(self) -> usize {
        segment(self.len)
    }
    /// Floats per channel row.
    const fn row(self) -> usize {
        self.batch * self.seg() + TILE
    }
    /// Index of position `l` of trajectory `b` in channel `c`.
    const fn at(self, c: usize, b: usize, l: usize) -> usize {
        c * self.row() + b * self.seg() + PAD + l
    }
}

/// Mish of the time embedding of step `t`: what every residual block projects.
/// Depends on `t` alone, so a batch computes it once per step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeEmbedding {
    t: u16,
    features: [f32; TIME_DIM],
}

impl TimeEmbedding {
    /// The Panda network's embedding of step `t` (1 ..= `STEPS`, as the network was trained);
    /// other arms' come from [`Network::time`].
    pub fn new(t: u16) -> Result<Self, Error> {
        NETWORK.time(t)
    }

    fn of(net: &Net, t: u16) -> Result<Self, Error> {
        if t == 0 || usize::from(t) > STEPS {
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
        linear(&net.time_in, &sinusoid, &mut hidden);
        hidden.iter_mut().for_each(|h| *h = mish(*h));
        let mut features = [0.0f32; TIME_DIM];
        linear(&net.time_out, &hidden, &mut features);
        features.iter_mut().for_each(|h| *h = mish(*h));
        Ok(Self { t, features })
    }

    /// The step this embedding is for.
    pub fn step(&self) -> u16 {
        self.t
    }
}

/// Working memory of one forward of up to `C` trajectories at once, sized at compile time from
/// the generated shapes.
#[derive(Clone)]
pub struct Scratch<const C: usize> {
    bufs: [[[f32; ACTIVATION_FLOATS]; C]; 3],
    skips: [[f32; SKIP_FLOATS]; C],
    weights: WeightTile,
}

impl<const C: usize> core::fmt::Debug for Scratch<C> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Scratch<{C}>({} bytes)", Self::BYTES)
    }
}

impl<const C: usize> Default for Scratch<C> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const C: usize> Scratch<C> {
    /// Bytes of this scratch: the network's whole working memory for `C` trajectories at once.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// Zeroed scratch (`const`: it can live in a `static`).
    pub const fn new() -> Self {
        Self {
            bufs: [[[0.0; ACTIVATION_FLOATS]; C]; 3],
            skips: [[0.0; SKIP_FLOATS]; C],
            weights: [0.0; MAX_TAPS * TILE_CHANNELS],
        }
    }
}

/// Predicts the noise in each of the `B` trajectories of `x` (horizon `LENGTHS[0]`) at the
/// step `time` was made for, `C` trajectories at a time (the scratch's capacity: 1 on a
/// microcontroller, a few on a PC where they share each weight tile). Each trajectory's result
/// is independent of the others, of `B` and of `C`, bit for bit.
///
/// Refuses non-finite input; an output that overflowed is [`Error::Overflow`].
pub fn predict_noise<const B: usize, const C: usize>(
    x: &[Trajectory<{ LENGTHS[0] }>; B],
    time: &TimeEmbedding,
    scratch: &mut Scratch<C>,
    eps: &mut [Trajectory<{ LENGTHS[0] }>; B],
) -> Result<(), Error> {
    NETWORK.predict_noise(x, time, scratch, eps)
}

/// [`predict_noise`] with the batch cut into parts, one per scratch (at most
/// `exec.parts()`), run by `exec`: the same bits as one scratch (every trajectory's result is
/// independent of its batch). `x` and `eps` must have the same length; no scratch is
/// [`Error::BadParameter`].
pub fn predict_noise_on<E: Executor, const C: usize>(
    exec: &E,
    x: &[Trajectory<{ LENGTHS[0] }>],
    time: &TimeEmbedding,
    scratches: &mut [Scratch<C>],
    eps: &mut [Trajectory<{ LENGTHS[0] }>],
) -> Result<(), Error> {
    NETWORK.predict_noise_on(exec, x, time, scratches, eps)
}

/// One chunk of at most `C` trajectories through the network.
fn forward<const J: usize, const C: usize>(
    net: &Net,
    x: &[[[f32; J]; LENGTHS[0]]],
    time: &TimeEmbedding,
    scratch: &mut Scratch<C>,
    eps: &mut [[[f32; J]; LENGTHS[0]]],
) {
    let batch = x.len();
    let temb = &time.features;
    let Scratch {
        bufs,
        skips,
        weights: wbuf,
    } = scratch;
    let [b0, b1, b2] = bufs;
    let (mut x_buf, h_buf, mut y_buf) = (b0.as_flattened_mut(), b1.as_flattened_mut(), b2.as_flattened_mut());
    let skips = skips.as_flattened_mut();

    // Input: channels first, zero pads.
    let top = Layout { batch, len: LENGTHS[0] };
    x_buf[..J * top.row()].fill(0.0);
    for (b, trajectory) in x.iter().enumerate() {
        for (l, waypoint) in trajectory.iter().enumerate() {
            for (j, v) in waypoint.iter().enumerate() {
                x_buf[top.at(j, b, l)] = *v;
            }
        }
    }

    let mut skip_offset = 0;
    let mut channels = J;
    for (i, level) in net.down.iter().enumerate() {
        let lay = Layout { batch, len: LENGTHS[i] };
        res_block(&level.res0, x_buf, lay, temb, h_buf, y_buf, wbuf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        res_block(&level.res1, x_buf, lay, temb, h_buf, y_buf, wbuf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        channels = DIMS[i];
        if keeps_skip(i) {
            let n = channels * lay.row();
            skips[skip_offset..skip_offset + n].copy_from_slice(&x_buf[..n]);
            skip_offset += n;
        }
        // Every level but the deepest samples down (the build checks the table).
        if let (Some(sample), Some(&next)) = (&level.sample, LENGTHS.get(i + 1)) {
            conv_down(sample, x_buf, lay, y_buf, Layout { batch, len: next }, wbuf);
            core::mem::swap(&mut x_buf, &mut y_buf);
        }
    }
    let deepest = Layout {
        batch,
        len: LENGTHS[LEVELS - 1],
    };
    res_block(&net.mid0, x_buf, deepest, temb, h_buf, y_buf, wbuf);
    core::mem::swap(&mut x_buf, &mut y_buf);
    res_block(&net.mid1, x_buf, deepest, temb, h_buf, y_buf, wbuf);
    core::mem::swap(&mut x_buf, &mut y_buf);

    for (j, level) in net.up.iter().enumerate() {
        let i = LEVELS - 1 - j;
        let lay = Layout { batch, len: LENGTHS[i] };
        // Concatenate [x, skip_i] on channels: the skip's rows follow x's.
        let n = channels * lay.row();
        skip_offset -= n;
        copy(x_buf.get_mut(n..2 * n), skips.get(skip_offset..skip_offset + n));
        res_block(&level.res0, x_buf, lay, temb, h_buf, y_buf, wbuf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        res_block(&level.res1, x_buf, lay, temb, h_buf, y_buf, wbuf);
        core::mem::swap(&mut x_buf, &mut y_buf);
        conv_up(
            &level.sample,
            x_buf,
            lay,
            y_buf,
            Layout {
                batch,
                len: LENGTHS[i - 1],
            },
        );
        core::mem::swap(&mut x_buf, &mut y_buf);
        channels = level.sample.cout;
    }
    if TOP_SKIP {
        let n = channels * top.row();
        copy(x_buf.get_mut(n..2 * n), skips.get(..n));
    }
    conv_block(&net.final_block, x_buf, top, y_buf, wbuf);
    conv_same(&net.out, y_buf, top, h_buf, Accumulate::Overwrite, wbuf);
    for (b, trajectory) in eps.iter_mut().enumerate() {
        for (l, waypoint) in trajectory.iter_mut().enumerate() {
            for (j, v) in waypoint.iter_mut().enumerate() {
                *v = h_buf[top.at(j, b, l)];
            }
        }
    }
}

/// `dst = src` where both ranges exist (they do: the build checks every network's shapes); the
/// channel counts come from the arm's network table, which the compiler cannot see, so a
/// slice copy would link a panic path.
fn copy(dst: Option<&mut [f32]>, src: Option<&[f32]>) {
    if let (Some(dst), Some(src)) = (dst, src) {
        for (d, s) in dst.iter_mut().zip(src) {
            *d = *s;
        }
    }
}

/// Mish, x·tanh(softplus(x)), with one `expf`: tanh(ln(1 + u)) = n / (n + 2), n = u(u + 2).
/// Above 20 it is x (PyTorch's softplus threshold), so `u²` never overflows.
#[inline]
fn mish(x: f32) -> f32 {
    mish_from_exp(x, mish_exp(x))
}

/// `e^min(x, 20)` as `expf(min(x, 20) / 8)⁸` (three squarings). `libm::expf` takes one of three
/// paths by `|x|` (up to ½ ln 2, up to 1.5 ln 2, beyond); on normalized activations the three
/// are about equally likely and most calls mispredicted the branch (`perf`: `expf` was a quarter
/// of the network's time). An eighth of the argument stays on the first path except beyond
/// |x| > 2.77. Relative error 1.8 × 10⁻⁶ instead of 2.1 × 10⁻⁷ on [−20, 20] (numpy, every f32
/// step of 2 × 10⁻⁵), far below the int8 weights' error; the same bits on every target.
#[inline(always)]
fn mish_exp(x: f32) -> f32 {
    eighth_power(mish_exp_eighth(x))
}

/// `expf(min(x, 20) / 8)`: the one call of [`mish_exp`].
#[inline(always)]
fn mish_exp_eighth(x: f32) -> f32 {
    libm::expf(x.min(20.0) * 0.125)
}

/// `e⁸` by three squarings: the rest of [`mish_exp`].
#[inline(always)]
fn eighth_power(e: f32) -> f32 {
    let e2 = e * e;
    let e4 = e2 * e2;
    e4 * e4
}

/// Mish of `x` given `u = mish_exp(x)`.
#[inline(always)]
fn mish_from_exp(x: f32, u: f32) -> f32 {
    let n = u * (u + 2.0);
    if x > 20.0 { x } else { x * n / (n + 2.0) }
}

fn linear(layer: &Linear, input: &[f32], out: &mut [f32]) {
    // Iterators and `get`, not indexing, here and below: the generated tables always fit, and
    // this way no bounds-check panic path is linked into firmware.
    let rows = layer.weights.chunks_exact(layer.fin.max(1));
    for (((y, row), scale), bias) in out
        .iter_mut()
        .zip(rows)
        .zip(layer.scale)
        .zip(layer.bias)
        .take(layer.fout)
    {
        let acc = row
            .iter()
            .zip(input)
            .fold(0.0f32, |acc, (w, x)| acc + f32::from(*w as i8) * x);
        *y = acc * scale + bias;
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Accumulate {
    Overwrite,
    Add,
}

/// Output positions one tile covers (two AVX registers per channel: eight accumulators, enough
/// independent sums to hide the adds' latency; 24 positions spill).
#[cfg(not(target_arch = "arm"))]
const TILE: usize = 16;
/// On a Cortex-M's scalar FPU (32 single registers) the 16 accumulators of a 4 × 4 tile fit
/// beside the inputs and weights they read, where 4 × 8 spill: 1.71 → 1.39 × 10⁹ instructions
/// per plan of the wall under QEMU. A tile's shape changes no sum's order, so no bit.
#[cfg(target_arch = "arm")]
const TILE: usize = 4;
/// Output channels one tile covers.
const TILE_CHANNELS: usize = 4;
/// Taps of the widest convolution (an up level's concatenated input, kernel `KERNEL`).
const MAX_TAPS: usize = 2 * MAX_WIDTH * KERNEL;

/// One channel group's weights as f32, `[ci][tap][c]`.
type WeightTile = [f32; MAX_TAPS * TILE_CHANNELS];

/// `CO` output channels × `TILE` positions of a stride-1 convolution with `K` taps, accumulated
/// in registers. `weights` holds the `CO` channels' weights as f32, `[ci][tap][c]`; `input`
/// starts at the first tap of the tile's first position in channel 0. Each output sums over
/// input channel, then tap: the order every path keeps.
/// The taps [`conv_tile`] runs, `K` either way. On x86-64 read from the layer at run time: a
/// loop the compiler does not unroll, so that each tap's window is one unaligned load, where
/// the unrolled taps were stitched from overlapping loads with shuffles (network 385 → 328 ×
/// 10⁶ instructions per plan). A Cortex-M has no vectors to stitch and keeps the constant.
#[cfg(not(target_arch = "arm"))]
fn taps_of<const K: usize>(conv: &Conv) -> usize {
    conv.k.min(K)
}
#[cfg(target_arch = "arm")]
fn taps_of<const K: usize>(_: &Conv) -> usize {
    K
}

#[inline(always)]
fn conv_tile<const CO: usize, const K: usize>(
    weights: &[f32],
    input: &[f32],
    row: usize,
    cin: usize,
    taps: usize,
) -> [[f32; TILE]; CO] {
    let mut acc = [[0.0f32; TILE]; CO];
    // The inputs one channel's taps read: `taps` windows of `TILE`.
    let span = taps.min(K) + TILE - 1;
    // Per input channel: its `K · CO` weights, then tap by tap a window of `TILE` inputs. The
    // zip of exact chunks and windows is a counted loop: no check per tap.
    for (ci, w) in weights.chunks_exact(K * CO).take(cin).enumerate() {
        let Some(x_span) = input.get(ci * row..ci * row + span) else {
            break;
        };
        for (w_k, x) in w.chunks_exact(CO).zip(x_span.windows(TILE)) {
            let Some(x) = x.first_chunk::<TILE>() else {
                break;
            };
            for (acc_c, w_c) in acc.iter_mut().zip(w_k) {
                for (a, v) in acc_c.iter_mut().zip(x) {
                    *a += w_c * v;
                }
            }
        }
    }
    acc
}

/// "Same" convolution (k 1 or 5, stride 1) over whole rows; writes only data positions, and
/// zero rows first when overwriting, so pads stay zero. `wbuf` holds one channel group's
/// weights as f32 (converted once per group, not once per tile).
fn conv_same(conv: &Conv, input: &[f32], lay: Layout, out: &mut [f32], mode: Accumulate, wbuf: &mut WeightTile) {
    match conv.k {
        1 => conv_groups::<1, 1>(conv, input, lay, lay, out, mode, wbuf),
        _ => conv_groups::<KERNEL, 1>(conv, input, lay, lay, out, mode, wbuf),
    }
}

/// Stride-2 convolution, k 3, pad 1, per trajectory: `len` → ⌈len / 2⌉. Output `l` is what a
/// "same" k-3 convolution gives at position `2l`, so the same register tiles compute it and
/// only the even positions are kept: twice the multiplications of a strided loop, but whole
/// vectors instead of a gather (the strided loop was an eighth of the network's time). Each
/// output sums over input channel, then tap, as the strided loop did: the same bits.
fn conv_down(conv: &Conv, input: &[f32], lay: Layout, out: &mut [f32], lay_out: Layout, wbuf: &mut WeightTile) {
    conv_groups::<3, 2>(conv, input, lay, lay_out, out, Accumulate::Overwrite, wbuf);
}

/// A convolution with `K` taps (centred, zero pads) in groups of `TILE_CHANNELS` output
/// channels, keeping every `S`-th data position: output `l` of trajectory `b` is position
/// `S·l` of the input's trajectory `b`, written at `lay_out.at(c, b, l)`.
fn conv_groups<const K: usize, const S: usize>(
    conv: &Conv,
    input: &[f32],
    lay: Layout,
    lay_out: Layout,
    out: &mut [f32],
    mode: Accumulate,
    wbuf: &mut WeightTile,
) {
    let mut co0 = 0;
    while co0 < conv.cout {
        if co0 + TILE_CHANNELS <= conv.cout {
            conv_rows::<TILE_CHANNELS, K, S>(conv, input, Layouts { lay, lay_out }, co0, out, mode, wbuf);
            co0 += TILE_CHANNELS;
        } else {
            conv_rows::<1, K, S>(conv, input, Layouts { lay, lay_out }, co0, out, mode, wbuf);
            co0 += 1;
        }
    }
}

/// The layouts a convolution reads its input in and writes its output in.
#[derive(Clone, Copy)]
struct Layouts {
    lay: Layout,
    lay_out: Layout,
}

#[inline(always)]
fn conv_rows<const CO: usize, const K: usize, const S: usize>(
    conv: &Conv,
    input: &[f32],
    Layouts { lay, lay_out }: Layouts,
    co0: usize,
    out: &mut [f32],
    mode: Accumulate,
    wbuf: &mut WeightTile,
) {
    let (row, seg) = (lay.row(), lay.seg());
    let row_out = lay_out.row();
    let shift = PAD - K / 2;
    let taps = conv.cin * K;
    if let Some(tile) = wbuf.get_mut(..taps * CO) {
        for c in 0..CO {
            let w = conv.weights.get((co0 + c) * taps..(co0 + c + 1) * taps).unwrap_or(&[]);
            for (at_tap, w) in tile.chunks_exact_mut(CO).zip(w) {
                if let Some(slot) = at_tap.get_mut(c) {
                    *slot = f32::from(*w as i8);
                }
            }
        }
    }
    if mode == Accumulate::Overwrite
        && let Some(rows) = out.get_mut(co0 * row_out..(co0 + CO) * row_out)
    {
        rows.fill(0.0);
    }
    // `taps · CO` ≤ `MAX_TAPS · TILE_CHANNELS` for every generated layer; the exact length lets
    // the compiler drop the tile's checks.
    let Some(weights) = wbuf.get(..taps * CO) else {
        return;
    };
    // Output q sits at row index q + PAD and reads input q + shift .. q + shift + K.
    let outputs = lay.batch * seg - 2 * PAD;
    let mut q0 = 0;
    while q0 < outputs {
        let acc = conv_tile::<CO, K>(
            weights,
            input.get(shift + q0..).unwrap_or(&[]),
            row,
            conv.cin,
            taps_of::<K>(conv),
        );
        // Keep the tile's data positions: trajectory b's run [b·seg + PAD, b·seg + PAD + len).
        let (lo, hi) = (q0 + PAD, (q0 + PAD + TILE).min(outputs + PAD));
        let mut b = lo / seg;
        while b * seg + PAD < hi {
            let first = b * seg + PAD;
            let (from, to) = (first.max(lo), (first + lay.len).min(hi));
            if from < to {
                for (c, acc_c) in acc.iter().enumerate() {
                    let (Some(&scale), Some(&bias)) = (conv.scale.get(co0 + c), conv.bias.get(co0 + c)) else {
                        continue;
                    };
                    let run = acc_c.get(from - lo..to - lo).unwrap_or(&[]);
                    if S == 1 {
                        let Some(dst) = out.get_mut((co0 + c) * row + from..(co0 + c) * row + to) else {
                            continue;
                        };
                        for (d, a) in dst.iter_mut().zip(run) {
                            match mode {
                                Accumulate::Overwrite => *d = *a * scale + bias,
                                Accumulate::Add => *d += *a * scale + bias,
                            }
                        }
                    } else {
                        for (l, a) in (from - first..to - first).zip(run) {
                            if l % S != 0 {
                                continue;
                            }
                            if let Some(d) = out.get_mut(lay_out.at(co0 + c, b, l / S)) {
                                match mode {
                                    Accumulate::Overwrite => *d = *a * scale + bias,
                                    Accumulate::Add => *d += *a * scale + bias,
                                }
                            }
                        }
                    }
                }
            }
            b += 1;
        }
        q0 += TILE;
    }
}

/// Transposed convolution, k 4, stride 2, pad 1, per trajectory: `len` → 2·len, cropped.
/// Input i lands on output 2i + k − 1, so output 2m takes taps 1 (x_m) and 3 (x_{m−1}) and
/// output 2m + 1 takes taps 0 (x_{m+1}) and 2 (x_m); the zero pads supply x_{−1} and x_len.
fn conv_up(conv: &Conv, input: &[f32], lay: Layout, out: &mut [f32], lay_out: Layout) {
    let len = lay.len.min(LENGTHS[0]);
    let out_len = lay_out.len.min(LENGTHS[0]);
    let (mut even, mut odd) = ([0.0f32; LENGTHS[0]], [0.0f32; LENGTHS[0]]);
    let mut acc = [0.0f32; LENGTHS[0]];
    if let Some(rows) = out.get_mut(..conv.cout * lay_out.row()) {
        rows.fill(0.0);
    }
    for ((co, &scale), &bias) in (0..conv.cout).zip(conv.scale).zip(conv.bias) {
        for b in 0..lay.batch {
            even[..len].fill(0.0);
            odd[..len].fill(0.0);
            for ci in 0..conv.cin {
                let at = lay.at(ci, b, 0);
                let w = conv
                    .weights
                    .get((co * conv.cin + ci) * 4..)
                    .and_then(|w| w.first_chunk::<4>());
                let Some(&w) = w else { continue };
                let [w0, w1, w2, w3] = w.map(|w| f32::from(w as i8));
                let (Some(prev), Some(here), Some(next)) = (
                    input.get(at - 1..at - 1 + len),
                    input.get(at..at + len),
                    input.get(at + 1..at + 1 + len),
                ) else {
                    continue;
                };
                for (((e, o), (p, h)), n) in even[..len]
                    .iter_mut()
                    .zip(&mut odd[..len])
                    .zip(prev.iter().zip(here))
                    .zip(next)
                {
                    *e += w1 * h;
                    *e += w3 * p;
                    *o += w0 * n;
                    *o += w2 * h;
                }
            }
            for (pair, (e, o)) in acc[..out_len].chunks_mut(2).zip(even[..len].iter().zip(&odd[..len])) {
                // Output 2m is the even sum, 2m + 1 the odd one (dropped past the crop).
                for (a, v) in pair.iter_mut().zip([e, o]) {
                    *a = *v;
                }
            }
            let start = lay_out.at(co, b, 0);
            if let Some(dst) = out.get_mut(start..start + lay_out.len) {
                write_run(dst, &acc[..out_len], scale, bias);
            }
        }
    }
}

fn write_run(dst: &mut [f32], acc: &[f32], scale: f32, bias: f32) {
    for (d, a) in dst.iter_mut().zip(acc) {
        *d = *a * scale + bias;
    }
}

/// Lanes of [`crate::float::expf_lanes`] in Mish: one AVX register.
const LANES: usize = 8;

/// GroupNorm (per trajectory; biased variance, ε 1e-5, two passes) then Mish, in place on the
/// data positions. The `expf`s go first, run by run and eight lanes at a time (the same bits
/// as one call each), so the rest of Mish vectorizes.
fn norm_mish(x: &mut [f32], channels: usize, lay: Layout, gamma: &[f32], beta: &[f32]) {
    let len = lay.len;
    let per_group = channels / GROUPS;
    let count = (per_group * len) as f32;
    let mut u = [0.0f32; LENGTHS[0]];
    for b in 0..lay.batch {
        for g in 0..GROUPS {
            let rows = g * per_group..(g + 1) * per_group;
            let run = |c: usize| x.get(lay.at(c, b, 0)..lay.at(c, b, len)).unwrap_or(&[]);
            let mut sum = 0.0f32;
            for c in rows.clone() {
                sum += run(c).iter().fold(0.0f32, |a, v| a + v);
            }
            let mean = sum / count;
            let mut var = 0.0f32;
            for c in rows.clone() {
                var += run(c).iter().fold(0.0f32, |a, v| a + (v - mean) * (v - mean));
            }
            let inv = 1.0 / crate::float::sqrt(var / count + 1e-5);
            for c in rows {
                let (Some(&ga), Some(&be)) = (gamma.get(c), beta.get(c)) else {
                    continue;
                };
                let ga = ga * inv;
                let Some(run) = x.get_mut(lay.at(c, b, 0)..lay.at(c, b, len)) else {
                    continue;
                };
                // Three passes, so that only the `expf` calls stay scalar: the normalization, the
                // calls, then the squarings (a chain of three products after each call) and the
                // rest of Mish in vectors. The same operations on the same values: the same bits.
                for v in run.iter_mut() {
                    *v = (*v - mean) * ga + be;
                }
                let mut calls = run.chunks_exact(LANES).zip(u.chunks_exact_mut(LANES));
                for (v, e) in &mut calls {
                    if let (Ok(v), Ok(e)) = (<&[f32; LANES]>::try_from(v), <&mut [f32; LANES]>::try_from(e)) {
                        *e = crate::float::expf_lanes(&v.map(|x| x.min(20.0) * 0.125));
                    }
                }
                let done = run.len() - run.len() % LANES;
                for (v, e) in run.iter().zip(u.iter_mut()).skip(done) {
                    *e = mish_exp_eighth(*v);
                }
                for (v, e) in run.iter_mut().zip(&u) {
                    *v = mish_from_exp(*v, eighth_power(*e));
                }
            }
        }
    }
}

fn conv_block(block: &ConvBlock, input: &[f32], lay: Layout, out: &mut [f32], wbuf: &mut WeightTile) {
    conv_same(&block.conv, input, lay, out, Accumulate::Overwrite, wbuf);
    norm_mish(out, block.conv.cout, lay, block.gamma, block.beta);
}

/// `out = block1(block0(x) + time) + residual(x)`, `h` is scratch.
fn res_block(
    block: &ResBlock,
    x: &[f32],
    lay: Layout,
    temb: &[f32; TIME_DIM],
    h: &mut [f32],
    out: &mut [f32],
    wbuf: &mut WeightTile,
) {
    let cout = block.block0.conv.cout.min(MAX_WIDTH);
    conv_block(&block.block0, x, lay, h, wbuf);
    let mut shift = [0.0f32; MAX_WIDTH];
    linear(&block.time, temb, &mut shift[..cout]);
    for (c, add) in shift[..cout].iter().enumerate() {
        for b in 0..lay.batch {
            for v in h.get_mut(lay.at(c, b, 0)..lay.at(c, b, lay.len)).unwrap_or(&mut []) {
                *v += add;
            }
        }
    }
    conv_block(&block.block1, h, lay, out, wbuf);
    match &block.residual {
        Some(res) => conv_same(res, x, lay, out, Accumulate::Add, wbuf),
        // Pads are zero in both, so whole rows add.
        None => {
            for (o, v) in out.iter_mut().zip(x).take(cout * lay.row()) {
                *o += v;
            }
        }
    }
}
