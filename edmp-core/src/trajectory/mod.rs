//! Time parameterization: a planned path becomes a time-stamped trajectory inside the arm's
//! velocity, acceleration and jerk limits ([`Robot::max_velocity`],
//! [`Robot::max_acceleration`], [`Robot::max_jerk`], frozen with its tables), starting and
//! ending at rest. Any arm: the functions take its [`Robot`] table and are generic over its
//! number of joints `J`.
//!
//! 1. **Shape** ([`spline`]): the waypoints as control points of a uniform cubic B-spline (C²,
//!    within [`deviation_bound`] of the polyline), or the exact polyline.
//! 2. **Check** ([`check_curve`]): the exact checker along the curve; [`parameterize_checked`]
//!    falls back to the polyline (what the planner checked) when the spline touches anything.
//! 3. **Time-optimal profile** ([`topp`]): TOPP-RA-style reachability on a grid over the
//!    parameter, velocity and acceleration limits.
//! 4. **Jerk** (`profile.rs`): a moving average of the profile over a window `w` bounds its
//!    jerk; a final uniform time scaling `k ≥ 1`, measured on samples of every piece and
//!    verified on other samples (with an analytic bound as the guaranteed last resort), makes
//!    every limit hold.
//!
//! The result, [`Timed`], answers [`Timed::sample`] at any time: a controller pulls setpoints at
//! its own rate and nothing is buffered. Everything is `f32`, fixed memory, deterministic.
//!
//! ```
//! use edmp_core::robot::PANDA;
//! use edmp_core::trajectory::{Limits, Shape, Timed, parameterize};
//! let waypoints: [[f32; 7]; 50] = core::array::from_fn(|k| {
//!     let s = k as f32 / 49.0;
//!     [s, -0.785, 0.5 * s, -2.356, 0.0, 1.571, 0.785]
//! });
//! let mut timed = Timed::<{ edmp_core::trajectory::DEFAULT_GRID }, 50, 7>::new();
//! parameterize(&PANDA, &waypoints, Shape::Spline, &Limits::DEFAULT, &mut timed).unwrap();
//! let end = timed.sample(timed.duration());
//! assert_eq!(end.positions, waypoints[49]);
//! assert_eq!(end.velocities, [0.0; 7]);
//! ```

pub mod check;
pub mod limits;
pub(crate) mod profile;
pub mod spline;
pub mod topp;

pub use check::{CurveReport, check_curve};
pub use limits::{JointLimits, Limits};
pub use spline::{Curve, Shape, deviation_bound};

use crate::collision::checker::CheckConfig;
use crate::error::Error;
use crate::path::HORIZON;
use crate::robot::{JOINTS, Robot};
use crate::scene::Scene;
use profile::{Law, Profile};

/// Most grid points per span: 8 gave durations 4 % shorter (0.1 s on a 2.8 s plan) for 2.8x the
/// work (3.7 against 1.3 ms per plan, `cargo bench -p edmp-core --bench trajectory`).
pub const MAX_GRID_PER_SPAN: usize = 4;
/// Grid capacity that gives a 50-waypoint path [`MAX_GRID_PER_SPAN`] points per span in either
/// shape (the polyline's `3·50 − 3 = 147` spans, plus the last point).
pub const DEFAULT_GRID: usize = MAX_GRID_PER_SPAN * (3 * HORIZON - 3) + 1;
/// Moving-average window in units of the arm's largest `a_j / j_j` (whatever the scale: 2 ms
/// for the Panda's datasheet, longer for an arm whose jerk limit is lower): the filter's own
/// jerk, about `|q'| · 2 max|ü| / w`, then stays well inside the limit.
pub const WINDOW_FACTOR: f32 = 4.0;
/// Relative margin added to every measured time scale.
pub const SAFETY: f32 = 0.01;
/// Measure-and-verify rounds before the analytic bound decides the time scale.
pub const RETRIES: usize = 3;
/// Longest trajectory (s): anything slower is [`Error::Overflow`].
pub const MAX_DURATION: f32 = 3600.0;

/// One setpoint of a trajectory of an arm with `J` joints (the Panda's 7 unless named, as
/// `Plan`'s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedPoint<const J: usize = JOINTS> {
    /// Seconds from the start.
    pub time: f32,
    /// rad.
    pub positions: [f32; J],
    /// rad/s.
    pub velocities: [f32; J],
    /// rad/s².
    pub accelerations: [f32; J],
}

