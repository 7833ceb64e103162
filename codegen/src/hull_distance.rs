//! Distance between the convex hulls of two point sets: GJK in f64 (build time only).
//!
//! The self-collision rule [`crate::arms::PairRule::ApartAtZero`] asks whether two links'
//! convex pieces touch at the all-zero configuration. GJK walks the Minkowski difference
//! `A ⊖ B` through its support points and keeps a simplex (up to four of them) whose closest
//! point to the origin approaches the hulls' distance. The closest point of a simplex is found
//! by trying every face of it (at most 15) and keeping the nearest projection that falls
//! inside its face: slow but plain, and the simplices are tiny.

use crate::math::Vec3;

/// Stops when a step improves the squared distance by less than this fraction of it.
const RELATIVE_EPS: f64 = 1e-12;
/// Below this distance (metres) the hulls count as overlapping: distance 0.
const OVERLAP_EPS: f64 = 1e-12;
/// Enough for any pair of meshes: each step adds a new support point or stops.
const MAX_ITERATIONS: usize = 200;

fn sub(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: &Vec3, b: &Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The point of `points` farthest along `d` (first one on ties).
fn support(points: &[Vec3], d: &Vec3) -> Vec3 {
    let mut best = points[0];
    let mut best_dot = dot(&best, d);
    for p in &points[1..] {
        let v = dot(p, d);
        if v > best_dot {
            best = *p;
            best_dot = v;
        }
    }
    best
}

/// Distance between the convex hulls of `a` and `b` (0 when they touch or overlap); `None` if
/// either set is empty or a coordinate is not finite.
pub fn hull_distance(a: &[Vec3], b: &[Vec3]) -> Option<f64> {
    if a.is_empty() || b.is_empty() || a.iter().chain(b).flatten().any(|x| !x.is_finite()) {
        return None;
    }
    // Support of A ⊖ B along d: farthest of A along d minus farthest of B along −d.
    let support_difference = |d: &Vec3| sub(&support(a, d), &support(b, &d.map(|x| -x)));
    let mut simplex = vec![sub(&a[0], &b[0])];
    let mut v = simplex[0];
    for _ in 0..MAX_ITERATIONS {
        let vv = dot(&v, &v);
        if vv.sqrt() <= OVERLAP_EPS {
            return Some(0.0);
        }
        let w = support_difference(&v.map(|x| -x));
        // `v·v − v·w` bounds how much closer the hull can come: stop when it is negligible.
        if vv - dot(&v, &w) <= RELATIVE_EPS * vv || simplex.contains(&w) {
            return Some(vv.sqrt());
        }
        simplex.push(w);
        match closest_on_simplex(&simplex) {
            Some((point, kept)) => {
                if kept.len() == 4 {
                    // The origin is inside the tetrahedron: the hulls overlap.
                    return Some(0.0);
                }
                simplex = kept;
                v = point;
            }
            None => return Some(vv.sqrt()),
        }
    }
    Some(dot(&v, &v).sqrt())
}

/// The point of the simplex's hull nearest the origin and the vertices of the face it lies in
/// (the smallest such face). `None` if no face gives a valid projection (numerically
/// degenerate input).
fn closest_on_simplex(simplex: &[Vec3]) -> Option<(Vec3, Vec<Vec3>)> {
    let n = simplex.len();
    let mut best: Option<(f64, Vec3, Vec<Vec3>)> = None;
    for mask in 1u32..(1 << n) {
        let face: Vec<Vec3> = (0..n).filter(|i| mask >> i & 1 == 1).map(|i| simplex[i]).collect();
        let Some(weights) = affine_projection(&face) else {
            continue;
        };
        if weights.iter().any(|&w| w <= 0.0) {
            continue;
        }
        let mut point = [0.0; 3];
        for (p, w) in face.iter().zip(&weights) {
            for k in 0..3 {
                point[k] += w * p[k];
            }
        }
        let d = dot(&point, &point);
        let better = match &best {
            None => true,
            Some((bd, _, bf)) => d < *bd || (d == *bd && face.len() < bf.len()),
        };
        if better {
            best = Some((d, point, face));
        }
    }
    best.map(|(_, point, face)| (point, face))
}

/// Barycentric weights of the origin's projection onto the affine hull of `face` (1 to 4
/// points); `None` if the points are affinely dependent.
fn affine_projection(face: &[Vec3]) -> Option<Vec<f64>> {
    let m = face.len() - 1;
    if m == 0 {
        return Some(vec![1.0]);
    }
    // Minimise |p0 + Σ μ_i e_i|² with e_i = p_i − p0: the normal equations G μ = −Eᵀ p0.
    let e: Vec<Vec3> = face[1..].iter().map(|p| sub(p, &face[0])).collect();
    let mut g = vec![vec![0.0; m + 1]; m];
    let scale = e.iter().map(|x| dot(x, x)).fold(0.0, f64::max);
    for i in 0..m {
        for j in 0..m {
            g[i][j] = dot(&e[i], &e[j]);
        }
        g[i][m] = -dot(&e[i], &face[0]);
    }
    // Gaussian elimination with partial pivoting on the augmented matrix.
    for col in 0..m {
        let pivot = (col..m).max_by(|&r, &s| g[r][col].abs().total_cmp(&g[s][col].abs()))?;
        if g[pivot][col].abs() <= 1e-14 * scale || scale == 0.0 {
            return None;
        }
        g.swap(col, pivot);
        let pivot_row = g[col].clone();
        for (r, row) in g.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / pivot_row[col];
                for (x, p) in row.iter_mut().zip(&pivot_row).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    let mu: Vec<f64> = (0..m).map(|i| g[i][m] / g[i][i]).collect();
    let mut weights = vec![1.0 - mu.iter().sum::<f64>()];
    weights.extend(mu);
    Some(weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(min: Vec3, size: f64) -> Vec<Vec3> {
        (0..8)
            .map(|i| [0, 1, 2].map(|k| min[k] + if i >> k & 1 == 1 { size } else { 0.0 }))
            .collect()
    }

    #[test]
    fn unit_cubes_apart_touching_and_overlapping() {
        let a = cube([0.0; 3], 1.0);
        let apart = hull_distance(&a, &cube([2.5, 0.0, 0.0], 1.0)).unwrap();
        assert!((apart - 1.5).abs() < 1e-12, "{apart}");
        // Edge to edge across a diagonal gap: √(0.5² + 0.5²).
        let diagonal = hull_distance(&a, &cube([1.5, 1.5, 0.2], 1.0)).unwrap();
        assert!((diagonal - 0.5f64.hypot(0.5)).abs() < 1e-12, "{diagonal}");
        // Corner to corner.
        let corner = hull_distance(&a, &cube([2.0, 2.0, 2.0], 1.0)).unwrap();
        assert!((corner - 3f64.sqrt()).abs() < 1e-12, "{corner}");
        assert_eq!(hull_distance(&a, &cube([1.0, 0.3, -0.2], 1.0)), Some(0.0));
        assert_eq!(hull_distance(&a, &cube([0.5, 0.5, 0.5], 1.0)), Some(0.0));
        assert_eq!(hull_distance(&a, &cube([0.25, 0.25, 0.25], 0.5)), Some(0.0));
    }

    #[test]
    fn tetrahedron_against_a_point() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        // Above the slanted face x + y + z = 1: distance (3·0.5 − 1)/√3 along its normal.
        let d = hull_distance(&t, &[[0.5, 0.5, 0.5]]).unwrap();
        assert!((d - 0.5 / 3f64.sqrt()).abs() < 1e-12, "{d}");
        // Beside an edge, beyond a vertex, inside.
        let d = hull_distance(&t, &[[-1.0, -1.0, 0.5]]).unwrap();
        assert!((d - 2f64.sqrt()).abs() < 1e-12, "{d}");
        let d = hull_distance(&t, &[[3.0, 0.0, 0.0]]).unwrap();
        assert!((d - 2.0).abs() < 1e-12, "{d}");
        assert_eq!(hull_distance(&t, &[[0.1, 0.1, 0.1]]), Some(0.0));
        assert_eq!(hull_distance(&[[0.1, 0.1, 0.1]], &t), Some(0.0));
    }

    #[test]
    fn refuses_empty_and_non_finite_sets() {
        assert_eq!(hull_distance(&[], &[[0.0; 3]]), None);
        assert_eq!(hull_distance(&[[f64::NAN, 0.0, 0.0]], &[[0.0; 3]]), None);
    }
}
