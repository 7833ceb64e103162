//! Under table (unseen kind): a table (four legs) or a shelf (two side panels and a back)
//! whose top is 35-60 cm up, on a floor slab, with cans and boxes on the top and a few under
//! it at the back. Goals are under the top, just past its front edge, the hand level;
//! task-oriented starts are above the top or beside the table (where that is within reach).

use super::environment::{Approach, Environment, Frame, clutter};
use edmp_core::rng::Rng;

/// Regions whose middle is farther than this from the base are dropped.
const REACH: f32 = 0.85;

pub(super) fn generate(rng: &mut Rng) -> Environment {
    let height = rng.uniform_f32(0.35, 0.6);
    let thick = rng.uniform_f32(0.02, 0.05);
    let width = rng.uniform_f32(0.7, 1.1);
    let depth = rng.uniform_f32(0.5, 0.8);
    let legs = rng.unit_f32() < 0.6;
    let frame = Frame::facing(rng, [0.35, 0.5], 0.5, 0.2);

    let (hw, under) = (width / 2.0, height - thick);
    let mut prims = vec![
        frame.cuboid([-0.1, -hw, -0.02], [depth, hw, 0.0]),
        frame.cuboid([0.0, -hw, under], [depth, hw, height]),
    ];
    // How far in from the sides the supports reach: goals keep 10 cm clear of them.
    let side = if legs {
        let size = rng.uniform_f32(0.04, 0.06);
        let inset = rng.uniform_f32(0.02, 0.08);
        let round = rng.unit_f32() < 0.5;
        for x in [inset, depth - inset - size] {
            for y in [-hw + inset, hw - inset - size] {
                if round {
                    let r = size / 2.0;
                    prims.push(frame.cylinder([x + r, y + r, 0.0], r, under));
                } else {
                    prims.push(frame.cuboid([x, y, 0.0], [x + size, y + size, under]));
                }
            }
        }
        inset + size
    } else {
        let t = rng.uniform_f32(0.015, 0.03);
        prims.push(frame.cuboid([0.0, -hw, 0.0], [depth, -hw + t, under]));
        prims.push(frame.cuboid([0.0, hw - t, 0.0], [depth, hw, under]));
        prims.push(frame.cuboid([depth - t, -hw + t, 0.0], [depth, hw - t, under]));
        t
    };
    let on_top = rng.below(5) as usize;
    clutter(
        &frame,
        rng,
        [[0.02, depth - 0.02], [-hw + 0.02, hw - 0.02]],
        height,
        0.3,
        on_top,
        &mut prims,
    );
    let below = rng.below(3) as usize;
    clutter(
        &frame,
        rng,
        [[0.6 * depth, depth - 0.05], [-hw + side + 0.01, hw - side - 0.01]],
        0.0,
        (under - 0.05).min(0.2),
        below,
        &mut prims,
    );

    let level = |spread| Approach::Level {
        yaw: frame.yaw,
        spread,
        upright: false,
    };
    let goals = vec![frame.region(
        [0.04, -hw + side + 0.1, 0.06],
        [(0.5 * depth).min(0.3), hw - side - 0.1, under - 0.06],
        level(core::f32::consts::FRAC_PI_6),
    )];
    let mut regions = vec![frame.region(
        [0.05, -hw + 0.05, height + 0.03],
        [(depth - 0.05).min(0.35), hw - 0.05, height + 0.15],
        Approach::RoughlyDown,
    )];
    for sign in [-1.0f32, 1.0] {
        let lo = [0.0, sign * (hw + 0.08), 0.1];
        let hi = [0.3, sign * (hw + 0.25), height + 0.1];
        let mid = core::array::from_fn(|i| (lo[i] + hi[i]) / 2.0);
        if frame.reach_of(mid) <= REACH {
            let (y0, y1) = (lo[1].min(hi[1]), lo[1].max(hi[1]));
            regions.push(frame.region(
                [lo[0], y0, lo[2]],
                [hi[0], y1, hi[2]],
                level(core::f32::consts::FRAC_PI_4),
            ));
        }
    }
    Environment { prims, regions, goals }
}
