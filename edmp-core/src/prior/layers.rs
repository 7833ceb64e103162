//! The network's layer types, as the generated weight table (`weights.rs`) lays them out and
//! the forward pass (`net.rs`) reads them: int8 weights with one f32 scale per output channel.

use super::weights::LEVELS;

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
    pub(crate) down: &'static [Down; LEVELS],
    pub(crate) mid0: ResBlock,
    pub(crate) mid1: ResBlock,
    pub(crate) up: &'static [Up; LEVELS - 1],
    pub(crate) final_block: ConvBlock,
    pub(crate) out: Conv,
}
