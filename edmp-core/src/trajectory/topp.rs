//! Time-optimal path parameterization under joint velocity and acceleration limits, in the
//! manner of TOPP-RA (Pham & Pham, 2018): reachability analysis on a grid over the path
//! parameter, `x = u̇²` at the grid points, `ü` constant on each grid interval (so
//! `x_{i+1} = x_i + 2 Δu ü_i`).
//!
//! Constraints at grid point `i`, per joint `j`: `q'_j² x ≤ v_j²` and
//! `|q'_j ü + q''_j x| ≤ a_j`. The backward pass computes each point's controllable set
//! `[lo_i, hi_i]` (the `x` from which the rest of the path can still stop at `x_end = 0`) as the
//! projection of a 2-D polygon in `(x, ü)`: Fourier-Motzkin elimination of `ü`, every bound kept
//! in multiplied form so that no division by a small `q'` happens before the last step. The
//! forward pass then takes, from `x_0 = 0`, the largest admissible `ü` that stays controllable.

use super::limits::JointLimits;
use super::spline::{Curve, eval_span};

/// Cap on `u̇²` (spans²/s²): where the path barely moves, nothing else bounds it. 1e6 means at
/// most 1000 spans per second, far faster than any limit allows on a moving path.
pub const X_CAP: f32 = 1e6;

/// Share of each joint's jerk limit given to the path's own `q''' u̇³` term (the rest is for
/// the filter's): an `x` cap where the path turns sharply in the parameter (the polyline's
/// waypoints, where `q' = q'' = 0` and nothing else bounds the speed of `u`).
pub const JERK_SHARE: f32 = 0.5;

/// One half-plane `r ü + p x ≤ d` of the `(x, ü)` polygon.
#[derive(Clone, Copy)]
struct Row {
    r: f32,
    p: f32,
    d: f32,
}

/// The `(x, ü)` polygon of one interval: four acceleration rows per joint (both ends, both
/// signs), then up to four more: the bound on `|ü|` and the next point's set. Rows per joint
/// rather than one array of `4 J + 4`, which a generic `J` cannot size.
struct Rows<const J: usize> {
    joints: [[Row; 4]; J],
    extra: [Row; 4],
    extras: usize,
}

impl<const J: usize> Rows<J> {
    /// The acceleration rows of interval `i` in `(x_i, ü_i)`: at its start, and at its end where
    /// `x_{i+1} = x_i + 2Δu ü_i` (TOPP-RA's first-order interpolation scheme: without it the
    /// speed may jump wherever `q' = 0` at a grid point, and the acceleration in between is
    /// unbounded); and the bound on `|ü|` where there is one.
    fn acceleration(a: &Point<J>, b: &Point<J>, du: f32, limits: &JointLimits<J>) -> Self {
        let zero = Row { r: 0.0, p: 0.0, d: 0.0 };
        let mut rows = Self {
            joints: [[zero; 4]; J],
            extra: [zero; 4],
            extras: 0,
        };
        for (j, out) in rows.joints.iter_mut().enumerate() {
            let g = |x: &[f32; J]| x.get(j).copied().unwrap_or(0.0);
            let lim = g(&limits.acceleration);
            let (r0, p0) = (g(&a.d1), g(&a.d2));
            let p1 = g(&b.d2);
            let r1 = g(&b.d1) + 2.0 * du * p1;
            *out = [
                Row { r: r0, p: p0, d: lim },
                Row { r: -r0, p: -p0, d: lim },
                Row { r: r1, p: p1, d: lim },
                Row { r: -r1, p: -p1, d: lim },
            ];
        }
        if a.acc_cap.is_finite() {
            rows.push(Row {
                r: 1.0,
                p: 0.0,
                d: a.acc_cap,
            });
            rows.push(Row {
                r: -1.0,
                p: 0.0,
                d: a.acc_cap,
            });
        }
        rows
    }

    fn push(&mut self, row: Row) {
        if let Some(slot) = self.extra.get_mut(self.extras) {
            *slot = row;
            self.extras += 1;
        }
    }

    /// Every row, in order: the joints' (joint by joint), then the others as pushed.
    fn iter(&self) -> impl Iterator<Item = &Row> {
        self.joints
            .as_flattened()
            .iter()
            .chain(self.extra.get(..self.extras).unwrap_or(&[]))
    }
}

