//! Square roots for the hot paths: `libm`'s, the same bits everywhere, called so that x86-64
//! does not stall on them.
//!
//! On x86-64 `libm::sqrtf` is inline assembly of the legacy-SSE `sqrtss`. Inlined among the
//! AVX code of an x86-64-v3 build, it runs while the upper halves of the vector registers are
//! dirty and waits on them (`perf`: GroupNorm's one square root per group was a third of its
//! block's time, and the network 14 % faster without it). Behind a call that is never inlined,
//! the compiler clears the upper halves (`vzeroupper`) before the call and the instruction runs
//! clean. Elsewhere (a Cortex-M) the call is inlined as usual. Either way it is the same
//! function: a correctly rounded square root, the same bits as before and on every target.

/// `√x`, correctly rounded (`libm::sqrtf`); NaN below 0, as `libm`.
#[cfg(target_arch = "x86_64")]
#[inline(never)]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// `√x`, correctly rounded (`libm::sqrtf`); NaN below 0, as `libm`.
#[cfg(not(target_arch = "x86_64"))]
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// `x` limited to `[lo, hi]`: `f32::clamp`'s bits where `lo <= hi` (NaN stays NaN), without
/// its assertion, whose panic path a firmware would link when the bounds are an arm's table
/// the compiler cannot see (`lo > hi` gives `hi`).
#[inline]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}

/// A lower bound on `√x` within 0.1 % of it, without `libm::sqrtf`, whose legacy-SSE `sqrtss`
/// stalls among the AVX code around it on x86-64-v3 (`perf`: the balls' gaps were a tenth of a
/// global-stage plan's time): a first guess from the bits, one Newton step (which lands at most
/// 0.096 % above `√x`, never below but for rounding), then 0.1 % off. 0 where `x` is tiny or
/// not finite (always a lower bound).
#[inline]
pub fn sqrt_below(x: f32) -> f32 {
    if !x.is_finite() || x < 1e-30 {
        return 0.0;
    }
    let guess = f32::from_bits((x.to_bits() >> 1) + 0x1fbd_1df5);
    let newton = 0.5 * (guess + x / guess);
    newton * 0.999
}

/// `libm::expf` of every lane, the same bits: vertical SIMD. Each lane runs libm's own
/// reduction and polynomial (FreeBSD's `e_expf.c`) with its branches turned into selects, so an
/// x86-64 build computes eight lanes in a few AVX instructions where the scalar calls each
/// mispredict a branch on `|x|`; a lane outside the range those branches share (`|x|` ≤ 2⁻¹⁴,
/// beyond ±87.3, NaN) takes `libm::expf` itself. A Cortex-M runs the same lanes one by one.
pub fn expf_lanes<const L: usize>(x: &[f32; L]) -> [f32; L] {
    // libm 0.2's constants for `expf`.
    const HALF: [f32; 2] = [0.5, -0.5];
    const LN2_HI: f32 = 6.931_457_5e-1;
    const LN2_LO: f32 = 1.428_606_8e-6;
    const INV_LN2: f32 = core::f32::consts::LOG2_E; // 0x3fb8aa3b, libm's INV_LN2
    const P1: f32 = 1.666_662_5e-1;
    const P2: f32 = -2.766_733_3e-3;
    let mut out = [0.0f32; L];
    for (y, &x) in out.iter_mut().zip(x) {
        let hx = x.to_bits() & 0x7fff_ffff;
        let sign = x.to_bits() >> 31;
        // |x| > 1.5 ln 2: k rounds x / ln 2; above ½ ln 2: k = ±1; else k = 0, where the
        // reduction below leaves x as it is (x − 0·ln2hi = x, lo = 0).
        let k = if hx > 0x3f85_1592 {
            (INV_LN2 * x + if sign == 0 { HALF[0] } else { HALF[1] }) as i32
        } else if hx > 0x3eb1_7218 {
            1 - 2 * sign as i32
        } else {
            0
        };
        let kf = k as f32;
        let hi = x - kf * LN2_HI;
        let lo = kf * LN2_LO;
        let r = hi - lo;
        let rr = r * r;
        let c = r - rr * (P1 + rr * P2);
        let e = 1.0 + (r * c / (2.0 - c) - lo + hi);
        // libm's `scalbnf(e, k)`: for k in [−126, 127] one product with 2^k (1 for k = 0).
        *y = e * f32::from_bits(((0x7f + k.clamp(-126, 127)) as u32) << 23);
    }
    for (y, &x) in out.iter_mut().zip(x) {
        let hx = x.to_bits() & 0x7fff_ffff;
        if hx <= 0x3900_0000 || hx >= 0x42ae_ac50 {
            *y = libm::expf(x);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expf_lanes_is_libms_expf_bit_for_bit() {
        // Every 61st f32 bit pattern (positive and negative, NaNs and infinities included), in
        // lanes of 8, and the boundaries of libm's branches.
        let mut checked = 0u32;
        let mut lanes = [0.0f32; 8];
        let edges = [
            0x3900_0000u32,
            0x3eb1_7218,
            0x3f85_1592,
            0x42ae_ac50,
            0x42b1_7218,
            0x42cf_f1b5,
        ];
        let patterns = (0..=u32::MAX).step_by(61).chain(
            edges
                .iter()
                .flat_map(|&e| (e - 2..=e + 2).flat_map(|b| [b, b | 0x8000_0000])),
        );
        for (i, bits) in patterns.enumerate() {
            lanes[i % 8] = f32::from_bits(bits);
            if i % 8 == 7 {
                for (got, x) in expf_lanes(&lanes).iter().zip(&lanes) {
                    assert_eq!(
                        got.to_bits(),
                        libm::expf(*x).to_bits(),
                        "expf({x:e}) ({:#x})",
                        x.to_bits()
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 70_000_000, "{checked}");
    }

    #[test]
    fn clamp_has_f32_clamps_bits_and_never_panics() {
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            2.8973,
            -2.8973,
            1e-30,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let mut rng = crate::rng::Rng::new(7);
        let values = specials
            .into_iter()
            .chain((0..2000).map(|_| rng.uniform_f32(-4.0, 4.0)));
        let values: heapless::Vec<f32, 2048> = values.collect();
        for &x in &values {
            for (&lo, &hi) in values.iter().zip(values.iter().rev()).take(200) {
                let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
                assert_eq!(
                    clamp(x, lo, hi).to_bits(),
                    x.clamp(lo, hi).to_bits(),
                    "{x} in [{lo}, {hi}]"
                );
            }
        }
        assert!(clamp(f32::NAN, -1.0, 1.0).is_nan());
        // Bounds the wrong way round give `hi`, not a panic.
        assert_eq!(clamp(0.0, 1.0, -1.0), -1.0);
    }
}
