//! A cloud made small enough to hold: [`reduce`] keeps every point while they fit; beyond the
//! capacity it replaces the points of each cell of a grid by one ball at the cell's centre,
//! grown by the cell's half diagonal, so the reduced balls still cover every input ball
//! (conservative, never truncated).

use crate::surface::element::SurfaceError;

/// How a cloud was held: the points kept and the radius of their balls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reduced {
    /// Points now at the front of the buffer.
    pub points: usize,
    /// The ball radius that covers the input (the input's when nothing was reduced).
    pub radius: f32,
    /// The grid cell used (0 when nothing was reduced).
    pub cell: f32,
}

/// Grid cells tried before giving up: the cell doubles each time from the ball radius.
const ATTEMPTS: u32 = 24;

fn cell_key(p: &[f32; 3], cell: f32) -> [i64; 3] {
    p.map(|x| libm::floorf(x / cell) as i64)
}

/// Brings `points` down to at most `capacity` balls covering the input balls of `radius`;
/// the kept points are moved to the front. Refuses non-finite input.
pub fn reduce(points: &mut [[f32; 3]], radius: f32, capacity: usize) -> Result<Reduced, SurfaceError> {
    if !(radius.is_finite()) {
        return Err(SurfaceError::NonFinite);
    }
    if radius <= 0.0 {
        return Err(SurfaceError::NonPositiveRadius);
    }
    if points.iter().flatten().any(|x| !x.is_finite()) {
        return Err(SurfaceError::NonFinite);
    }
    if points.len() <= capacity {
        return Ok(Reduced {
            points: points.len(),
            radius,
            cell: 0.0,
        });
    }
    if capacity == 0 {
        return Err(SurfaceError::TooManyPieces);
    }
    let mut cell = radius;
    for _ in 0..ATTEMPTS {
        points.sort_unstable_by(|a, b| {
            cell_key(a, cell)
                .cmp(&cell_key(b, cell))
                .then(a.map(f32::to_bits).cmp(&b.map(f32::to_bits)))
        });
        let mut cells = 0usize;
        let mut last: Option<[i64; 3]> = None;
        for p in points.iter() {
            let k = cell_key(p, cell);
            if last != Some(k) {
                cells += 1;
                last = Some(k);
            }
        }
        if cells <= capacity {
            let mut kept = 0usize;
            let mut last: Option<[i64; 3]> = None;
            for i in 0..points.len() {
                let Some(&p) = points.get(i) else { break };
                let k = cell_key(&p, cell);
                if last != Some(k) {
                    last = Some(k);
                    if let Some(slot) = points.get_mut(kept) {
                        *slot = k.map(|c| (c as f32 + 0.5) * cell);
                    }
                    kept += 1;
                }
            }
            // The half diagonal, rounded up, and the centre's own rounding.
            let grow = cell * 0.866_026 * (1.0 + 1e-5) + cell * 1e-6;
            return Ok(Reduced {
                points: kept,
                radius: radius + grow,
                cell,
            });
        }
        cell *= 2.0;
    }
    Err(SurfaceError::TooManyPieces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use std::vec::Vec;

    #[test]
    fn reduction_covers_every_input_ball() {
        let input: Vec<[f32; 3]> = (0..20_000)
            .map(|i| {
                let f = i as f32;
                [libm::sinf(f) * 0.4 + 0.5, libm::cosf(f * 0.7) * 0.4, (f * 0.001) % 0.6]
            })
            .collect();
        let mut points = input.clone();
        let r = reduce(&mut points, 0.0075, 2000).unwrap();
        assert!(r.points <= 2000 && r.cell > 0.0 && r.radius > 0.0075);
        let kept = &points[..r.points];
        for p in &input {
            let v = Vector3::from(*p);
            let covered = kept.iter().any(|c| (Vector3::from(*c) - v).norm() + 0.0075 <= r.radius);
            assert!(covered, "{p:?}");
        }
        let mut few = input[..100].to_vec();
        assert_eq!(reduce(&mut few, 0.0075, 100).unwrap().points, 100);
        assert_eq!(few, input[..100]);
        assert_eq!(reduce(&mut few, 0.0, 10), Err(SurfaceError::NonPositiveRadius));
    }
}
