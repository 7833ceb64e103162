//! Arbitrary bytes through the host's PCD reader (`edmp_host::formats::cloud::parse_pcd`). It
//! must never panic nor reserve memory from the header's `POINTS`: the result is finite points
//! or an error that says what is wrong.
#![no_main]

use edmp_host::formats::cloud::parse_pcd;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match parse_pcd(data) {
        Ok(points) => assert!(points.iter().flatten().all(|v| v.is_finite())),
        Err(e) => assert!(!e.message.is_empty()),
    }
});
