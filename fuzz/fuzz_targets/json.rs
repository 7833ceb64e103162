//! Arbitrary bytes through the host's one reader of `edmp-scene/1` (`edmp_host::formats::json`), which
//! the CLI and the Python package share. It must never panic: the result is either a problem
//! whose ends are finite and whose obstacles fit the scene's capacity, or an error message
//! (the JSON path of the bad field and why).
#![no_main]

use edmp_host::formats::json::{Goal, parse_problem};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = core::str::from_utf8(data) else {
        return;
    };
    match parse_problem(text) {
        Ok(problem) => {
            assert!(problem.start.iter().all(|v| v.is_finite()));
            match problem.goal {
                Goal::Joints(q) => assert!(q.iter().all(|v| v.is_finite())),
                Goal::Pose { position, quaternion } => {
                    assert!(position.iter().chain(quaternion.iter()).all(|v| v.is_finite()))
                }
            }
            assert!(problem.scene().obstacles().len() <= edmp_core::scene::MAX_OBSTACLES);
        }
        Err(message) => assert!(!message.to_string().is_empty(), "an error names its field"),
    }
});
