//! Arbitrary bytes through the firmware's decoder: `postcard::from_bytes::<wire::Problem<N>>`
//! then `Problem::to_scene`, as examples/firmware-qemu decodes. Decoding must fail cleanly or
//! give a problem that re-encodes to bytes that decode to the same problem; `to_scene` must
//! build exactly the primitives' obstacles (finite, positive, rotations orthonormal) and the
//! finger opening, or return the first primitive's typed error (then the opening's), never `TooManyObstacles` (the list and the scene share N).
#![no_main]

use edmp_core::scene::{SceneError, Shape};
use edmp_core::wire::Problem;
use libfuzzer_sys::fuzz_target;

const N: usize = edmp_core::scene::MAX_OBSTACLES;

fuzz_target!(|data: &[u8]| {
    let Ok(problem) = postcard::from_bytes::<Problem<N>>(data) else {
        return;
    };
    let mut buf = [0u8; 16384];
    let bytes = postcard::to_slice(&problem, &mut buf).expect("a decoded problem re-encodes");
    let again: Problem<N> = postcard::from_bytes(bytes).expect("re-encoded bytes decode");
    let mut buf2 = [0u8; 16384];
    assert_eq!(postcard::to_slice(&again, &mut buf2).unwrap(), bytes, "encoding is not stable");

    let expected = problem
        .obstacles
        .iter()
        .chain(problem.held.iter())
        .map(|p| p.to_obstacle())
        .find_map(Result::err)
        .or_else(|| edmp_core::scene::finger_opening(problem.finger).err());
    match problem.to_scene() {
        Ok(scene) => {
            assert!(expected.is_none());
            assert_eq!(scene.obstacles().len(), problem.obstacles.len());
            assert_eq!(scene.held().is_some(), problem.held.is_some());
            assert_eq!(scene.gripper().to_bits(), problem.finger.to_bits());
            for o in scene.obstacles().iter().chain(scene.held()) {
                assert!(o.center.iter().chain(o.rotation.iter()).all(|x| x.is_finite()));
                let r = o.rotation;
                assert!((r.transpose() * r - nalgebra::Matrix3::identity()).norm() < 1e-3, "{r:?}");
                match o.shape {
                    Shape::Cuboid { dims } => assert!(dims.iter().all(|&d| d.is_finite() && d > 0.0)),
                    Shape::Cylinder { radius, height } => {
                        assert!(radius.is_finite() && radius > 0.0 && height.is_finite() && height > 0.0)
                    }
                    Shape::Sphere { radius } => assert!(radius.is_finite() && radius > 0.0),
                }
            }
        }
        Err(SceneError::TooManyObstacles) => panic!("capacity error from a list of at most N"),
        Err(e) => assert_eq!(Some(e), expected),
    }
});
