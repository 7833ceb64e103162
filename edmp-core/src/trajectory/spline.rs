//! The path's shape in joint space: a uniform cubic B-spline over the waypoints.
//!
//! [`Shape::Spline`] takes the waypoints as control points, the first and last three times
//! over: the curve starts and ends exactly at them with zero first and second parameter
//! derivatives, is C² (so a finite jerk is possible), and each span lies in the convex hull of
//! four consecutive waypoints. [`Shape::Polyline`] takes every waypoint three times: each span's
//! control points are then copies of two consecutive waypoints, so the curve *is* the linear
//! interpolation the planner checked, stopping (zero parameter velocity) at every waypoint.
//!
//! The parameter `u` runs over `[0, spans]`, one unit per span; derivatives are per unit of `u`.

use crate::error::Error;

/// Largest magnitude (rad) of a waypoint joint the timing accepts: far beyond any arm's joint,
/// small enough that every difference and product of the timing stays finite in `f32`.
pub const MAX_JOINT_MAGNITUDE: f32 = 100.0;

/// Which curve through the waypoints the trajectory follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// The C² cubic B-spline: smooth and fast, within [`deviation_bound`] of the polyline.
    Spline,
    /// The exact polyline (linear interpolation), stopping at every waypoint.
    Polyline,
}

/// A curve's position and its first three derivatives with respect to `u` at one parameter,
/// for an arm with `J` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint<const J: usize> {
    /// Joint positions (rad).
    pub q: [f32; J],
    /// dq/du (rad per span).
    pub d1: [f32; J],
    /// d²q/du².
    pub d2: [f32; J],
    /// d³q/du³ (constant on a span).
    pub d3: [f32; J],
}

/// The curve of `shape` over `H` borrowed waypoints of `J` joints.
#[derive(Clone, Copy, Debug)]
pub struct Curve<'a, const H: usize, const J: usize> {
    waypoints: &'a [[f32; J]; H],
    shape: Shape,
}

/// Checks every waypoint joint: finite, and within [`MAX_JOINT_MAGNITUDE`].
pub fn validate_waypoints<const J: usize>(waypoints: &[[f32; J]]) -> Result<(), Error> {
    for w in waypoints {
        for (j, v) in w.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::NonFiniteJoint { joint: j as u8 });
            }
            if v.abs() > MAX_JOINT_MAGNITUDE {
                return Err(Error::OutOfRange { joint: j as u8 });
            }
        }
    }
    Ok(())
}

impl<'a, const H: usize, const J: usize> Curve<'a, H, J> {
    /// The curve of `shape` through `waypoints` (validate them first: [`validate_waypoints`]).
    pub const fn new(waypoints: &'a [[f32; J]; H], shape: Shape) -> Self {
        Self { waypoints, shape }
    }

    /// Number of spans: `H + 1` for the spline (`H + 4` control points), `3H - 3` for the
    /// polyline (`3H`), at least 1.
    pub const fn spans(&self) -> usize {
        let s = match self.shape {
            Shape::Spline => H + 1,
            Shape::Polyline => (3 * H).saturating_sub(3),
        };
        if s == 0 { 1 } else { s }
    }

    /// Control point `k` (indices past either end repeat the end).
    pub fn control(&self, k: usize) -> [f32; J] {
        let w = match self.shape {
            Shape::Spline => k.saturating_sub(2),
            Shape::Polyline => k / 3,
        };
        let last = H.saturating_sub(1);
        self.waypoints.get(w.min(last)).copied().unwrap_or([0.0; J])
    }

    /// The four control points of span `i`.
    pub fn span_points(&self, i: usize) -> [[f32; J]; 4] {
        core::array::from_fn(|k| self.control(i + k))
    }

    /// Splits `u` into a span index and the local parameter in [0, 1] (clamped; NaN gives 0).
    pub fn locate(&self, u: f32) -> (usize, f32) {
        let spans = self.spans();
        let u = if u > 0.0 { u.min(spans as f32) } else { 0.0 };
        let i = (libm::floorf(u) as usize).min(spans - 1);
        (i, (u - i as f32).clamp(0.0, 1.0))
    }

    /// Position and derivatives at `u`.
    pub fn eval(&self, u: f32) -> CurvePoint<J> {
        let (i, s) = self.locate(u);
        eval_span(&self.span_points(i), s)
    }

    /// Largest |dq_j/du| on span `i`, over all joints: the derivative is a quadratic B-spline
    /// whose control points are the differences of consecutive control points, so it is bounded
    /// by the largest of them.
    pub fn speed_bound(&self, i: usize) -> f32 {
        let p = self.span_points(i);
        let mut b = 0.0f32;
        for k in 0..3 {
            if let (Some(a), Some(c)) = (p.get(k), p.get(k + 1)) {
                for (x, y) in a.iter().zip(c) {
                    b = b.max((y - x).abs());
                }
            }
        }
        b
    }

