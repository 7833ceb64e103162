//! The time law `u(τ)`: TOPP's piecewise-quadratic profile, and its moving average.
//!
//! On grid interval `i` (from `τ = t_i`), `u = u_i + u̇_i σ + ü_i σ²/2` with `u̇_i = √x_i` and
//! `ü_i = (x_{i+1} − x_i)/(2Δu)`; `u = 0` before the start and `u = S` (the last parameter) after
//! the end. Its acceleration jumps between intervals, so its jerk is unbounded. The moving
//! average over a window `w`,
//! `u_f(τ) = (1/w) ∫_{τ−w}^{τ} u`, has `u̇_f = (u(τ) − u(τ−w))/w`, `ü_f = (u̇(τ) − u̇(τ−w))/w` and
//! `u⃛_f = (ü(τ) − ü(τ−w))/w`, bounded by `2 max|ü| / w`: it starts and ends at rest, never runs
//! backwards, and lasts `w` longer.

/// The grid arrays of one profile (`x` and `t` hold `points` entries).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Profile<'a> {
    pub(crate) x: &'a [f32],
    pub(crate) t: &'a [f32],
    /// Grid points per span (`Δu = 1/m`).
    pub(crate) m: f32,
    /// Moving-average window (0: none).
    pub(crate) w: f32,
}

/// `u` and its first three derivatives with respect to (unscaled) time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Law {
    pub(crate) u: f32,
    pub(crate) v: f32,
    pub(crate) a: f32,
    pub(crate) j: f32,
}