/// Largest excess, as a fraction of the limit, of a joint's acceleration inside an interval over
/// its values at the ends. On an interval `q̈_j` is a quadratic in `u` whose `u²` coefficient is
/// `2.5 q'''_j ü`, so its excess is at most `2.5 |q'''_j ü| Δu² / 4`: bounding that bounds `|ü|`
/// (where `q' = 0` at a grid point, the polyline's waypoints, nothing else would).
pub const INTERIOR_EXCESS: f32 = 0.05;

/// What the passes need of the curve at one grid point.
#[derive(Clone, Copy)]
struct Point<const J: usize> {
    d1: [f32; J],
    d2: [f32; J],
    cap: f32,
    /// Bound on `|ü|` over the interval that starts here ([`INTERIOR_EXCESS`]).
    acc_cap: f32,
}

/// The curve's derivatives at grid point `i`, and the cap on `x` there: velocity, the state
/// part of jerk (both spans meeting at a knot, when jerk counts), and [`X_CAP`].
fn point<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    i: usize,
    m: usize,
    limits: &JointLimits<J>,
    jerk: bool,
    acc_cap: f32,
) -> Point<J> {
    let u = i as f32 / m as f32;
    let p = curve.eval(u);
    let mut cap = X_CAP;
    for (d, v) in p.d1.iter().zip(&limits.velocity) {
        let d2 = d * d;
        if d2 > 0.0 {
            cap = cap.min(v * v / d2);
        }
    }
    if jerk {
        let (span, _) = curve.locate(u);
        let left = if i.is_multiple_of(m) {
            span.saturating_sub(1)
        } else {
            span
        };
        for s in [left, span] {
            let d3 = eval_span(&curve.span_points(s), 0.0).d3;
            for (d, j) in d3.iter().zip(&limits.jerk) {
                let d = d.abs();
                if d > 0.0 {
                    let c = libm::cbrtf(JERK_SHARE * j / d);
                    cap = cap.min(c * c);
                }
            }
        }
    }
    let d3 = eval_span(&curve.span_points(i / m), 0.0).d3;
    let local = interior_cap(&d3, m, limits);
    let acc_cap = if local.is_finite() { local } else { acc_cap };
    Point {
        d1: p.d1,
        d2: p.d2,
        cap,
        acc_cap,
    }
}

/// The [`INTERIOR_EXCESS`] bound on `|ü|` for third derivatives `d3`.
fn interior_cap<const J: usize>(d3: &[f32; J], m: usize, limits: &JointLimits<J>) -> f32 {
    let du = 1.0 / m as f32;
    let mut cap = f32::INFINITY;
    for (d, a) in d3.iter().zip(&limits.acceleration) {
        let d = d.abs();
        if d > 0.0 {
            cap = cap.min(4.0 * INTERIOR_EXCESS * a / (2.5 * d * du * du));
        }
    }
    cap
}

/// The same over the whole curve: for spans where the path stands still (repeated waypoints:
/// `q' = q'' = q''' = 0`), so that the parameter's speed still changes gradually there and the
/// filter's jerk where motion resumes stays bounded.
fn global_cap<const H: usize, const J: usize>(curve: &Curve<'_, H, J>, m: usize, limits: &JointLimits<J>) -> f32 {
    let [_, _, d3] = curve.derivative_bounds();
    interior_cap(&d3, m, limits)
}