    /// Per-joint bounds on |q'|, |q''|, |q'''| over the whole curve: the largest first, second
    /// and third differences of the control points (the derivatives are B-splines over them).
    pub fn derivative_bounds(&self) -> [[f32; J]; 3] {
        let mut out = [[0.0f32; J]; 3];
        let n = self.spans() + 3;
        for k in 0..n {
            let p: [[f32; J]; 4] = core::array::from_fn(|m| self.control(k + m));
            let [p0, p1, p2, p3] = p;
            for j in 0..J {
                let v = |q: &[f32; J]| q.get(j).copied().unwrap_or(0.0);
                let (a, b, c, d) = (v(&p0), v(&p1), v(&p2), v(&p3));
                let diffs = [b - a, c - 2.0 * b + a, d - 3.0 * c + 3.0 * b - a];
                for (o, dv) in out.iter_mut().zip(diffs) {
                    if let Some(slot) = o.get_mut(j) {
                        *slot = slot.max(dv.abs());
                    }
                }
            }
        }
        out
    }
}

/// Position and derivatives on one span. Written in differences from the second control point
/// so that equal control points give exactly that point (the ends, the polyline's waypoints).
pub fn eval_span<const J: usize>(p: &[[f32; J]; 4], s: f32) -> CurvePoint<J> {
    let r = 1.0 - s;
    let (s2, s3) = (s * s, s * s * s);
    let b = [r * r * r / 6.0, (-3.0 * s3 + 3.0 * s2 + 3.0 * s + 1.0) / 6.0, s3 / 6.0];
    let c = [-0.5 * r * r, 0.5 * (-3.0 * s2 + 2.0 * s + 1.0), 0.5 * s2];
    let e = [r, 1.0 - 3.0 * s, s];
    let f = [-1.0, -3.0, 1.0];
    let [p0, p1, p2, p3] = p;
    let mut out = CurvePoint {
        q: *p1,
        d1: [0.0; J],
        d2: [0.0; J],
        d3: [0.0; J],
    };
    for j in 0..J {
        let at = |q: &[f32; J]| q.get(j).copied().unwrap_or(0.0);
        let base = at(p1);
        let d = [at(p0) - base, at(p2) - base, at(p3) - base];
        let dot = |w: &[f32; 3]| w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
        if let Some(q) = out.q.get_mut(j) {
            *q = base + dot(&b);
        }
        if let Some(v) = out.d1.get_mut(j) {
            *v = dot(&c);
        }
        if let Some(v) = out.d2.get_mut(j) {
            *v = dot(&e);
        }
        if let Some(v) = out.d3.get_mut(j) {
            *v = dot(&f);
        }
    }
    out
}

/// Rounding allowance (rad) added to [`deviation_bound`]: `f32` evaluation of joints within a
/// turn and a bit either way (|q| < 8 rad, every arm's range; a few ulps of 5e-7).
pub const ROUNDING_ALLOWANCE: f32 = 1e-5;

