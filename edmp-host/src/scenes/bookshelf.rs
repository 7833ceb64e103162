//! Bookshelf (unseen kind): two side panels, usually a back panel, and 2-6 boards, each gap
//! between boards drawn apart (20-40 cm), the lowest board 0-35 cm up. Cans and small boxes
//! stand on every board under another one. Goals are in the gaps whose middle is at most 1 m
//! up (the hand level, entering from the open front); task-oriented starts are in another
//! gap or in front of the shelf.

use super::environment::{Approach, Environment, Frame, clutter};
use edmp_core::rng::Rng;

/// Gaps whose middle is higher than this are out of the arm's comfortable reach.
const HIGHEST_GOAL: f32 = 1.0;

pub(super) fn generate(rng: &mut Rng) -> Environment {
    let boards = 2 + rng.below(5) as usize;
    let width = rng.uniform_f32(0.6, 1.1);
    let depth = rng.uniform_f32(0.25, 0.4);
    let t = rng.uniform_f32(0.015, 0.03);
    let lowest = rng.uniform_f32(0.0, 0.35);
    let gaps: Vec<f32> = (1..boards).map(|_| rng.uniform_f32(0.2, 0.4)).collect();
    let back = rng.unit_f32() < 0.7;
    let frame = Frame::facing(rng, [0.45, 0.6], 0.5, 0.2);

    // Board i spans z ∈ [bottoms[i], bottoms[i] + t]; gap i is between boards i and i + 1.
    let mut bottoms = vec![lowest];
    for g in &gaps {
        let last = bottoms[bottoms.len() - 1];
        bottoms.push(last + t + g);
    }
    let top = bottoms[bottoms.len() - 1] + t;
    let hw = width / 2.0;
    let inner_depth = if back { depth - t } else { depth };
    let mut prims = vec![
        frame.cuboid([0.0, -hw - t, 0.0], [depth, -hw, top]),
        frame.cuboid([0.0, hw, 0.0], [depth, hw + t, top]),
    ];
    if back {
        prims.push(frame.cuboid([depth - t, -hw, 0.0], [depth, hw, top]));
    }
    for &z in &bottoms {
        prims.push(frame.cuboid([0.0, -hw, z], [inner_depth, hw, z + t]));
    }
    let mut goals = Vec::new();
    let level = Approach::Level {
        yaw: frame.yaw,
        spread: core::f32::consts::FRAC_PI_6,
        upright: false,
    };
    for (i, g) in gaps.iter().enumerate() {
        let floor = bottoms[i] + t;
        let count = rng.below(4) as usize;
        clutter(
            &frame,
            rng,
            [[0.01, inner_depth - 0.01], [-hw + 0.01, hw - 0.01]],
            floor,
            (g - 0.06).min(0.25),
            count,
            &mut prims,
        );
        if floor + g / 2.0 <= HIGHEST_GOAL {
            goals.push(frame.region(
                [0.04, -hw + 0.1, floor + 0.04],
                [inner_depth - 0.06, hw - 0.1, floor + g - 0.04],
                level,
            ));
        }
    }
    let mut regions = goals.clone();
    regions.push(frame.region(
        [-0.25, -hw.min(0.4), lowest.max(0.1)],
        [-0.08, hw.min(0.4), top.min(0.9)],
        Approach::Level {
            yaw: frame.yaw,
            spread: core::f32::consts::FRAC_PI_4,
            upright: false,
        },
    ));
    Environment { prims, regions, goals }
}