/// A time-parameterized path of `H` waypoints of an arm with `J` joints (the Panda's 7 unless
/// named), in fixed memory: the waypoints, the TOPP grid (`u̇²` and the time at each of up to
/// `N` grid points), the filter window and the time scale. It keeps no arm: the limits were
/// applied when it was timed, and sampling needs only the curve and the law.
///
/// Memory: `8 N + 4 J H` bytes plus a few scalars ([`Timed::BYTES`]; about 11 KB for the
/// defaults), so a firmware keeps it in a `static` (`const fn new`). Until a successful
/// [`parameterize`] (and after a failed one) it is the empty trajectory: duration 0, at rest at
/// zero.
#[derive(Clone, Debug)]
pub struct Timed<const N: usize = DEFAULT_GRID, const H: usize = HORIZON, const J: usize = JOINTS> {
    waypoints: [[f32; J]; H],
    shape: Shape,
    limits: Limits,
    per_span: usize,
    points: usize,
    x: [f32; N],
    t: [f32; N],
    window: f32,
    scale: f32,
    duration: f32,
    tolerance: f32,
}

impl<const N: usize, const H: usize, const J: usize> Default for Timed<N, H, J> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const H: usize, const J: usize> Timed<N, H, J> {
    /// Bytes this type occupies.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// The empty trajectory.
    pub const fn new() -> Self {
        Self {
            waypoints: [[0.0; J]; H],
            shape: Shape::Spline,
            limits: Limits::DEFAULT,
            per_span: 0,
            points: 0,
            x: [0.0; N],
            t: [0.0; N],
            window: 0.0,
            scale: 1.0,
            duration: 0.0,
            tolerance: 0.0,
        }
    }

    fn clear(&mut self) {
        self.waypoints = [[0.0; J]; H];
        self.per_span = 0;
        self.points = 0;
        self.window = 0.0;
        self.scale = 1.0;
        self.duration = 0.0;
        self.tolerance = 0.0;
    }

    /// Total time (s).
    pub fn duration(&self) -> f32 {
        self.duration
    }

    /// The curve followed.
    pub fn shape(&self) -> Shape {
        self.shape
    }

    /// The limits it was timed under.
    pub fn limits(&self) -> Limits {
        self.limits
    }

    /// Largest max-norm distance (rad) of any position from the waypoints' polyline.
    pub fn tolerance(&self) -> f32 {
        self.tolerance
    }

    /// The final uniform time scale `k ≥ 1` (1: the filtered TOPP profile as it was).
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// The moving-average window (s, before scaling; 0 without jerk limiting).
    pub fn window(&self) -> f32 {
        self.window
    }

    /// Grid points used (0 for a trajectory at rest).
    pub fn grid_points(&self) -> usize {
        self.points
    }

    /// The waypoints it follows.
    pub fn waypoints(&self) -> &[[f32; J]; H] {
        &self.waypoints
    }

