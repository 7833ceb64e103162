//! The core's global search wired to the exact checker: a wall between two configurations
//! (the planner bench's scene), a path found around it, and the 50-waypoint output checked
//! free as a whole trajectory.

use edmp_core::collision::checker::{CheckConfig, check_state, check_trajectory};
use edmp_core::path::HORIZON;
use edmp_core::planner::search::{SearchConfig, SearchSpace, search};
use edmp_core::rng::Rng;
use edmp_core::robot::PANDA;
use edmp_core::robot::kinematics::Joints;
use edmp_core::scene::{Obstacle, Scene};

const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];

fn wall_scene() -> Scene<'static, 8> {
    let mut scene = Scene::<8>::new();
    scene
        .push(Obstacle::cuboid([0.5, 0.0, -0.01], [1.2, 1.6, 0.02], ID).unwrap())
        .unwrap();
    scene
        .push(Obstacle::cuboid([0.55, 0.0, 0.45], [0.3, 0.02, 0.5], ID).unwrap())
        .unwrap();
    scene
}

#[test]
fn search_finds_a_checked_free_path_around_a_wall() {
    let scene = wall_scene();
    let cfg = CheckConfig::DEFAULT;
    let start: Joints<f32> = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    let goal: Joints<f32> = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    assert_eq!(check_state(&edmp_core::robot::PANDA, &scene, &start, &cfg), Ok(None));
    assert_eq!(check_state(&edmp_core::robot::PANDA, &scene, &goal, &cfg), Ok(None));
    assert!(
        !check_trajectory(&edmp_core::robot::PANDA, &scene, &[start, goal], &cfg, true)
            .unwrap()
            .is_free()
    );

    let config = SearchConfig::DEFAULT;
    let mut space = Box::new(SearchSpace::<2048>::new());
    let mut first = None;
    for seed in 1..=6 {
        let mut calls = 0u64;
        let mut edge_free = |a: &Joints<f32>, b: &Joints<f32>| {
            calls += 1;
            Ok(check_trajectory(&edmp_core::robot::PANDA, &scene, &[*a, *b], &cfg, true)?.is_free())
        };
        let found = search(
            &PANDA,
            &start,
            &goal,
            &config,
            &mut space,
            &mut Rng::new(seed),
            &mut edge_free,
        )
        .unwrap()
        .expect("a path around the wall");
        println!(
            "seed {seed}: {} iterations, {} nodes, {} corners, even {}, {} oracle calls",
            found.iterations, found.nodes, found.corners, found.even, found.oracle_calls
        );
        assert_eq!(u64::from(found.oracle_calls), calls);
        assert!(calls <= config.max_oracle_calls(2048));
        assert_eq!(found.path.len(), HORIZON);
        assert_eq!((found.path[0], found.path[HORIZON - 1]), (start, goal));
        let whole = check_trajectory(&edmp_core::robot::PANDA, &scene, &found.path, &cfg, false).unwrap();
        assert!(whole.is_free(), "seed {seed}: {whole:?}");
        first.get_or_insert(found);
    }
    let found = first.unwrap();
    // Deterministic: the same seed gives the same bits.
    let again = search(
        &PANDA,
        &start,
        &goal,
        &config,
        &mut space,
        &mut Rng::new(1),
        &mut |a: &Joints<f32>, b: &Joints<f32>| {
            Ok(check_trajectory(&edmp_core::robot::PANDA, &scene, &[*a, *b], &cfg, true)?.is_free())
        },
    )
    .unwrap()
    .unwrap();
    assert_eq!(again, found);
}
