//! Window box (unseen kind): a closed box of about 70 cm, on the floor or a low stand, whose
//! front wall has a window of 30-36 cm on a side at a random place (the wall is four panels
//! around the hole). Goals are just inside the window, the hand's wide side upright or level
//! (per scene); cans and boxes stand on the box's floor behind them. Task-oriented starts are
//! above the box or in front of the window.

use super::environment::{Approach, Environment, Frame, clutter};
use edmp_core::rng::Rng;

pub(super) fn generate(rng: &mut Rng) -> Environment {
    let (width, depth, height) = (
        rng.uniform_f32(0.62, 0.78),
        rng.uniform_f32(0.62, 0.78),
        rng.uniform_f32(0.62, 0.75),
    );
    let t = rng.uniform_f32(0.012, 0.03);
    let stand = if rng.unit_f32() < 0.5 {
        rng.uniform_f32(0.03, 0.12)
    } else {
        0.0
    };
    let (ww, wh) = (rng.uniform_f32(0.3, 0.36), rng.uniform_f32(0.3, 0.36));
    let hw = width / 2.0;
    let (z0, z1) = (stand, stand + height);
    // The window's middle, leaving at least 2 cm of wall on every side of it.
    let wy = rng.uniform_f32(-hw + t + ww / 2.0 + 0.02, hw - t - ww / 2.0 - 0.02);
    let wz = rng.uniform_f32(z0 + t + wh / 2.0 + 0.02, z1 - t - wh / 2.0 - 0.02);
    let upright = rng.unit_f32() < 0.5;
    let frame = Frame::facing(rng, [0.42, 0.55], 0.5, 0.2);

    let (yl, yr, zb, zt) = (wy - ww / 2.0, wy + ww / 2.0, wz - wh / 2.0, wz + wh / 2.0);
    let mut prims = Vec::new();
    if stand > 0.0 {
        prims.push(frame.cuboid([0.0, -hw, -0.02], [depth, hw, z0]));
    }
    prims.extend([
        frame.cuboid([0.0, -hw, z0], [depth, hw, z0 + t]),
        frame.cuboid([0.0, -hw, z1 - t], [depth, hw, z1]),
        frame.cuboid([depth - t, -hw, z0 + t], [depth, hw, z1 - t]),
        frame.cuboid([t, -hw, z0 + t], [depth - t, -hw + t, z1 - t]),
        frame.cuboid([t, hw - t, z0 + t], [depth - t, hw, z1 - t]),
        // The front wall: right of, left of, below and above the window.
        frame.cuboid([0.0, -hw, z0 + t], [t, yl, z1 - t]),
        frame.cuboid([0.0, yr, z0 + t], [t, hw, z1 - t]),
        frame.cuboid([0.0, yl, z0 + t], [t, yr, zb]),
        frame.cuboid([0.0, yl, zt], [t, yr, z1 - t]),
    ]);
    let count = rng.below(5) as usize;
    clutter(
        &frame,
        rng,
        [[t + 0.3, depth - t - 0.01], [-hw + t + 0.01, hw - t - 0.01]],
        z0 + t,
        0.2,
        count,
        &mut prims,
    );

    // Just inside the window: 6-25 cm past the wall, 11 cm clear of the window's edges along
    // the hand's wide side (20 cm), 6 cm along its narrow side.
    let (side_y, side_z) = if upright {
        (ww / 2.0 - 0.06, wh / 2.0 - 0.11)
    } else {
        (ww / 2.0 - 0.11, wh / 2.0 - 0.06)
    };
    let goals = vec![frame.region(
        [t + 0.06, wy - side_y, wz - side_z],
        [t + 0.25, wy + side_y, wz + side_z],
        Approach::Level {
            yaw: frame.yaw,
            spread: core::f32::consts::FRAC_PI_8,
            upright,
        },
    )];
    let regions = vec![
        frame.region(
            [0.03, -hw + 0.05, z1 + 0.03],
            [0.25, hw - 0.05, z1 + 0.15],
            Approach::RoughlyDown,
        ),
        frame.region(
            [-0.2, wy - ww, zb],
            [-0.08, wy + ww, zt],
            Approach::Level {
                yaw: frame.yaw,
                spread: core::f32::consts::FRAC_PI_4,
                upright: false,
            },
        ),
    ];
    Environment { prims, regions, goals }
}
