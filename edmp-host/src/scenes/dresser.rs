//! Dresser (MpiNets `Dresser`): a 1 cm board body, split recursively into drawer cells (split
//! probability 0.7, decaying by 0.8; cells under 0.3 m are not split further in that
//! direction), two drawers pulled out by 0.9 of their depth, the pose regions inside them.
//! Simplifications: closed drawers are their front panels only (the rest is hidden in the
//! body); MpiNets' 70 % rejection of start and goal drawers at the same height is not applied.

use super::environment::{Approach, Environment, Region, yaw_quaternion};
use edmp_core::rng::Rng;
use edmp_core::scene::Primitive;

struct Cell {
    x: [f32; 2],
    z: [f32; 2],
}

fn split(rng: &mut Rng, cell: Cell, p: f32, walls: &mut Vec<([f32; 3], [f32; 3])>, cells: &mut Vec<Cell>, depth: f32) {
    let (w, h) = (cell.x[1] - cell.x[0], cell.z[1] - cell.z[0]);
    if (w < 0.3 && h < 0.3) || rng.unit_f32() >= p {
        cells.push(cell);
        return;
    }
    let vertical = if w < 0.3 {
        false
    } else if h < 0.3 {
        true
    } else {
        rng.unit_f32() < 0.5
    };
    let y = 0.0;
    if vertical {
        let at = rng.uniform_f32(cell.x[0] + 0.15, cell.x[1] - 0.15);
        walls.push(([at, y, (cell.z[0] + cell.z[1]) / 2.0], [0.01, depth, h]));
        split(
            rng,
            Cell {
                x: [cell.x[0], at],
                z: cell.z,
            },
            p * 0.8,
            walls,
            cells,
            depth,
        );
        split(
            rng,
            Cell {
                x: [at, cell.x[1]],
                z: cell.z,
            },
            p * 0.8,
            walls,
            cells,
            depth,
        );
    } else {
        let at = rng.uniform_f32(cell.z[0] + 0.15, cell.z[1] - 0.15);
        walls.push(([(cell.x[0] + cell.x[1]) / 2.0, y, at], [w, depth, 0.01]));
        split(
            rng,
            Cell {
                x: cell.x,
                z: [cell.z[0], at],
            },
            p * 0.8,
            walls,
            cells,
            depth,
        );
        split(
            rng,
            Cell {
                x: cell.x,
                z: [at, cell.z[1]],
            },
            p * 0.8,
            walls,
            cells,
            depth,
        );
    }
}

pub(super) fn generate(rng: &mut Rng) -> Environment {
    let width = rng.uniform_f32(0.8, 1.2);
    let depth = rng.uniform_f32(0.2, 0.4);
    let height = rng.uniform_f32(0.55, 0.85);
    let origin = [rng.uniform_f32(0.55, 0.75), rng.uniform_f32(-0.1, 0.1)];
    let yaw =
        core::f32::consts::FRAC_PI_2 + rng.uniform_f32(-core::f32::consts::FRAC_PI_3, core::f32::consts::FRAC_PI_3);

    // Local frame: width along x, depth along y with the open front at +y, z up.
    let (hw, hd) = (width / 2.0, depth / 2.0);
    let mut local: Vec<([f32; 3], [f32; 3])> = vec![
        ([0.0, 0.0, height - 0.005], [width, depth, 0.01]),
        ([0.0, 0.0, 0.005], [width, depth, 0.01]),
        ([-hw + 0.005, 0.0, height / 2.0], [0.01, depth, height]),
        ([hw - 0.005, 0.0, height / 2.0], [0.01, depth, height]),
        ([0.0, -hd + 0.005, height / 2.0], [width, 0.01, height]),
    ];
    let mut cells = Vec::new();
    for _ in 0..20 {
        let mut walls = Vec::new();
        cells.clear();
        split(
            rng,
            Cell {
                x: [-hw + 0.01, hw - 0.01],
                z: [0.01, height - 0.01],
            },
            0.7,
            &mut walls,
            &mut cells,
            depth,
        );
        if cells.len() >= 2 {
            local.extend(walls);
            break;
        }
    }
    if cells.len() < 2 {
        // Never split: one horizontal shelf makes two drawers.
        let mid = height / 2.0;
        local.push(([0.0, 0.0, mid], [width - 0.02, depth, 0.01]));
        cells = vec![
            Cell {
                x: [-hw + 0.01, hw - 0.01],
                z: [0.01, mid],
            },
            Cell {
                x: [-hw + 0.01, hw - 0.01],
                z: [mid, height - 0.01],
            },
        ];
    }
    let first = rng.below(cells.len() as u32) as usize;
    let second = (first + 1 + rng.below(cells.len() as u32 - 1) as usize) % cells.len();
    let drawer_depth = 0.9 * depth;
    let pull = 0.9 * drawer_depth;
    let mut regions_local = Vec::new();
    for (i, cell) in cells.iter().enumerate() {
        let (cx, w) = ((cell.x[0] + cell.x[1]) / 2.0, cell.x[1] - cell.x[0] - 0.004);
        let h = cell.z[1] - cell.z[0] - 0.004;
        let open = i == first || i == second;
        let shift = if open { pull } else { 0.0 };
        let front_y = hd + shift - 0.0095;
        local.push(([cx, front_y, (cell.z[0] + cell.z[1]) / 2.0], [w, 0.019, h]));
        if !open {
            continue;
        }
        let back_y = front_y - drawer_depth;
        let mid_y = (front_y + back_y) / 2.0;
        local.push(([cx, mid_y, cell.z[0] + 0.004], [w, drawer_depth, 0.004]));
        local.push((
            [cell.x[0] + 0.004, mid_y, (cell.z[0] + cell.z[1]) / 2.0],
            [0.004, drawer_depth, h],
        ));
        local.push((
            [cell.x[1] - 0.004, mid_y, (cell.z[0] + cell.z[1]) / 2.0],
            [0.004, drawer_depth, h],
        ));
        local.push(([cx, back_y, (cell.z[0] + cell.z[1]) / 2.0], [w, 0.004, h]));
        // Inside the drawer, eroded by 2 cm, its top lowered by 5 cm.
        let inner = [w / 2.0 - 0.02, drawer_depth / 2.0 - 0.02];
        let z = [cell.z[0] + 0.02, (cell.z[1] - 0.05).max(cell.z[0] + 0.03)];
        if inner[0] > 0.0 && inner[1] > 0.0 {
            regions_local.push((
                [cx, mid_y, (z[0] + z[1]) / 2.0],
                [inner[0], inner[1], (z[1] - z[0]) / 2.0],
            ));
        }
    }
    let (s, c) = yaw.sin_cos();
    let place = |p: [f32; 3]| [origin[0] + c * p[0] - s * p[1], origin[1] + s * p[0] + c * p[1], p[2]];
    let prims = local
        .into_iter()
        .map(|(p, dims)| Primitive::Cuboid {
            center: place(p),
            dims,
            quaternion: yaw_quaternion(yaw),
        })
        .collect();
    let regions = regions_local
        .into_iter()
        .map(|(p, half)| Region {
            center: place(p),
            half,
            yaw,
            approach: Approach::Down { yaw },
        })
        .collect();
    Environment {
        prims,
        regions,
        goals: Vec::new(),
    }
}
