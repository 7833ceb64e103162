//! Tabletop (MpiNets `TabletopEnvironment`): a front table, sometimes a side table, the robot's
//! mount table, and 3-14 boxes and cylinders on the tables' task parts.
//! Simplifications: an object's clearance to the others is measured between bounding circles
//! of their footprints (MpiNets uses the exact SDF); pose regions are clipped to the arm's reach.

use super::environment::{Approach, Environment, Region, yaw_quaternion};
use edmp_core::rng::Rng;
use edmp_core::scene::Primitive;

/// Beyond this distance from the base the Panda's TCP cannot go; regions are clipped to it.
const REACH: f32 = 0.85;

struct Area {
    x: [f32; 2],
    y: [f32; 2],
}

impl Area {
    fn size(&self) -> f32 {
        (self.x[1] - self.x[0]).max(0.0) * (self.y[1] - self.y[0]).max(0.0)
    }
}

pub(super) fn generate(rng: &mut Rng) -> Environment {
    let h = if rng.unit_f32() < 0.65 {
        rng.uniform_f32(0.0, 0.4)
    } else {
        0.0
    };
    let (x0, x1) = (rng.uniform_f32(0.275, 0.375), rng.uniform_f32(1.275, 1.375));
    let y_max = rng.uniform_f32(1.5, 1.65);
    let side = rng.unit_f32() < 0.5;
    let y_min = if side {
        rng.uniform_f32(-1.0, -0.75)
    } else {
        rng.uniform_f32(-0.75, -0.55)
    };
    let table = |x: [f32; 2], y: [f32; 2]| Primitive::Cuboid {
        center: [(x[0] + x[1]) / 2.0, (y[0] + y[1]) / 2.0, (h - 0.02) / 2.0],
        dims: [x[1] - x[0], y[1] - y[0], h + 0.02],
        quaternion: [1.0, 0.0, 0.0, 0.0],
    };
    let mut prims = vec![table([x0, x1], [y_min, y_max])];
    let front_fraction = rng.uniform_f32(0.55, 0.65);
    let mut areas = vec![Area {
        x: [x0, x1],
        y: [y_min, y_min + front_fraction * (y_max - y_min)],
    }];
    let (cx, cy) = (rng.uniform_f32(-0.02, 0.02), rng.uniform_f32(-0.02, 0.02));
    let mut mount_y = rng.uniform_f32(0.9, 0.94);
    if side {
        let xs0 = x0 - rng.uniform_f32(0.0, 1.375);
        let ys1 = rng.uniform_f32(-0.325, -0.275);
        if x0 - xs0 > 0.01 {
            prims.push(table([xs0, x0], [y_min, ys1]));
            let f = rng.uniform_f32(0.55, 0.65);
            areas.push(Area {
                x: [x0 - f * (x0 - xs0), x0],
                y: [y_min, ys1],
            });
            mount_y = 2.0 * (cy - ys1);
        }
    }
    prims.push(Primitive::Cuboid {
        center: [cx, cy, -0.01],
        dims: [2.0 * (x0 - cx), mount_y, 0.02],
        quaternion: [1.0, 0.0, 0.0, 0.0],
    });

    // Objects: candidates uniform over the task areas (area-weighted), kept 5 cm clear.
    let count = 3 + rng.below(12) as usize;
    let total: f32 = areas.iter().map(Area::size).sum();
    let mut placed: Vec<([f32; 2], f32)> = Vec::new();
    for _ in 0..10 * count {
        if placed.len() >= count {
            break;
        }
        let mut pick = rng.uniform_f32(0.0, total);
        let area = areas.iter().find(|a| {
            pick -= a.size();
            pick <= 0.0
        });
        let Some(area) = area.or(areas.last()) else { break };
        let c = [
            rng.uniform_f32(area.x[0], area.x[1]),
            rng.uniform_f32(area.y[0], area.y[1]),
        ];
        let d = placed
            .iter()
            .map(|(p, r)| ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)).sqrt() - r)
            .fold(f32::INFINITY, f32::min);
        let limit = d.min(0.15);
        if d <= 0.05 || limit <= 0.05 {
            continue;
        }
        let height = rng.uniform_f32(0.05, 0.35);
        let center = [c[0], c[1], h + height / 2.0];
        if rng.unit_f32() < 0.3 {
            let radius = rng.uniform_f32(0.05, limit);
            prims.push(Primitive::Cylinder {
                center,
                radius,
                height,
                quaternion: [1.0, 0.0, 0.0, 0.0],
            });
            placed.push((c, radius));
        } else {
            let (dx, dy) = (rng.uniform_f32(0.05, limit), rng.uniform_f32(0.05, limit));
            let yaw = rng.uniform_f32(0.0, core::f32::consts::FRAC_PI_2);
            prims.push(Primitive::Cuboid {
                center,
                dims: [dx, dy, height],
                quaternion: yaw_quaternion(yaw),
            });
            placed.push((c, 0.5 * (dx * dx + dy * dy).sqrt()));
        }
    }

    // Gripper targets 1-12 cm above the task areas, within reach.
    let regions = areas
        .iter()
        .filter_map(|a| {
            let x = [a.x[0], a.x[1].min(REACH)];
            let y = [a.y[0].max(-REACH), a.y[1].min(REACH)];
            (x[1] > x[0] && y[1] > y[0]).then(|| Region {
                center: [(x[0] + x[1]) / 2.0, (y[0] + y[1]) / 2.0, h + 0.065],
                half: [(x[1] - x[0]) / 2.0, (y[1] - y[0]) / 2.0, 0.055],
                yaw: 0.0,
                approach: Approach::RoughlyDown,
            })
        })
        .collect();
    Environment {
        prims,
        regions,
        goals: Vec::new(),
    }
}
