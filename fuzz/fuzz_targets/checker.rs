//! Arbitrary scenes, states, segments and settings through the exact checker: `check_end`,
//! `check_state`, `check_segment` and `check_trajectory`. Every call must answer or return a
//! typed error that matches the input (`BadParameter` for a bad config, `NonFiniteJoint`,
//! `SegmentTooLong`); the answers must agree with each other (a free trajectory has free ends
//! and free segments; stopping at the first contact does not change whether one exists).
#![no_main]

#[path = "common.rs"]
mod common;

use common::{Reader, finite, scene};
use edmp_core::Error;
use edmp_core::collision::checker::{CheckConfig, MAX_STEPS_PER_SEGMENT, check_end, check_segment, check_state, check_trajectory};
use edmp_core::robot::kinematics::Joints;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut r = Reader(data);
    let flags = r.byte();
    let scene = scene::<6>(&mut r);
    let mut config = CheckConfig { self_collision: flags & 1 == 0, ..CheckConfig::default() };
    if flags & 2 != 0 {
        config.margin = r.raw();
        config.end_margin = r.raw();
        config.end_radius = r.raw();
        config.self_margin = r.raw();
    }
    if flags & 4 != 0 {
        config.max_step = r.raw();
    }
    let d = |x: f32| x.is_finite() && x >= 0.0;
    let config_ok = d(config.margin)
        && d(config.end_margin)
        && d(config.end_radius)
        && d(config.self_margin)
        && config.max_step.is_finite()
        && config.max_step > 0.0;
    // Three waypoints; in tame mode each is the previous plus at most 0.1 rad per joint.
    let a = r.array::<7>();
    let mut traj = [a; 3];
    for i in 1..3 {
        traj[i] = if flags & 8 == 0 {
            core::array::from_fn(|j| traj[i - 1][j] + f32::from(r.byte() as i8) / 1280.0)
        } else {
            r.array::<7>()
        };
    }
    let all_finite = traj.iter().all(|q| finite(q));

    let expect_state = |res: Result<Option<_>, Error>, q: &Joints<f32>| match res {
        Ok(_) => assert!(config_ok && finite(q)),
        Err(Error::BadParameter) => assert!(!config_ok),
        Err(Error::NonFiniteJoint { joint }) => assert!(config_ok && !q[usize::from(joint)].is_finite()),
        Err(e) => panic!("unexpected state error {e:?}"),
    };
    let end = check_end(&edmp_core::robot::PANDA, &scene, &traj[0], &config);
    expect_state(end, &traj[0]);
    expect_state(check_state(&edmp_core::robot::PANDA, &scene, &traj[2], &config), &traj[2]);
    expect_state(check_end(&edmp_core::robot::PANDA, &scene, &traj[2], &config), &traj[2]);

    // Segments are taken in order: the first whose joint difference is not finite is
    // `NonFiniteJoint` (also for finite waypoints whose difference overflows), the first too
    // long to interpolate is `SegmentTooLong`; `None` when every segment is fine.
    let first_bad = traj.windows(2).find_map(|w| {
        let diffs = || w[0].iter().zip(&w[1]).map(|(x, y)| (y - x).abs());
        let widest = if diffs().all(f32::is_finite) { diffs().fold(0.0f32, f32::max) } else { f32::NAN };
        if !widest.is_finite() {
            Some(Error::NonFiniteJoint { joint: 0 })
        } else if (widest / config.max_step).ceil() > MAX_STEPS_PER_SEGMENT as f32 {
            Some(Error::SegmentTooLong)
        } else {
            None
        }
    });
    let steps_ok = first_bad.is_none();
    let expect_path = |e: Error| match e {
        Error::BadParameter => assert!(!config_ok),
        Error::NonFiniteJoint { .. } => assert!(config_ok && matches!(first_bad, Some(Error::NonFiniteJoint { .. }))),
        Error::SegmentTooLong => assert!(config_ok && first_bad == Some(Error::SegmentTooLong)),
        e => panic!("unexpected trajectory error {e:?}"),
    };
    let full = check_trajectory(&edmp_core::robot::PANDA, &scene, &traj, &config, false);
    let first = check_trajectory(&edmp_core::robot::PANDA, &scene, &traj, &config, true);
    match (full, first) {
        (Ok(full), Ok(first)) => {
            assert!(config_ok && all_finite && steps_ok);
            assert!(full.colliding_states <= full.states && first.states <= full.states);
            assert_eq!(full.is_free(), first.is_free());
            assert_eq!(full.first_contact, first.first_contact);
            assert_eq!(first.colliding_states, u32::from(first.first_contact.is_some()));
            // The first state is checked exactly as `check_end` checks it (fresh GJK hints,
            // `end_margin`); later states reuse the hints, so only the first is compared.
            assert_eq!(end.is_ok_and(|c| c.is_some()), matches!(full.first_contact, Some(c) if c.segment == 0 && c.step == 0));
            // `check_segment` checks the same states in another order (the far end first, then
            // every 8th), so only a state that GJK's carried direction decides at the margin can
            // make the verdicts differ: it must answer, and it agrees with a fresh check of its
            // far end, which it checks first with fresh directions.
            let segment = check_segment(&edmp_core::robot::PANDA, &scene, &traj[0], &traj[1], [&traj[0], &traj[2]], &config);
            assert!(segment.is_ok(), "{segment:?}");
            let near = |e: &[f32; 7]| traj[1].iter().zip(e).all(|(x, y)| (x - y).abs() <= config.end_radius);
            if !near(&traj[0]) && !near(&traj[2]) && check_state(&edmp_core::robot::PANDA, &scene, &traj[1], &config).is_ok_and(|c| c.is_some()) {
                assert_eq!(segment, Ok(false));
            }
        }
        (Err(a), Err(b)) => {
            assert_eq!(a, b);
            expect_path(a);
        }
        (a, b) => {
            // Stopping at a first contact may skip a later segment that is too long.
            assert!(matches!(b, Ok(ref rep) if !rep.is_free()), "full {a:?}, first {b:?}");
            expect_path(a.unwrap_err());
        }
    }
});