/// Largest max-norm distance (rad) from any point of the curve to the polyline, bounded
/// analytically. On span `i` the curve minus the polyline point `(1-s)P₁ + sP₂` is
/// `(1-s)³/6 Δ²P₀ + s³/6 Δ²P₁` (the spline reproduces linear functions), so it never exceeds the
/// largest second difference of the control points over 6. The polyline shape is exact, up to
/// [`ROUNDING_ALLOWANCE`], which both include.
pub fn deviation_bound<const H: usize, const J: usize>(waypoints: &[[f32; J]; H], shape: Shape) -> f32 {
    match shape {
        Shape::Polyline => ROUNDING_ALLOWANCE,
        Shape::Spline => {
            let mut worst = 0.0f32;
            for w in waypoints.windows(3) {
                if let [a, b, c] = w {
                    for ((x, y), z) in a.iter().zip(b).zip(c) {
                        worst = worst.max((x - 2.0 * y + z).abs());
                    }
                }
            }
            // The tripled ends: second differences W₁ - W₀ and W_{H-2} - W_{H-1}.
            if let (Some(a), Some(b)) = (waypoints.first(), waypoints.get(1)) {
                for (x, y) in a.iter().zip(b) {
                    worst = worst.max((y - x).abs());
                }
            }
            if let (Some(a), Some(b)) = (
                waypoints.last(),
                waypoints.len().checked_sub(2).and_then(|k| waypoints.get(k)),
            ) {
                for (x, y) in a.iter().zip(b) {
                    worst = worst.max((y - x).abs());
                }
            }
            worst / 6.0 + ROUNDING_ALLOWANCE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn wavy() -> [[f32; 7]; 12] {
        core::array::from_fn(|k| core::array::from_fn(|j| 0.3 * libm::sinf(0.5 * k as f32 + j as f32) + 0.1 * j as f32))
    }

    #[test]
    fn ends_are_exact_and_at_rest() {
        let w = wavy();
        for shape in [Shape::Spline, Shape::Polyline] {
            let c = Curve::new(&w, shape);
            let a = c.eval(0.0);
            let b = c.eval(c.spans() as f32);
            assert_eq!(a.q, w[0]);
            assert_eq!(b.q, w[11]);
            assert_eq!((a.d1, a.d2), ([0.0; 7], [0.0; 7]));
            assert_eq!((b.d1, b.d2), ([0.0; 7], [0.0; 7]));
        }
        assert_eq!(Curve::new(&w, Shape::Spline).spans(), 13);
        assert_eq!(Curve::new(&w, Shape::Polyline).spans(), 33);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let w = wavy();
        for shape in [Shape::Spline, Shape::Polyline] {
            let c = Curve::new(&w, shape);
            let h = 1e-3f32;
            for k in 1..(c.spans() * 7) {
                let u = k as f32 / 7.0 + 0.031;
                if (u - libm::roundf(u)).abs() < 2.0 * h || u + h > c.spans() as f32 {
                    continue;
                }
                let (m, p, z) = (c.eval(u - h), c.eval(u + h), c.eval(u));
                for j in 0..7 {
                    let fd1 = (p.q[j] - m.q[j]) / (2.0 * h);
                    let fd2 = (p.d1[j] - m.d1[j]) / (2.0 * h);
                    let fd3 = (p.d2[j] - m.d2[j]) / (2.0 * h);
                    assert!(
                        (fd1 - z.d1[j]).abs() < 2e-3,
                        "{shape:?} u {u} j {j}: {fd1} vs {}",
                        z.d1[j]
                    );
                    assert!(
                        (fd2 - z.d2[j]).abs() < 2e-3,
                        "{shape:?} u {u} j {j}: {fd2} vs {}",
                        z.d2[j]
                    );
                    assert!(
                        (fd3 - z.d3[j]).abs() < 2e-3,
                        "{shape:?} u {u} j {j}: {fd3} vs {}",
                        z.d3[j]
                    );
                }
            }
        }
    }

    /// Max-norm distance from `p` to segment `a → b`, minimised over the segment parameter by
    /// a fine scan (an independent, slow oracle).
    fn dist_to_polyline(p: &[f32; 7], w: &[[f32; 7]]) -> f32 {
        let mut best = f32::INFINITY;
        for s in w.windows(2) {
            for k in 0..=2000 {
                let t = k as f32 / 2000.0;
                let d = (0..7)
                    .map(|j| (p[j] - (s[0][j] + t * (s[1][j] - s[0][j]))).abs())
                    .fold(0.0, f32::max);
                best = best.min(d);
            }
        }
        best
    }

    #[test]
    fn the_deviation_bound_holds_and_the_polyline_is_exact() {
        let w = wavy();
        let bound = deviation_bound(&w, Shape::Spline);
        let c = Curve::new(&w, Shape::Spline);
        let mut worst = 0.0f32;
        let samples: Vec<f32> = (0..=c.spans() * 10).map(|k| k as f32 / 10.0).collect();
        for &u in &samples {
            worst = worst.max(dist_to_polyline(&c.eval(u).q, &w));
        }
        assert!(worst <= bound, "{worst} > {bound}");
        assert!(worst > 0.3 * bound, "bound {bound} is loose: {worst}");
        let c = Curve::new(&w, Shape::Polyline);
        for k in 0..c.spans() * 10 {
            let u = k as f32 / 10.0;
            let (i, _) = c.locate(u);
            let (a, b) = (w[i / 3], w[(i / 3 + 1).min(11)]);
            let q = c.eval(u).q;
            // On the segment: one common interpolation parameter for every joint.
            let j = (0..7)
                .max_by(|&x, &y| (b[x] - a[x]).abs().total_cmp(&(b[y] - a[y]).abs()))
                .unwrap();
            let t = (q[j] - a[j]) / (b[j] - a[j]);
            assert!((-1e-6..=1.0 + 1e-6).contains(&t));
            for j in 0..7 {
                assert!((q[j] - (a[j] + t * (b[j] - a[j]))).abs() < 1e-5, "u {u} joint {j}");
            }
        }
    }

    #[test]
    fn bounds_cover_sampled_derivatives() {
        let w = wavy();
        let c = Curve::new(&w, Shape::Spline);
        let [b1, b2, b3] = c.derivative_bounds();
        for k in 0..=c.spans() * 16 {
            let p = c.eval(k as f32 / 16.0);
            for j in 0..7 {
                assert!(p.d1[j].abs() <= b1[j] * 1.0001 + 1e-7);
                assert!(p.d2[j].abs() <= b2[j] * 1.0001 + 1e-7);
                assert!(p.d3[j].abs() <= b3[j] * 1.0001 + 1e-7);
                assert!(p.d1[j].abs() <= c.speed_bound(c.locate(k as f32 / 16.0).0) * 1.0001 + 1e-7);
            }
        }
        assert_eq!(
            validate_waypoints(&[[0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0]]),
            Err(Error::NonFiniteJoint { joint: 2 })
        );
        assert_eq!(
            validate_waypoints(&[[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1e3]]),
            Err(Error::OutOfRange { joint: 6 })
        );
    }
}
