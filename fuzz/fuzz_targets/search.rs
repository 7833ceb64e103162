//! `search::search` (RRT-Connect) with an arbitrary config and ends, over an analytic oracle
//! (up to 3 boxes in joint space, edges sampled at 0.05 rad, optionally failing with an injected
//! error after some calls) or, for one input in eight, the exact checker (`check_segment`).
//! A found path must be finite, run from exactly the start to exactly the goal and pass the
//! oracle on every segment, within the documented oracle-call bound; errors must be typed and
//! match the input (non-finite ends, a bad config, the oracle's own error).
#![no_main]

#[path = "common.rs"]
mod common;

use common::{Reader, finite, scene};
use edmp_core::robot::PANDA;
use edmp_core::Error;
use edmp_core::collision::checker::{CheckConfig, check_segment};
use edmp_core::robot::kinematics::Joints;
use edmp_core::path::HORIZON;
use edmp_core::rng::Rng;
use edmp_core::planner::search::{SearchConfig, SearchSpace, search};
use libfuzzer_sys::fuzz_target;

const CAP: usize = 128;

/// Joint-space boxes (centre, half width per joint): the segment is blocked if a sample is inside.
fn analytic_free(boxes: &[([f32; 7], f32)], a: &Joints<f32>, b: &Joints<f32>) -> bool {
    let widest = a.iter().zip(b).map(|(x, y)| (y - x).abs()).fold(0.0f32, f32::max);
    let steps = ((widest / 0.05).ceil() as usize).clamp(1, 64);
    (0..=steps).all(|k| {
        let t = k as f32 / steps as f32;
        let q: Joints<f32> = core::array::from_fn(|j| a[j] + (b[j] - a[j]) * t);
        !boxes.iter().any(|(c, h)| q.iter().zip(c).all(|(x, c)| (x - c).abs() <= *h))
    })
}

fuzz_target!(|data: &[u8]| {
    let mut r = Reader(data);
    let flags = r.byte();
    let use_checker = flags & 7 == 0;
    let boxes: Vec<([f32; 7], f32)> = (0..r.byte() % 4)
        .map(|_| (r.array::<7>().map(|v| v / 2.0), f32::from(r.byte() % 100) / 100.0))
        .collect();
    let scene = scene::<2>(&mut r);
    let (start, goal) = (r.array::<7>(), r.array::<7>());
    let config = SearchConfig {
        max_iterations: if use_checker { u32::from(r.byte() % 16) } else { u32::from(r.byte()) * 4 },
        step: if flags & 8 == 0 { f32::from(r.byte() % 60 + 1) / 100.0 } else { r.raw() },
        shortcuts: u32::from(r.byte() % 64),
        max_nodes: u16::from(r.byte()),
        lazy: flags & 32 == 0,
    };
    let fail_after = if flags & 16 == 0 { u32::MAX } else { u32::from(r.byte()) };
    let mut rng = Rng::new(u64::from(r.byte()));
    let mut space = Box::new(SearchSpace::<CAP>::new());
    let (mut calls, mut injected) = (0u32, false);
    let check = CheckConfig::default();
    let mut oracle = |a: &Joints<f32>, b: &Joints<f32>| -> Result<bool, Error> {
        calls += 1;
        if calls > fail_after {
            injected = true;
            return Err(Error::Overflow);
        }
        if use_checker {
            check_segment(&edmp_core::robot::PANDA, &scene, a, b, [&start, &goal], &check)
        } else {
            Ok(analytic_free(&boxes, a, b))
        }
    };
    let result = search(&PANDA, &start, &goal, &config, &mut space, &mut rng, &mut oracle);
    let within_limits = |q: &[f32; 7]| edmp_core::robot::PANDA.within_soft_limits(q, 1e-5);
    let bound = config.max_oracle_calls(CAP);
    assert!(u64::from(calls) <= bound, "{calls} oracle calls, bound {bound}");
    let ends_finite = finite(&start) && finite(&goal);
    let config_ok = config.step.is_finite() && config.step > 0.0 && config.max_nodes > 0;
    match result {
        Ok(Some(o)) => {
            assert!(ends_finite && config_ok && !injected);
            // Ends outside the limits are refused now (the finding
            // fuzz/artifacts-kept/search/nan-path-huge-start gave NaN waypoints).
            assert!(within_limits(&start) && within_limits(&goal));
            assert!(o.path.iter().all(|q| finite(q)), "{:?}", o.path);
            assert_eq!(o.path[0], start);
            assert_eq!(o.path[HORIZON - 1], goal);
            assert_eq!(o.oracle_calls, calls);
            assert!(o.iterations <= config.max_iterations && o.corners >= 2);
            assert!(o.nodes <= 2 * config.tree_capacity(CAP));
            if !use_checker {
                for w in o.path.windows(2) {
                    assert!(analytic_free(&boxes, &w[0], &w[1]), "unchecked segment {w:?}");
                }
            }
        }
        Ok(None) => assert!(ends_finite && config_ok && !injected),
        Err(Error::OutsideLimits { .. }) => assert!(ends_finite && !(within_limits(&start) && within_limits(&goal))),
        Err(Error::NonFiniteJoint { .. }) if !ends_finite => {}
        Err(Error::BadParameter) => assert!(ends_finite && !config_ok),
        Err(Error::Overflow) => assert!(injected),
        // The checker refuses segments too long to interpolate, or whose difference overflows.
        Err(Error::SegmentTooLong | Error::NonFiniteJoint { .. }) if use_checker && ends_finite => {}
        Err(e) => panic!("unexpected search error {e:?} (ends finite {ends_finite}, config ok {config_ok})"),
    }
});