    fn profile(&self) -> Profile<'_> {
        let n = self.points.min(N);
        Profile {
            x: self.x.get(..n).unwrap_or(&[]),
            t: self.t.get(..n).unwrap_or(&[]),
            m: self.per_span.max(1) as f32,
            w: self.window,
        }
    }

    /// The setpoint at `time` (clamped into `[0, duration]`; NaN reads as 0).
    pub fn sample(&self, time: f32) -> TimedPoint<J> {
        let time = if time > 0.0 { time.min(self.duration) } else { 0.0 };
        let k = self.scale;
        let law = self.profile().law(time / k);
        let p = Curve::new(&self.waypoints, self.shape).eval(law.u);
        let (v, a) = (law.v / k, law.a / (k * k));
        let mut out = TimedPoint {
            time,
            positions: p.q,
            velocities: [0.0; J],
            accelerations: [0.0; J],
        };
        for (j, (d1, d2)) in p.d1.iter().zip(&p.d2).enumerate() {
            if let (Some(vel), Some(acc)) = (out.velocities.get_mut(j), out.accelerations.get_mut(j)) {
                *vel = d1 * v;
                *acc = d1 * a + d2 * v * v;
            }
        }
        out
    }

    /// FNV-1a over every bit that decides the trajectory, like `Plan::fingerprint`: equal
    /// fingerprints on firmware and host mean the same trajectory, bit for bit.
    pub fn fingerprint(&self) -> u64 {
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |word: u32| {
            for byte in word.to_le_bytes() {
                hash = (hash ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for v in self.waypoints.iter().flatten() {
            eat(v.to_bits());
        }
        eat(self.shape as u32);
        eat(self.per_span as u32);
        eat(self.points as u32);
        let p = self.profile();
        for v in p.x.iter().chain(p.t) {
            eat(v.to_bits());
        }
        for v in [self.window, self.scale, self.duration, self.tolerance] {
            eat(v.to_bits());
        }
        hash
    }
}

/// Times the curve of `shape` through `waypoints` of `robot` into `out` under `limits`: TOPP
/// under the arm's velocity and acceleration limits, scaled; with `limits.jerk_limited`, the
/// moving average and the time scale that bound the jerk (jerk limit = the arm's ×
/// `acceleration_scale`).
///
/// Errors: [`Error::BadScale`], [`Error::NonFiniteJoint`] / [`Error::OutOfRange`] for a bad
/// waypoint, [`Error::BadParameter`] for `H = 0`, [`Error::GridTooSmall`] when `N` cannot hold a
/// point per span, [`Error::Overflow`] when the trajectory would last over [`MAX_DURATION`]. On
/// error `out` is left empty. Waypoints that are all equal give a trajectory at rest, of
/// duration 0.
pub fn parameterize<const N: usize, const H: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    waypoints: &[[f32; J]; H],
    shape: Shape,
    limits: &Limits,
    out: &mut Timed<N, H, J>,
) -> Result<(), Error> {
    out.clear();
    let result = fill(robot, waypoints, shape, limits, out);
    if result.is_err() {
        out.clear();
    }
    result
}

/// Checks the spline with [`check_curve`] (the arm `robot` in `scene`) and times it when free;
/// otherwise times the exact polyline, which the planner's own check covered (it is not
/// re-checked here). Returns the shape used.
pub fn parameterize_checked<const N: usize, const H: usize, const J: usize, const M: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<M>,
    waypoints: &[[f32; J]; H],
    limits: &Limits,
    check: &CheckConfig,
    out: &mut Timed<N, H, J>,
) -> Result<Shape, Error> {
    out.clear();
    limits.joint_limits(robot)?;
    let shape = if check_curve(robot, scene, waypoints, Shape::Spline, check)?.free {
        Shape::Spline
    } else {
        Shape::Polyline
    };
    parameterize(robot, waypoints, shape, limits, out)?;
    Ok(shape)
}

fn fill<const N: usize, const H: usize, const J: usize>(
    robot: &Robot<f32, J>,
    waypoints: &[[f32; J]; H],
    shape: Shape,
    limits: &Limits,
    out: &mut Timed<N, H, J>,
) -> Result<(), Error> {
    let joint = limits.joint_limits(robot)?;
    spline::validate_waypoints(waypoints)?;
    let Some(first) = waypoints.first() else {
        return Err(Error::BadParameter);
    };
    out.waypoints = *waypoints;
    out.shape = shape;
    out.limits = *limits;
    out.tolerance = deviation_bound(waypoints, shape);
    if waypoints.iter().all(|w| w == first) {
        return Ok(());
    }
    let curve = Curve::new(waypoints, shape);
    let spans = curve.spans();
    let m = (N.saturating_sub(1) / spans).min(MAX_GRID_PER_SPAN);
    if m == 0 {
        return Err(Error::GridTooSmall);
    }
    let k = m * spans;
    out.per_span = m;
    topp::backward(&curve, m, k, &joint, limits.jerk_limited, &mut out.x, &mut out.t);
    topp::forward(&curve, m, k, &joint, limits.jerk_limited, &mut out.x, &out.t);
    // Times of the grid points: each interval at constant ü takes 2Δu / (u̇_i + u̇_{i+1}).
    let du2 = 2.0 / m as f32;
    let mut time = 0.0f32;
    let mut prev = 0.0f32;
    for (i, (x, t)) in out.x.iter().zip(out.t.iter_mut()).take(k + 1).enumerate() {
        let speed = crate::float::sqrt(*x);
        if i > 0 {
            time += du2 / (prev + speed);
        }
        *t = time;
        prev = speed;
    }
    if time.is_nan() || time > MAX_DURATION {
        return Err(Error::Overflow);
    }
    out.points = k + 1;
    out.window = if limits.jerk_limited {
        let ratio = joint
            .acceleration
            .iter()
            .zip(&joint.jerk)
            .fold(0.0f32, |r, (a, j)| r.max(a / j));
        WINDOW_FACTOR * ratio
    } else {
        0.0
    };
    let scale = time_scale(&curve, &out.profile(), &joint, limits.jerk_limited);
    let duration = scale * out.profile().duration();
    if duration.is_nan() || duration > MAX_DURATION {
        return Err(Error::Overflow);
    }
    out.scale = scale;
    out.duration = duration;
    Ok(())
}

