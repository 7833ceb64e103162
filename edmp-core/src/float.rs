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

#[cfg(test)]
mod tests {
    use super::*;

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
