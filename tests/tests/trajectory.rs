//! Time parameterization (`edmp_core::trajectory`) judged from the outside, in f64: on smooth
//! and jagged paths of the Panda, and on planned paths of the iiwa 7 and the xArm 6, sampled at
//! 1 kHz and 100 Hz, every reported velocity and acceleration and every finite difference
//! (velocity and acceleration from positions, acceleration from velocities, jerk from
//! accelerations) stays within the arm's limits (its `Robot` table's) times the scales; the
//! trajectory starts and ends at rest at the ends; positions stay on the curve; bad input is a
//! typed error; the same input gives the same bits.
//!
//! Timed plans for `benchmarks/check_timed.py` and `benchmarks/toppra_compare.py` come from
//! `edmp-host plan --timed`.

use edmp_core::Error;
use edmp_core::collision::checker::CheckConfig;
use edmp_core::guidance::guides::EDMP_GUIDES;
use edmp_core::path::HORIZON;
use edmp_core::planner::PlanConfig;
use edmp_core::prior::Network;
use edmp_core::rng::Rng;
use edmp_core::robot::kinematics::Joints;
use edmp_core::robot::{PANDA, Robot};
use edmp_core::scene::{Obstacle, Scene};
use edmp_core::trajectory::{
    DEFAULT_GRID, Limits, Shape, Timed, TimedPoint, check_curve, deviation_bound, parameterize, parameterize_checked,
};
use edmp_host::formats::json::parse_problem_for;
use edmp_host::formats::trajectory::{TimedRequest, trajectory_document};
use edmp_host::planning::plan_problem;
use proptest::prelude::*;

type Path = [Joints<f32>; HORIZON];
type Traj = Timed<DEFAULT_GRID, HORIZON>;

const READY: Joints<f32> = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

/// A smooth path: the ready pose plus a few random low-frequency sines per joint.
fn smooth(rng: &mut Rng, amplitude: f32) -> Path {
    let coef: [[(f32, f32, f32); 3]; 7] = core::array::from_fn(|_| {
        core::array::from_fn(|_| {
            (
                rng.uniform_f32(-amplitude, amplitude),
                rng.uniform_f32(0.3, 3.0),
                rng.uniform_f32(0.0, core::f32::consts::TAU),
            )
        })
    });
    core::array::from_fn(|k| {
        let s = k as f32 / (HORIZON - 1) as f32;
        core::array::from_fn(|j| {
            READY[j]
                + coef[j]
                    .iter()
                    .map(|(a, f, p)| a * ((f * s * 3.0 + p).sin() - p.sin()))
                    .sum::<f32>()
        })
    })
}

/// A jagged path: a random walk with steps up to `step`, some waypoints repeated.
fn jagged(rng: &mut Rng, step: f32) -> Path {
    let mut q = READY;
    core::array::from_fn(|_| {
        if rng.below(5) != 0 {
            for v in q.iter_mut() {
                *v += rng.uniform_f32(-step, step);
            }
        }
        q
    })
}

/// `robot`'s limits times the scales, in f64.
fn joint_limits<const J: usize>(robot: &Robot<f32, J>, limits: &Limits) -> [[f64; J]; 3] {
    let (v, a) = (f64::from(limits.velocity_scale), f64::from(limits.acceleration_scale));
    [
        robot.max_velocity.map(|x| f64::from(x) * v),
        robot.max_acceleration.map(|x| f64::from(x) * a),
        robot.max_jerk.map(|x| f64::from(x) * a),
    ]
}

