//! Cubby (MpiNets `Cubby`, 2×2) and merged cubby: seven boards, turned about the cubby's centre
//! by up to ±10°. The four pockets, bounded by the boards' centre lines, are the pose regions.
//! Merged: two pockets are drawn and the shelf and/or wall between them is removed (MpiNets
//! keeps it at zero thickness; zero sizes are invalid in our scene format, so it is left out).

use super::environment::{Approach, Environment, Region, yaw_quaternion};
use edmp_core::rng::Rng;
use edmp_core::scene::Primitive;

pub(super) fn generate(rng: &mut Rng, merged: bool) -> Environment {
    let mut pm = |c: f32, r: f32| rng.uniform_f32(c - r, c + r);
    let left = pm(0.7, 0.1);
    let right = pm(-0.7, 0.1);
    let bottom = pm(0.2, 0.1);
    let front = pm(0.55, 0.1);
    let back = front + pm(0.35, 0.2);
    let top = pm(0.7, 0.1);
    let middle = pm(0.45, 0.1);
    let wall = pm(0.0, 0.1);
    let t = pm(0.02, 0.01);
    let yaw = pm(0.0, core::f32::consts::PI / 18.0);
    let (cx, cy) = ((front + back) / 2.0, (left + right) / 2.0);
    let (depth, width) = (back - front, left - right);

    let pockets: Vec<([f32; 2], [f32; 2])> = [[right, wall], [wall, left]]
        .iter()
        .flat_map(|&y| [[bottom, middle], [middle, top]].map(|z| (y, z)))
        .collect();
    let (mut keep_middle, mut keep_wall) = (true, true);
    let chosen: Vec<usize> = if merged {
        let a = rng.below(4) as usize;
        let b = (a + 1 + rng.below(3) as usize) % 4;
        keep_middle = pockets[a].1 == pockets[b].1; // same row: the shelf stays
        keep_wall = pockets[a].0 == pockets[b].0; // same column: the wall stays
        vec![a, b]
    } else {
        (0..4).collect()
    };

    let mut boards = vec![
        ([back, cy, top / 2.0], [t, width, top]),
        ([cx, cy, bottom], [depth, width, t]),
        ([cx, cy, top], [depth, width, t]),
        ([cx, right, (top + bottom) / 2.0], [depth, t, top - bottom + t]),
        ([cx, left, (top + bottom) / 2.0], [depth, t, top - bottom + t]),
    ];
    if keep_middle {
        boards.push(([cx, cy, middle], [depth, width, t]));
    }
    if keep_wall {
        boards.push(([cx, wall, (top + bottom) / 2.0], [depth, t, top - bottom]));
    }
    let (s, c) = yaw.sin_cos();
    let turn = |x: f32, y: f32| [cx + c * (x - cx) - s * (y - cy), cy + s * (x - cx) + c * (y - cy)];
    let prims = boards
        .into_iter()
        .map(|(p, dims)| {
            let [x, y] = turn(p[0], p[1]);
            Primitive::Cuboid {
                center: [x, y, p[2]],
                dims,
                quaternion: yaw_quaternion(yaw),
            }
        })
        .collect();
    let regions = chosen
        .iter()
        .map(|&i| {
            let (y, z) = pockets[i];
            let [x, yc] = turn(cx, (y[0] + y[1]) / 2.0);
            Region {
                center: [x, yc, (z[0] + z[1]) / 2.0],
                half: [depth / 2.0, (y[1] - y[0]).abs() / 2.0, (z[1] - z[0]).abs() / 2.0],
                yaw,
                approach: Approach::Horizontal { yaw },
            }
        })
        .collect();
    Environment {
        prims,
        regions,
        goals: Vec::new(),
    }
}