/// Largest ratio of demand to limit at `τ` (velocity as is, acceleration under a square root,
/// jerk under a cube root: each is what a time scale divides out).
fn demand<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    law: Law,
    limits: &JointLimits<J>,
    jerk: bool,
) -> f32 {
    let p = curve.eval(law.u);
    let (mut rv, mut ra, mut rj) = (0.0f32, 0.0f32, 0.0f32);
    for j in 0..J {
        let g = |x: &[f32; J]| x.get(j).copied().unwrap_or(0.0);
        let (d1, d2, d3) = (g(&p.d1), g(&p.d2), g(&p.d3));
        let (vl, al, jl) = (g(&limits.velocity), g(&limits.acceleration), g(&limits.jerk));
        rv = rv.max((d1 * law.v).abs() / vl);
        ra = ra.max((d1 * law.a + d2 * law.v * law.v).abs() / al);
        if jerk {
            let v = law.v;
            rj = rj.max((d3 * v * v * v + 3.0 * d2 * v * law.a + d1 * law.j).abs() / jl);
        }
    }
    rv.max(crate::float::sqrt(ra)).max(libm::cbrtf(rj))
}

/// Largest [`demand`] at the given fractions of every piece of the law.
fn sampled_demand<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    profile: &Profile<'_>,
    limits: &JointLimits<J>,
    jerk: bool,
    fractions: &[f32],
) -> f32 {
    let mut worst = 0.0f32;
    profile.for_each_piece(|a, b| {
        for f in fractions {
            worst = worst.max(demand(curve, profile.law(a + f * (b - a)), limits, jerk));
        }
    });
    worst
}

/// The uniform time scale: measured at the start and middle of every piece, verified at its
/// quarters, at most [`RETRIES`] rounds, never above the analytic bound [`safe_scale`].
fn time_scale<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    profile: &Profile<'_>,
    limits: &JointLimits<J>,
    jerk: bool,
) -> f32 {
    let safe = safe_scale(curve, profile, limits, jerk);
    let mut k = (sampled_demand(curve, profile, limits, jerk, &[0.0, 0.5]) * (1.0 + SAFETY)).max(1.0);
    for _ in 0..RETRIES {
        if k >= safe {
            return safe;
        }
        let check = sampled_demand(curve, profile, limits, jerk, &[0.25, 0.75]);
        if check <= k {
            return k;
        }
        k = check * (1.0 + SAFETY);
    }
    safe
}

/// A time scale that provably satisfies every limit: per joint, `|q̇| ≤ Q₁U₁`,
/// `|q̈| ≤ Q₁U₂ + Q₂U₁²`, `|q⃛| ≤ Q₃U₁³ + 3Q₂U₁U₂ + Q₁U₃`, with `Qₙ` the curve's derivative bounds
/// and `U₁ = max u̇`, `U₂ = max |ü|`, `U₃ = 2U₂/w` the law's (the filter only averages `u̇` and
/// `ü`). Slow (the maxima rarely meet), hence only the last resort.
fn safe_scale<const H: usize, const J: usize>(
    curve: &Curve<'_, H, J>,
    profile: &Profile<'_>,
    limits: &JointLimits<J>,
    jerk: bool,
) -> f32 {
    let [q1, q2, q3] = curve.derivative_bounds();
    let x_max = profile.x.iter().fold(0.0f32, |m, x| m.max(*x));
    let u1 = crate::float::sqrt(x_max);
    let u2 = profile.x.windows(2).fold(0.0f32, |m, w| {
        m.max((w.last().copied().unwrap_or(0.0) - w.first().copied().unwrap_or(0.0)).abs())
    }) * profile.m
        * 0.5;
    let u3 = if profile.w > 0.0 { 2.0 * u2 / profile.w } else { 0.0 };
    let (mut rv, mut ra, mut rj) = (0.0f32, 0.0f32, 0.0f32);
    for j in 0..J {
        let g = |x: &[f32; J]| x.get(j).copied().unwrap_or(0.0);
        rv = rv.max(g(&q1) * u1 / g(&limits.velocity));
        ra = ra.max((g(&q1) * u2 + g(&q2) * u1 * u1) / g(&limits.acceleration));
        if jerk {
            rj = rj.max((g(&q3) * u1 * u1 * u1 + 3.0 * g(&q2) * u1 * u2 + g(&q1) * u3) / g(&limits.jerk));
        }
    }
    rv.max(crate::float::sqrt(ra)).max(libm::cbrtf(rj)).max(1.0) * (1.0 + 1e-3)
}