/// Max-norm distance from `p` to the polyline `w`: per segment a convex function of the
/// segment parameter, minimised by ternary search.
fn distance_to_polyline<const J: usize>(p: &[f64; J], w: &[[f32; J]; HORIZON]) -> f64 {
    let mut best = f64::INFINITY;
    for s in w.windows(2) {
        let (a, b) = (s[0].map(f64::from), s[1].map(f64::from));
        let f = |t: f64| {
            (0..J)
                .map(|j| (p[j] - (a[j] + t * (b[j] - a[j]))).abs())
                .fold(0.0, f64::max)
        };
        // Cheap reject: the segment's box.
        let gap = (0..J)
            .map(|j| (a[j].min(b[j]) - p[j]).max(p[j] - a[j].max(b[j])).max(0.0))
            .fold(0.0, f64::max);
        if gap >= best {
            continue;
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..60 {
            let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
            if f(m1) <= f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        best = best.min(f(0.5 * (lo + hi)));
    }
    best
}

/// Worst ratios found by [`verify`] (1 = at a limit).
#[derive(Debug, Default)]
struct Worst {
    velocity: f64,
    acceleration: f64,
    jerk: f64,
    deviation: f64,
    /// Where the worst acceleration was found.
    acceleration_at: (f32, &'static str),
}

/// Samples `timed`, a trajectory of `robot`, at `rate` Hz (and at its end) and asserts every
/// limit of `robot`'s, in f64. Finite differences carry f32 rounding: `noise(n)` is the error of
/// an n-th difference of f32 values.
fn verify<const J: usize>(
    robot: &Robot<f32, J>,
    timed: &Timed<DEFAULT_GRID, HORIZON, J>,
    w: &[[f32; J]; HORIZON],
    limits: &Limits,
    rate: f64,
) -> Worst {
    let [vl, al, jl] = joint_limits(robot, limits);
    let d = f64::from(timed.duration());
    let dt = 1.0 / rate;
    let n = (d * rate).floor() as usize;
    let mut times: Vec<f32> = (0..=n).map(|k| (k as f64 * dt) as f32).collect();
    if f64::from(*times.last().unwrap()) < d {
        times.push(timed.duration());
    }
    let pts: Vec<_> = times.iter().map(|&t| timed.sample(t)).collect();
    let first = pts.first().unwrap();
    let last = pts.last().unwrap();
    assert_eq!(first.positions, w[0]);
    assert_eq!(last.positions, w[HORIZON - 1]);
    assert_eq!(first.velocities, [0.0; J]);
    assert_eq!(last.velocities, [0.0; J]);
    assert_eq!(last.accelerations, [0.0; J]);
    if limits.jerk_limited {
        assert_eq!(first.accelerations, [0.0; J]);
    }
    let tol = 1.0 + 1e-4;
    let eps = f64::from(f32::EPSILON);
    let ulp = |x: f64| x.abs().max(1.0) * eps;
    let mut worst = Worst::default();
    let tolerance = f64::from(timed.tolerance()) + 1e-6;
    for (k, p) in pts.iter().enumerate() {
        assert!(p.time.is_finite());
        if k > 0 {
            assert!(p.time > pts[k - 1].time, "times must increase");
        }
        let q = p.positions.map(f64::from);
        if k % 4 == 0 || rate < 500.0 {
            let dev = distance_to_polyline(&q, w);
            assert!(dev <= tolerance, "t {}: {dev} from the polyline > {tolerance}", p.time);
            worst.deviation = worst.deviation.max(dev);
        }
        for j in 0..J {
            let (v, a) = (f64::from(p.velocities[j]), f64::from(p.accelerations[j]));
            assert!(v.is_finite() && a.is_finite() && q[j].is_finite());
            worst.velocity = worst.velocity.max(v.abs() / vl[j]);
            if a.abs() / al[j] > worst.acceleration {
                worst.acceleration = a.abs() / al[j];
                worst.acceleration_at = (p.time, "reported");
            }
        }
    }
    // Rounding of one f32 position: its own ulp, the time's (times speed), the parameter's.
    let noise = |p: &TimedPoint<J>, j: usize| {
        ulp(f64::from(p.positions[j])) + 2.0 * f64::from(p.velocities[j]).abs() * ulp(f64::from(p.time)) + 1e-6
    };
    for k in 1..pts.len() {
        let (a, b) = (&pts[k - 1], &pts[k]);
        let h = f64::from(b.time) - f64::from(a.time);
        for j in 0..J {
            let (qa, qb) = (f64::from(a.positions[j]), f64::from(b.positions[j]));
            let (va, vb) = (f64::from(a.velocities[j]), f64::from(b.velocities[j]));
            let (aa, ab) = (f64::from(a.accelerations[j]), f64::from(b.accelerations[j]));
            // Mean values over the step never exceed the maxima.
            let fd_v = ((qb - qa).abs() - noise(a, j) - noise(b, j)) / h;
            worst.velocity = worst.velocity.max(fd_v / vl[j]);
            let fd_a = ((vb - va).abs() - 2.0 * ulp(va)) / h;
            if fd_a / al[j] > worst.acceleration {
                worst.acceleration = fd_a / al[j];
                worst.acceleration_at = (b.time, "from velocities");
            }
            if limits.jerk_limited {
                let fd_j = ((ab - aa).abs() - 2.0 * ulp(aa)) / h;
                worst.jerk = worst.jerk.max(fd_j / jl[j]);
            }
            if k + 1 < pts.len() {
                let c = &pts[k + 1];
                let hc = f64::from(c.time) - f64::from(b.time);
                if (hc - h).abs() < 1e-9 {
                    let qc = f64::from(c.positions[j]);
                    // Second differences of positions: an acceleration at some point between.
                    let fd2 = ((qc - 2.0 * qb + qa).abs() - noise(a, j) - 2.0 * noise(b, j) - noise(c, j)) / (h * h);
                    if fd2 / al[j] > worst.acceleration {
                        worst.acceleration = fd2 / al[j];
                        worst.acceleration_at = (b.time, "from positions");
                    }
                    if limits.jerk_limited {
                        // Reported velocity = central difference of positions, up to h²/6 · jerk.
                        let vc = (qc - qa) / (2.0 * h);
                        let slack = h * h / 6.0 * jl[j] + (noise(a, j) + noise(c, j)) / (2.0 * h) + 1e-6;
                        assert!((vc - vb).abs() <= slack, "t {}: velocity {vb} vs {vc}", b.time);
                        let ac = (f64::from(c.velocities[j]) - va) / (2.0 * h);
                        let slack = h * jl[j] + 2.0 * ulp(vb) / h + 1e-6;
                        assert!((ac - ab).abs() <= slack, "t {}: acceleration {ab} vs {ac}", b.time);
                    }
                }
            }
        }
    }
    assert!(worst.velocity <= tol, "velocity at {} of the limit", worst.velocity);
    assert!(
        worst.acceleration <= tol,
        "acceleration at {} of the limit ({:?}), duration {}",
        worst.acceleration,
        worst.acceleration_at,
        timed.duration()
    );
    assert!(worst.jerk <= tol, "jerk at {} of the limit", worst.jerk);
    worst
}

fn timed(w: &Path, shape: Shape, limits: &Limits) -> Box<Traj> {
    let mut t = Box::new(Traj::new());
    parameterize(&PANDA, w, shape, limits, &mut t).unwrap();
    t
}

#[test]
fn limits_hold_at_1khz_and_100hz_on_smooth_and_jagged_paths() {
    let mut rng = Rng::new(7);
    let scales = [
        Limits::DEFAULT,
        Limits {
            velocity_scale: 0.3,
            acceleration_scale: 0.2,
            jerk_limited: true,
        },
        Limits {
            jerk_limited: false,
            ..Limits::DEFAULT
        },
    ];
    for case in 0..6 {
        let w = if case % 2 == 0 {
            smooth(&mut rng, 0.6)
        } else {
            jagged(&mut rng, 0.08)
        };
        for limits in &scales {
            for shape in [Shape::Spline, Shape::Polyline] {
                let t = timed(&w, shape, limits);
                let fast = verify(&PANDA, &t, &w, limits, 1000.0);
                let slow = verify(&PANDA, &t, &w, limits, 100.0);
                println!(
                    "case {case} {shape:?} {limits:?}: {:.3} s (scale {:.4}, window {:.4}), worst v {:.3} a {:.3} j {:.3}, 100 Hz a {:.3}, deviation {:.2e} of {:.2e}",
                    t.duration(),
                    t.scale(),
                    t.window(),
                    fast.velocity,
                    fast.acceleration,
                    fast.jerk,
                    slow.acceleration,
                    fast.deviation,
                    t.tolerance()
                );
                // Time-optimal: some limit is nearly reached (not a uselessly slow trajectory).
                assert!(fast.velocity.max(fast.acceleration).max(fast.jerk) > 0.8, "{fast:?}");
            }
        }
    }
}

#[test]
fn the_polyline_is_the_linear_interpolation() {
    let mut rng = Rng::new(11);
    let w = jagged(&mut rng, 0.1);
    let t = timed(&w, Shape::Polyline, &Limits::DEFAULT);
    assert!(t.tolerance() <= 1e-5);
    for k in 0..=2000 {
        let p = t.sample(t.duration() * k as f32 / 2000.0);
        assert!(distance_to_polyline(&p.positions.map(f64::from), &w) <= 1e-5);
    }
    // It stops at every waypoint: some sample lands there at rest.
    assert!(t.duration() > timed(&w, Shape::Spline, &Limits::DEFAULT).duration());
}

#[test]
fn the_spline_stays_within_its_stated_tolerance() {
    let mut rng = Rng::new(3);
    let w = jagged(&mut rng, 0.1);
    let t = timed(&w, Shape::Spline, &Limits::DEFAULT);
    assert_eq!(t.tolerance(), deviation_bound(&w, Shape::Spline));
    let mut worst = 0.0f64;
    for k in 0..=4000 {
        let p = t.sample(t.duration() * k as f32 / 4000.0);
        worst = worst.max(distance_to_polyline(&p.positions.map(f64::from), &w));
    }
    assert!(worst <= f64::from(t.tolerance()), "{worst} > {}", t.tolerance());
    assert!(
        worst > 0.2 * f64::from(t.tolerance()),
        "tolerance {} is loose: {worst}",
        t.tolerance()
    );
}

#[test]
fn jerk_limiting_costs_little_time_and_toppra_alone_is_faster() {
    let mut rng = Rng::new(5);
    for _ in 0..4 {
        let w = smooth(&mut rng, 0.6);
        let free = timed(
            &w,
            Shape::Spline,
            &Limits {
                jerk_limited: false,
                ..Limits::DEFAULT
            },
        );
        let jerk = timed(&w, Shape::Spline, &Limits::DEFAULT);
        println!("without jerk {:.4} s, with {:.4} s", free.duration(), jerk.duration());
        assert!(jerk.duration() >= free.duration());
        assert!(jerk.duration() < 1.25 * free.duration());
    }
}

#[test]
fn bad_input_is_a_typed_error_and_leaves_an_empty_trajectory() {
    let mut rng = Rng::new(1);
    let good = smooth(&mut rng, 0.5);
    let mut t = Box::new(Traj::new());
    for (joint, bad) in [(2usize, f32::NAN), (4, f32::INFINITY), (0, f32::NEG_INFINITY)] {
        let mut w = good;
        w[17][joint] = bad;
        assert_eq!(
            parameterize(&PANDA, &w, Shape::Spline, &Limits::DEFAULT, &mut t),
            Err(Error::NonFiniteJoint { joint: joint as u8 })
        );
        assert_eq!(t.duration(), 0.0);
        assert!(t.sample(0.5).positions.iter().all(|x| x.is_finite()));
    }
    let mut w = good;
    w[3][6] = 1e6;
    assert_eq!(
        parameterize(&PANDA, &w, Shape::Spline, &Limits::DEFAULT, &mut t),
        Err(Error::OutOfRange { joint: 6 })
    );
    for s in [0.0, -1.0, 1.5, f32::NAN, f32::INFINITY] {
        let l = Limits {
            velocity_scale: s,
            ..Limits::DEFAULT
        };
        assert_eq!(
            parameterize(&PANDA, &good, Shape::Spline, &l, &mut t),
            Err(Error::BadScale)
        );
        let l = Limits {
            acceleration_scale: s,
            ..Limits::DEFAULT
        };
        assert_eq!(
            parameterize(&PANDA, &good, Shape::Polyline, &l, &mut t),
            Err(Error::BadScale)
        );
    }
    let mut small = Box::new(Timed::<100, HORIZON>::new());
    assert_eq!(
        parameterize(&PANDA, &good, Shape::Polyline, &Limits::DEFAULT, &mut small),
        Err(Error::GridTooSmall)
    );
    // A smaller grid still works when it holds a point per span.
    parameterize(&PANDA, &good, Shape::Spline, &Limits::DEFAULT, &mut small).unwrap();
    assert_eq!(small.grid_points(), 52);
    // A scale so small that the trajectory would last for days.
    let l = Limits {
        velocity_scale: 1e-6,
        acceleration_scale: 1e-6,
        jerk_limited: true,
    };
    assert_eq!(
        parameterize(&PANDA, &good, Shape::Spline, &l, &mut t),
        Err(Error::Overflow)
    );
    // Huge but accepted values stay finite.
    let far: Path = core::array::from_fn(|k| [-99.0 + 198.0 * k as f32 / 49.0; 7]);
    parameterize(&PANDA, &far, Shape::Polyline, &Limits::DEFAULT, &mut t).unwrap();
    assert!(t.duration().is_finite() && t.duration() > 0.0);
    for k in 0..=100 {
        let p = t.sample(t.duration() * k as f32 / 100.0);
        assert!(
            p.positions
                .iter()
                .chain(&p.velocities)
                .chain(&p.accelerations)
                .all(|x| x.is_finite())
        );
    }
}

#[test]
fn still_and_nearly_still_paths_are_rest_trajectories() {
    let mut t = Box::new(Traj::new());
    let still: Path = [READY; HORIZON];
    for shape in [Shape::Spline, Shape::Polyline] {
        parameterize(&PANDA, &still, shape, &Limits::DEFAULT, &mut t).unwrap();
        assert_eq!(t.duration(), 0.0);
        for time in [0.0, 1.0, -1.0, f32::NAN, f32::INFINITY] {
            let p = t.sample(time);
            assert_eq!(
                (p.positions, p.velocities, p.accelerations),
                (READY, [0.0; 7], [0.0; 7])
            );
        }
    }
    let mut nearly = still;
    nearly[25][3] += 1e-6;
    for limits in [
        Limits::DEFAULT,
        Limits {
            jerk_limited: false,
            ..Limits::DEFAULT
        },
    ] {
        for shape in [Shape::Spline, Shape::Polyline] {
            parameterize(&PANDA, &nearly, shape, &limits, &mut t).unwrap();
            assert!(t.duration() > 0.0 && t.duration() < 0.5, "{}", t.duration());
            verify(&PANDA, &t, &nearly, &limits, 1000.0);
        }
    }
}

#[test]
fn the_same_input_gives_the_same_bits() {
    let mut rng = Rng::new(9);
    let w = smooth(&mut rng, 0.7);
    let a = timed(&w, Shape::Spline, &Limits::DEFAULT);
    let b = timed(&w, Shape::Spline, &Limits::DEFAULT);
    assert_eq!(a.fingerprint(), b.fingerprint());
    assert_eq!(
        a.sample(0.37).positions.map(f32::to_bits),
        b.sample(0.37).positions.map(f32::to_bits)
    );
    let c = timed(&w, Shape::Polyline, &Limits::DEFAULT);
    assert_ne!(a.fingerprint(), c.fingerprint());
    let mut w2 = w;
    w2[10][0] += 1e-6;
    assert_ne!(
        a.fingerprint(),
        timed(&w2, Shape::Spline, &Limits::DEFAULT).fingerprint()
    );
}

fn ball_scene(center: [f32; 3], radius: f32) -> Scene<'static, 4> {
    let mut scene = Scene::<4>::new();
    scene.push(Obstacle::sphere(center, radius).unwrap()).unwrap();
    scene
}

#[test]
fn the_curve_is_checked_densely_and_a_touching_spline_falls_back_to_the_polyline() {
    let mut rng = Rng::new(2);
    let w = smooth(&mut rng, 0.4);
    let cfg = CheckConfig::DEFAULT;
    let far = ball_scene([3.0, 3.0, 3.0], 0.1);
    let r = check_curve(&PANDA, &far, &w, Shape::Spline, &cfg).unwrap();
    assert!(r.free);
    // At least one state per 0.01 rad of the widest joint's travel along the curve.
    let travel: f32 = w
        .windows(2)
        .map(|s| (0..7).map(|j| (s[1][j] - s[0][j]).abs()).fold(0.0, f32::max))
        .sum();
    assert!(
        r.states as f32 >= 0.9 * travel / 0.01,
        "{} states for {travel} rad",
        r.states
    );
    let mut t = Box::new(Traj::new());
    assert_eq!(
        parameterize_checked(&PANDA, &far, &w, &Limits::DEFAULT, &cfg, &mut t),
        Ok(Shape::Spline)
    );
    assert_eq!(t.shape(), Shape::Spline);
    // A ball around the whole arm: the spline touches it, the polyline is used.
    let wall = ball_scene([0.3, 0.0, 0.5], 0.3);
    assert!(!check_curve(&PANDA, &wall, &w, Shape::Spline, &cfg).unwrap().free);
    assert_eq!(
        parameterize_checked(&PANDA, &wall, &w, &Limits::DEFAULT, &cfg, &mut t),
        Ok(Shape::Polyline)
    );
    assert_eq!(t.shape(), Shape::Polyline);
    let mut bad = w;
    bad[5][1] = f32::NAN;
    assert_eq!(
        check_curve(&PANDA, &far, &bad, Shape::Spline, &cfg),
        Err(Error::NonFiniteJoint { joint: 1 })
    );
}

/// Plans `scene` (a benchmark problem of `robot`'s) with the shipped configuration and checks
/// its timed path against `robot`'s own limits: the core's trajectory at 1 kHz and 100 Hz, full
/// and scaled, and the host's `trajectory` document (its joint names and every written point).
fn a_planned_path_keeps_the_arms_limits<const J: usize>(
    robot: &'static Robot<f32, J>,
    network: Option<&'static Network<J>>,
    scene: &str,
) {
    let network = network.expect("the arm's prior is compiled in");
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(scene);
    let text = std::fs::read_to_string(&file).unwrap();
    let problem = parse_problem_for(&text, file.parent().unwrap(), robot).unwrap();
    let config = PlanConfig::DEFAULT;
    let planned = plan_problem(network, &problem, &EDMP_GUIDES, &config, 0).unwrap();
    assert!(planned.plan.is_free(), "{scene}: the plan collides");
    let w = planned.plan.paths[planned.plan.best];
    let scene_ = problem.scene();
    let scaled = Limits {
        velocity_scale: 0.5,
        acceleration_scale: 0.3,
        jerk_limited: true,
    };
    for limits in [Limits::DEFAULT, scaled] {
        let mut t = Box::new(Timed::<DEFAULT_GRID, HORIZON, J>::new());
        let shape = parameterize_checked(robot, &scene_, &w, &limits, &config.check, &mut t).unwrap();
        assert_eq!(t.shape(), shape);
        let fast = verify(robot, &t, &w, &limits, 1000.0);
        let slow = verify(robot, &t, &w, &limits, 100.0);
        println!(
            "{} {scene} {shape:?} {limits:?}: {:.3} s (scale {:.4}, window {:.4}), worst v {:.3} a {:.3} j {:.3}, 100 Hz a {:.3}",
            robot.name,
            t.duration(),
            t.scale(),
            t.window(),
            fast.velocity,
            fast.acceleration,
            fast.jerk,
            slow.acceleration
        );
        // Time-optimal: some limit of this arm's is nearly reached.
        assert!(fast.velocity.max(fast.acceleration).max(fast.jerk) > 0.8, "{fast:?}");
    }
    let request = TimedRequest::new(100.0, 1.0, 1.0).unwrap();
    let doc = trajectory_document(robot, &scene_, &w, &config.check, &request).unwrap();
    let names: Vec<&str> = doc["joint_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(names, robot.joint_names);
    let [vl, al, _] = joint_limits(robot, &Limits::DEFAULT);
    let points = doc["points"].as_array().unwrap();
    assert!(points.len() > 10);
    for p in points {
        for (field, limit) in [("velocities", &vl), ("accelerations", &al)] {
            let values = p[field].as_array().unwrap();
            assert_eq!(values.len(), J);
            for (j, v) in values.iter().enumerate() {
                let v = v.as_f64().unwrap();
                assert!(v.abs() <= limit[j] * (1.0 + 1e-4), "{field}[{j}] = {v} > {}", limit[j]);
            }
        }
    }
}

#[test]
fn a_planned_path_of_the_iiwa7_keeps_its_limits() {
    a_planned_path_keeps_the_arms_limits(
        &edmp_core::robot::arms::iiwa7::ROBOT,
        edmp_core::prior::arms::iiwa7::NETWORK,
        "benchmarks/iiwa7/problems/tabletop/000.json",
    );
}

#[test]
fn a_planned_path_of_the_xarm6_keeps_its_limits() {
    let robot = &edmp_core::robot::arms::xarm6::ROBOT;
    assert_eq!(robot.joint_names.len(), 6);
    a_planned_path_keeps_the_arms_limits(
        robot,
        edmp_core::prior::arms::xarm6::NETWORK,
        "benchmarks/xarm6/problems/tabletop/000.json",
    );
}

/// A path and limits for the property test.
fn case() -> impl Strategy<Value = (Path, Limits, Shape)> {
    (
        any::<u64>(),
        any::<bool>(),
        0.05f32..=1.0,
        0.05f32..=1.0,
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(seed, jag, vs, as_, jerk, poly)| {
            let mut rng = Rng::new(seed);
            let w = if jag {
                jagged(&mut rng, 0.12)
            } else {
                smooth(&mut rng, 0.8)
            };
            let limits = Limits {
                velocity_scale: vs,
                acceleration_scale: as_,
                jerk_limited: jerk,
            };
            (w, limits, if poly { Shape::Polyline } else { Shape::Spline })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn limits_hold_on_random_paths_and_scales((w, limits, shape) in case()) {
        let t = timed(&w, shape, &limits);
        verify(&PANDA, &t, &w, &limits, 250.0);
    }
}