impl Profile<'_> {
    fn intervals(&self) -> usize {
        self.t.len().min(self.x.len()).saturating_sub(1)
    }

    /// End of the raw profile.
    pub(crate) fn end(&self) -> f32 {
        self.t.get(self.intervals()).copied().unwrap_or(0.0)
    }

    /// Last parameter value.
    fn last_u(&self) -> f32 {
        self.intervals() as f32 / self.m
    }

    /// Duration of the (filtered) profile.
    pub(crate) fn duration(&self) -> f32 {
        self.end() + self.w
    }

    /// Index of the interval holding `τ` (in `[0, end]`).
    fn interval(&self, tau: f32) -> usize {
        let n = self.intervals();
        let t = self.t.get(..=n).unwrap_or(&[]);
        t.partition_point(|&ti| ti <= tau)
            .saturating_sub(1)
            .min(n.saturating_sub(1))
    }

    /// Interval `i`'s start time, start parameter, start speed and acceleration.
    fn piece(&self, i: usize) -> (f32, f32, f32, f32) {
        let t0 = self.t.get(i).copied().unwrap_or(0.0);
        let x0 = self.x.get(i).copied().unwrap_or(0.0);
        let x1 = self.x.get(i + 1).copied().unwrap_or(0.0);
        (t0, i as f32 / self.m, crate::float::sqrt(x0), (x1 - x0) * self.m * 0.5)
    }

    /// The raw profile at `τ`: (u, u̇, ü).
    pub(crate) fn raw(&self, tau: f32) -> (f32, f32, f32) {
        self.raw_in(tau, self.interval(tau))
    }

    /// [`Profile::raw`] with `τ`'s interval `i` already found (used only when `τ` is inside).
    fn raw_in(&self, tau: f32, i: usize) -> (f32, f32, f32) {
        if tau.is_nan() || tau <= 0.0 || self.intervals() == 0 {
            return (0.0, 0.0, 0.0);
        }
        if tau >= self.end() {
            return (self.last_u(), 0.0, 0.0);
        }
        let (t0, u0, v0, a) = self.piece(i);
        let s = (tau - t0).max(0.0);
        let u1 = (i + 1) as f32 / self.m;
        let u = (u0 + s * (v0 + 0.5 * a * s)).max(u0).min(u1);
        (u, (v0 + a * s).max(0.0), a)
    }

    /// Over the raw profile, in one pass piece by piece: `∫_{lo}^{hi} (u(τ) − c) dτ` (no
    /// cancellation of large values: each piece integrates its own offset from `c`) and
    /// `u(hi) − u(lo)` (summed, because the difference of two nearby values of `u` (up to 150
    /// spans) would lose `f32` digits that `u̇_f = (u(τ) − u(τ−w))/w` amplifies by `1/w`).
    /// `first` and `last` are the intervals holding `max(lo, 0)` and `min(hi, end)`.
    fn window(&self, lo: f32, hi: f32, c: f32, first: usize, last_interval: usize) -> (f32, f32) {
        let (end, last) = (self.end(), self.last_u());
        let (mut integral, mut increment) = (0.0f32, 0.0f32);
        if lo < 0.0 {
            integral += -c * (hi.min(0.0) - lo);
        }
        if hi > end {
            integral += (last - c) * (hi - lo.max(end));
        }
        let (a, b) = (lo.max(0.0), hi.min(end));
        if b > a {
            for i in first..=last_interval {
                let (t0, u0, v0, acc) = self.piece(i);
                let t1 = self.t.get(i + 1).copied().unwrap_or(t0);
                let s0 = a.max(t0) - t0;
                let s1 = b.min(t1) - t0;
                if s1 > s0 {
                    let (q0, q1) = (s0 * s0, s1 * s1);
                    integral += (u0 - c) * (s1 - s0) + 0.5 * v0 * (q1 - q0) + acc / 6.0 * (q1 * s1 - q0 * s0);
                    increment += v0 * (s1 - s0) + 0.5 * acc * (s1 * s1 - s0 * s0);
                }
            }
        }
        (integral, increment)
    }

    /// The time law at `τ ∈ [0, duration]` (filtered when `w > 0`; jerk 0 without the filter).
    pub(crate) fn law(&self, tau: f32) -> Law {
        let tau = if tau > 0.0 { tau.min(self.duration()) } else { 0.0 };
        if self.w.is_nan() || self.w <= 0.0 {
            let (u, v, a) = self.raw(tau);
            return Law { u, v, a, j: 0.0 };
        }
        // Two interval searches serve both ends of the window and the sums between them.
        let (lo, end) = (tau - self.w, self.end());
        let (first, last) = (self.interval(lo.max(0.0)), self.interval(tau.min(end)));
        let (u, v, a) = self.raw_in(tau, last);
        let (ub, vb, ab) = self.raw_in(lo, first);
        let inv = 1.0 / self.w;
        let (integral, increment) = self.window(lo, tau, ub, first, last);
        let mean = ub + integral * inv;
        Law {
            // max/min, not clamp: clamp panics when its bounds cross (a NaN, or rounding).
            u: mean.max(ub).min(u),
            v: (increment * inv).max(0.0),
            a: (v - vb) * inv,
            j: (a - ab) * inv,
        }
    }

    /// Calls `f(τ₀, τ₁)` for each piece between consecutive breakpoints of the law (the grid
    /// times, and the same shifted by `w`), in order.
    pub(crate) fn for_each_piece(&self, mut f: impl FnMut(f32, f32)) {
        let n = self.intervals();
        let t = self.t.get(..=n).unwrap_or(&[]);
        let shifted = self.w > 0.0;
        let (mut i, mut k) = (0usize, 0usize);
        let mut prev: Option<f32> = None;
        loop {
            let a = t.get(i).copied();
            let b = if shifted { t.get(k).map(|x| x + self.w) } else { None };
            let next = match (a, b) {
                (Some(a), Some(b)) if a <= b => {
                    i += 1;
                    a
                }
                (Some(a), None) => {
                    i += 1;
                    a
                }
                (_, Some(b)) => {
                    k += 1;
                    b
                }
                (None, None) => break,
            };
            if let Some(p) = prev
                && next > p
            {
                f(p, next);
            }
            if prev.is_none_or(|p| next > p) {
                prev = Some(next);
            }
        }
    }
}
