//! Small f64 linear algebra for the generator (build time only, so plain arrays are enough).

/// A 3×3 matrix, row major.
pub type Mat3 = [[f64; 3]; 3];
/// A 3-vector.
pub type Vec3 = [f64; 3];

/// The identity matrix.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// `a · b`.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

/// `m · v`.
pub fn mul_vec(m: &Mat3, v: &Vec3) -> Vec3 {
    [0, 1, 2].map(|i| (0..3).map(|k| m[i][k] * v[k]).sum())
}

/// `mᵀ`.
pub fn transpose(m: &Mat3) -> Mat3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[j][i]))
}

/// `a + b`.
pub fn add(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// The URDF `rpy` convention: fixed-axis roll about x, then pitch about y, then yaw about z,
/// so `R = Rz(yaw) · Ry(pitch) · Rx(roll)`.
pub fn rpy_to_matrix(rpy: &Vec3) -> Mat3 {
    let (sr, cr) = rpy[0].sin_cos();
    let (sp, cp) = rpy[1].sin_cos();
    let (sy, cy) = rpy[2].sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]];
    let ry = [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]];
    let rz = [[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]];
    mul(&rz, &mul(&ry, &rx))
}

/// Rotation by `angle` about the unit axis `a` (Rodrigues).
pub fn axis_angle(a: &Vec3, angle: f64) -> Mat3 {
    let (s, c) = angle.sin_cos();
    let k = cross_matrix(a);
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            r[i][j] = c * id + s * k[i][j] + (1.0 - c) * a[i] * a[j];
        }
    }
    r
}

/// The matrix `[a]×` with `[a]× v = a × v`.
pub fn cross_matrix(a: &Vec3) -> Mat3 {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}

/// Euclidean norm.
pub fn norm(a: &Vec3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Determinant.
pub fn det(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Eigenvectors (as columns) of a symmetric matrix by cyclic Jacobi rotations.
pub fn symmetric_eigenvectors(m: &Mat3) -> Mat3 {
    let mut a = *m;
    let mut v = IDENTITY;
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-18 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            let mut j = IDENTITY;
            j[p][p] = c;
            j[q][q] = c;
            j[p][q] = s;
            j[q][p] = -s;
            a = mul(&transpose(&j), &mul(&a, &j));
            v = mul(&v, &j);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_quarter_turns() {
        let r = rpy_to_matrix(&[core::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        // Roll +90°: y goes to z.
        let y = mul_vec(&r, &[0.0, 1.0, 0.0]);
        assert!((y[2] - 1.0).abs() < 1e-12 && y[1].abs() < 1e-12);
        let r = rpy_to_matrix(&[0.0, 0.0, core::f64::consts::FRAC_PI_2]);
        let x = mul_vec(&r, &[1.0, 0.0, 0.0]);
        assert!((x[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn jacobi_diagonalises() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1.0]];
        let v = symmetric_eigenvectors(&m);
        let d = mul(&transpose(&v), &mul(&m, &v));
        assert!(d[0][1].abs() + d[0][2].abs() + d[1][2].abs() < 1e-9);
        assert!((det(&v).abs() - 1.0).abs() < 1e-9);
    }
}
