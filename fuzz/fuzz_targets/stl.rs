//! Arbitrary bytes through the host's STL reader (`edmp_host::formats::mesh_file::parse_stl`).
//! It must never panic nor reserve memory beyond the bytes present: the result is a mesh of
//! finite vertices whose indices are in range, or an error that says what is wrong.
#![no_main]

use edmp_host::formats::mesh_file::parse_stl;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match parse_stl(data) {
        Ok(mesh) => {
            assert!(mesh.vertices.iter().flatten().all(|v| v.is_finite()));
            assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < mesh.vertices.len()));
            assert!(mesh.degenerate_count() <= mesh.triangles.len());
        }
        Err(e) => assert!(!e.message.is_empty()),
    }
});
