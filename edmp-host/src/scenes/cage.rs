//! Cage (unseen kind): a closed box on a stand in front of the robot; floor, roof, back and
//! sides are solid panels, the front is vertical bars (round or square) with 24-28 cm slots
//! between them. Goals are inside the cage just behind a slot, the hand upright so its wide
//! side passes between the bars; a few cans and boxes stand at the back of the cage.
//! Task-oriented starts are above the roof or in front of the bars.

use super::environment::{Approach, Environment, Frame, clutter};
use edmp_core::rng::Rng;

pub(super) fn generate(rng: &mut Rng) -> Environment {
    let slots = 2 + rng.below(2) as usize;
    let slot = rng.uniform_f32(0.24, 0.28);
    let bar = rng.uniform_f32(0.015, 0.03);
    let round = rng.unit_f32() < 0.5;
    let t = rng.uniform_f32(0.012, 0.025);
    let width = slots as f32 * slot + (slots + 1) as f32 * bar;
    let depth = rng.uniform_f32(0.3, 0.45);
    let inner = rng.uniform_f32(0.38, 0.5);
    let base = rng.uniform_f32(0.05, 0.3);
    let ledge = rng.uniform_f32(0.0, 0.08);
    let frame = Frame::facing(rng, [0.42, 0.55], 0.5, 0.2);

    // Local: the bars' front at x = 0, the cage over x ∈ [0, depth], y ∈ ±width/2 between
    // the bars' outer faces (the side panels outside them, so every slot is `slot` wide).
    let (hw, floor, roof) = (width / 2.0, base + t, base + t + inner);
    let mut prims = vec![
        // The stand, from the floor to the cage's bottom, a ledge wider than the cage.
        frame.cuboid([-ledge, -hw - t - ledge, -0.02], [depth + ledge, hw + t + ledge, base]),
        frame.cuboid([0.0, -hw - t, base], [depth, hw + t, floor]),
        frame.cuboid([0.0, -hw - t, roof], [depth, hw + t, roof + t]),
        frame.cuboid([depth - t, -hw, floor], [depth, hw, roof]),
        frame.cuboid([0.0, -hw - t, floor], [depth, -hw, roof]),
        frame.cuboid([0.0, hw, floor], [depth, hw + t, roof]),
    ];
    for i in 0..=slots {
        let y = -hw + bar / 2.0 + i as f32 * (slot + bar);
        if round {
            prims.push(frame.cylinder([bar / 2.0, y, floor], bar / 2.0, inner));
        } else {
            prims.push(frame.cuboid([0.0, y - bar / 2.0, floor], [bar, y + bar / 2.0, roof]));
        }
    }
    let reach_in = (0.55 * depth).min(bar + 0.2);
    let count = rng.below(4) as usize;
    clutter(
        &frame,
        rng,
        [[reach_in + 0.02, depth - t - 0.01], [-hw + 0.01, hw - 0.01]],
        floor,
        (inner - 0.15).min(0.15),
        count,
        &mut prims,
    );

    // Behind each slot: 5 cm past the bars up to `reach_in`, clear of the bars by 7 cm
    // sideways and of floor and roof by 12 cm (the upright hand is 20 cm tall).
    let upright = Approach::Level {
        yaw: frame.yaw,
        spread: core::f32::consts::FRAC_PI_8,
        upright: true,
    };
    let goals = (0..slots)
        .map(|i| {
            let y = -hw + bar + slot / 2.0 + i as f32 * (slot + bar);
            let side = slot / 2.0 - 0.07;
            frame.region(
                [bar + 0.05, y - side, floor + 0.12],
                [reach_in, y + side, roof - 0.12],
                upright,
            )
        })
        .collect();
    let regions = vec![
        frame.region(
            [0.03, -hw + 0.05, roof + t + 0.03],
            [0.5 * depth, hw - 0.05, roof + t + 0.15],
            Approach::RoughlyDown,
        ),
        frame.region(
            [-0.2, -hw, floor + 0.05],
            [-0.08, hw, roof],
            Approach::Level {
                yaw: frame.yaw,
                spread: core::f32::consts::FRAC_PI_4,
                upright: false,
            },
        ),
    ];
    Environment { prims, regions, goals }
}
