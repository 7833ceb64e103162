//! Arbitrary bytes through the host's PLY reader, as a point cloud and as a mesh
//! (`edmp_host::formats::cloud::parse_ply_points`, `mesh_file::parse_ply_mesh`). It must never
//! panic nor reserve memory from a header's claimed counts: the result is finite points, a mesh
//! whose indices are in range, or an error that says what is wrong.
#![no_main]

use edmp_host::formats::{cloud, mesh_file};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match cloud::parse_ply_points(data) {
        Ok(points) => assert!(points.iter().flatten().all(|v| v.is_finite())),
        Err(e) => assert!(!e.message.is_empty()),
    }
    match mesh_file::parse_ply_mesh(data) {
        Ok(mesh) => {
            assert!(mesh.vertices.iter().flatten().all(|v| v.is_finite()));
            assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < mesh.vertices.len()));
            assert!(mesh.degenerate_count() <= mesh.triangles.len());
        }
        Err(e) => assert!(!e.message.is_empty()),
    }
});