/// Fills `hi` and `lo` (indices `0..=k`) with the controllable sets of the grid `u_i = i/m`.
pub(crate) fn backward<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    m: usize,
    k: usize,
    limits: &JointLimits<J>,
    jerk: bool,
    hi: &mut [f32],
    lo: &mut [f32],
) {
    let du = 1.0 / m as f32;
    let (mut next_hi, mut next_lo) = (0.0f32, 0.0f32);
    if let (Some(h), Some(l)) = (hi.get_mut(k), lo.get_mut(k)) {
        (*h, *l) = (0.0, 0.0);
    }
    let cap = global_cap(curve, m, limits);
    let mut next = point(curve, k, m, limits, jerk, cap);
    for i in (0..k).rev() {
        let here = point(curve, i, m, limits, jerk, cap);
        let mut x_hi = here.cap;
        let mut x_lo = 0.0f32;
        let mut rows = Rows::acceleration(&here, &next, du, limits);
        rows.push(Row {
            r: 2.0 * du,
            p: 1.0,
            d: next_hi,
        });
        rows.push(Row {
            r: -2.0 * du,
            p: -1.0,
            d: -next_lo,
        });
        // Bound on x from one half-plane `px ≤ d` (no ü left).
        let mut apply = |p: f32, d: f32| {
            if p > 0.0 {
                x_hi = x_hi.min(d / p);
            } else if p < 0.0 {
                x_lo = x_lo.max(d / p);
            } else if d < 0.0 {
                x_hi = f32::NEG_INFINITY;
            }
        };
        for up in rows.iter() {
            if up.r == 0.0 {
                apply(up.p, up.d);
            }
            if up.r <= 0.0 {
                continue;
            }
            for down in rows.iter().filter(|d| d.r < 0.0) {
                // up·(−r_down) + down·r_up eliminates ü (both multipliers positive).
                let (mu, md) = (-down.r, up.r);
                apply(up.p * mu + down.p * md, up.d * mu + down.d * md);
            }
        }
        if x_hi.is_nan() || x_hi < x_lo {
            // Empty by rounding (or at a point no speed can pass): the slowest set there is.
            x_hi = x_lo.max(0.0);
        }
        next_hi = x_hi;
        next_lo = x_lo;
        next = here;
        if let (Some(h), Some(l)) = (hi.get_mut(i), lo.get_mut(i)) {
            (*h, *l) = (x_hi, x_lo);
        }
    }
}

/// Greedy forward pass over the sets of [`backward`]: overwrites `hi` with the chosen `x`
/// (`x_0 = 0`, `x_k = 0`).
pub(crate) fn forward<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    m: usize,
    k: usize,
    limits: &JointLimits<J>,
    jerk: bool,
    hi: &mut [f32],
    lo: &[f32],
) {
    let du = 1.0 / m as f32;
    let mut x = 0.0f32;
    if let Some(h) = hi.get_mut(0) {
        *h = 0.0;
    }
    let cap = global_cap(curve, m, limits);
    let mut here = point(curve, 0, m, limits, jerk, cap);
    for i in 0..k {
        let next = point(curve, i + 1, m, limits, jerk, cap);
        let rows = Rows::acceleration(&here, &next, du, limits);
        let mut acc_hi = f32::INFINITY;
        for row in rows.iter() {
            if row.r > 0.0 {
                acc_hi = acc_hi.min((row.d - row.p * x) / row.r);
            }
        }
        let (set_hi, set_lo) = (
            hi.get(i + 1).copied().unwrap_or(0.0),
            lo.get(i + 1).copied().unwrap_or(0.0),
        );
        let mut y = x + 2.0 * du * acc_hi;
        y = y.min(set_hi).max(set_lo).max(0.0);
        if !y.is_finite() || i + 1 == k {
            y = 0.0;
        }
        if let Some(h) = hi.get_mut(i + 1) {
            *h = y;
        }
        x = y;
        here = next;
    }
}

#[cfg(test)]
mod tests {
    use super::super::limits::Limits;
    use super::super::spline::Shape;
    use super::*;
    use crate::robot::PANDA;

    #[test]
    fn profile_starts_and_ends_at_rest_within_limits_at_the_grid() {
        let w: [[f32; 7]; 6] = core::array::from_fn(|k| [0.2 * k as f32, -0.1 * k as f32, 0.0, -1.5, 0.3, 1.5, 0.1]);
        let c = Curve::new(&w, Shape::Spline);
        let l = Limits::DEFAULT.joint_limits(&PANDA).unwrap();
        let (m, k) = (8, 8 * c.spans());
        let (mut hi, mut lo) = ([0.0f32; 64], [0.0f32; 64]);
        backward(&c, m, k, &l, true, &mut hi, &mut lo);
        assert!(hi.iter().take(k + 1).all(|h| h.is_finite() && *h >= 0.0));
        forward(&c, m, k, &l, true, &mut hi, &lo);
        assert_eq!((hi[0], hi[k]), (0.0, 0.0));
        assert!(hi[1..k].iter().all(|&x| x > 0.0));
        for i in 0..k {
            let p = c.eval(i as f32 / m as f32);
            let acc = (hi[i + 1] - hi[i]) * m as f32 / 2.0;
            for j in 0..7 {
                assert!(p.d1[j].abs() * hi[i].sqrt() <= l.velocity[j] * 1.001);
                assert!((p.d1[j] * acc + p.d2[j] * hi[i]).abs() <= l.acceleration[j] * 1.001 + 1e-3);
            }
        }
    }
}
