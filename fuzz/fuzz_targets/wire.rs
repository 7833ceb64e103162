//! Arbitrary bytes through the firmware's decoder: `wire::decode::<N, P, P, JOINTS>` (a problem, then an
//! optional surface section of built pieces and their tree) then `Problem::to_scene_with`, as
//! examples/firmware-qemu decodes. Decoding must fail with a typed error or give a problem and a
//! surface whose encoding is stable; a decoded surface's tree is one `Surface::new`
//! accepts; `to_scene_with` must build exactly the primitives' obstacles (finite, positive,
//! rotations orthonormal) and the finger opening, or return the first primitive's typed error
//! (then the opening's), never `TooManyObstacles` (the list and the scene share N).
#![no_main]

use edmp_core::robot::JOINTS;
use edmp_core::scene::{SceneError, Shape};
use edmp_core::wire::{Problem, WireError, WireSurface, decode, encode_surface, surface_bytes_max};
use libfuzzer_sys::fuzz_target;

const N: usize = edmp_core::scene::MAX_OBSTACLES;
/// Pieces: small, so that arbitrary bytes reach the tree's checks.
const P: usize = 64;

fuzz_target!(|data: &[u8]| {
    let mut surface = Box::new(WireSurface::<P>::new());
    let Ok(problem) = decode::<N, P, P, JOINTS>(data, &mut surface) else {
        assert!(surface.pieces().is_empty() && surface.nodes().is_empty(), "a refused input leaves no pieces");
        return;
    };
    let view = surface.surface().expect("a decoded tree is valid");
    assert_eq!(view.pieces().len(), surface.pieces().len());

    // What it re-encodes to decodes to the same problem and surface, and re-encodes alike.
    let bytes = encode(&problem, &surface);
    let mut again = Box::new(WireSurface::<P>::new());
    let back = decode::<N, P, P, JOINTS>(&bytes, &mut again).expect("re-encoded bytes decode");
    assert_eq!(encode(&back, &again), bytes, "encoding is not stable");
    assert_eq!(again.pieces().len(), surface.pieces().len());

    let expected = problem
        .obstacles
        .iter()
        .chain(problem.held.iter())
        .map(|p| p.to_obstacle())
        .find_map(Result::err)
        .or_else(|| edmp_core::scene::finger_opening(problem.finger).err());
    match problem.to_scene_with(&surface) {
        Ok(scene) => {
            assert!(expected.is_none());
            assert_eq!(scene.obstacles().len(), problem.obstacles.len());
            assert_eq!(scene.surface().pieces().len(), surface.pieces().len());
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
        Err(WireError::Scene(SceneError::TooManyObstacles)) => panic!("capacity error from a list of at most N"),
        Err(WireError::Scene(e)) => assert_eq!(Some(e), expected),
        Err(e) => panic!("a decoded surface refused when building the scene: {e}"),
    }
});

fn encode(problem: &Problem<N>, surface: &WireSurface<P>) -> Vec<u8> {
    let mut buf = vec![0u8; 16384 + surface_bytes_max(P, P)];
    let n = postcard::to_slice(problem, &mut buf).expect("a decoded problem re-encodes").len();
    let m = if surface.pieces().is_empty() {
        0
    } else {
        encode_surface(surface.pieces(), surface.nodes(), surface.boxes(), &mut buf[n..]).expect("re-encodes")
    };
    buf.truncate(n + m);
    buf
}
