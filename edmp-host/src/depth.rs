//! Depth images to world points: the one back-projection behind `edmp.points_from_depth`
//! (docs/python.md), whose result becomes a `points` obstacle of `edmp-scene/1`.
//!
//! Conventions are OpenCV's. The camera frame has x right, y down and z forward (the optical
//! axis). A pixel is addressed `(u, v)`: `u` the column (0 at the left), `v` the row (0 at
//! the top), and the integer coordinates are the pixel *centres* (the centre of the top-left
//! pixel is `(0, 0)`, its area spans `[-0.5, 0.5]²`), so `cx = (width - 1) / 2` puts the
//! principal point at the image's centre. The depth of a pixel is its point's z in the camera
//! frame (a z-buffer, as RGB-D cameras and OpenCV's `rgbd` module give it), not the length of
//! its ray. With `K = [[fx, s, cx], [0, fy, cy], [0, 0, 1]]` the point of pixel `(u, v)` at
//! depth `d` is `d · K⁻¹ · [u, v, 1]`:
//!
//! ```text
//! y = d · (v − cy) / fy
//! x = (d · (u − cx) − s · y) / fx
//! z = d
//! ```
//!
//! and in the world `pose · [x, y, z, 1]`, `pose` being the camera's frame in the world
//! (camera → world). Pixels with no return (a depth of 0, negative, NaN or infinite) and those
//! beyond `max_depth` are dropped; the others are kept in row-major order (row 0 first).

use core::fmt::Write as _;

/// How far `RᵀR` of the pose's rotation may be from the identity (each entry), and its bottom
/// row from `[0, 0, 0, 1]`.
pub const ORTHONORMAL_TOLERANCE: f64 = 1e-4;

/// The world points of a `width × height` depth image (metres, row-major: `depth[v * width +
/// u]`) seen by a pinhole camera with intrinsics `k` (OpenCV's `K`) at `pose` (camera →
/// world, a homogeneous matrix): see the module's conventions. Errors name the argument:
/// `depth` (size ≠ `width × height`), `K` (not finite, not `[[fx, s, cx], [0, fy, cy], [0, 0,
/// 1]]`, or a focal length ≤ 0), `pose` (not finite, bottom row not `[0, 0, 0, 1]`, rotation
/// not orthonormal within [`ORTHONORMAL_TOLERANCE`] or a reflection), `max_depth` (not
/// positive), or a point beyond the range of `f32`.
pub fn points_from_depth(
    depth: &[f32],
    width: usize,
    height: usize,
    k: [[f64; 3]; 3],
    pose: [[f64; 4]; 4],
    max_depth: Option<f32>,
) -> Result<Vec<[f32; 3]>, String> {
    let pixels = width
        .checked_mul(height)
        .ok_or_else(|| format!("depth: {width} × {height} pixels overflow"))?;
    if depth.len() != pixels {
        return Err(format!(
            "depth: {} values for a {width} × {height} image (expected {pixels})",
            depth.len()
        ));
    }
    check_intrinsics(&k)?;
    check_pose(&pose)?;
    let limit = match max_depth {
        None => f32::INFINITY,
        Some(m) if m > 0.0 => m,
        Some(m) => return Err(format!("max_depth: {m} is not positive")),
    };
    let [[fx, s, cx], [_, fy, cy], _] = k;
    let mut out = Vec::new();
    for (v, row) in depth.chunks_exact(width.max(1)).enumerate() {
        let rv = (v as f64 - cy) / fy;
        for (u, &d) in row.iter().enumerate() {
            if !(d.is_finite() && d > 0.0 && d <= limit) {
                continue;
            }
            let z = f64::from(d);
            let y = z * rv;
            let x = (z * (u as f64 - cx) - s * y) / fx;
            let mut w = [0.0f32; 3];
            for (i, slot) in w.iter_mut().enumerate() {
                let r = pose[i];
                let c = r[0] * x + r[1] * y + r[2] * z + r[3];
                *slot = c as f32;
                if !slot.is_finite() {
                    return Err(format!(
                        "depth: pixel (u {u}, v {v}) at {d} m lands at a coordinate {c:e} beyond f32"
                    ));
                }
            }
            out.push(w);
        }
    }
    Ok(out)
}

/// [`points_from_depth`] on the Python package's wire: the image as little-endian `f32` bytes
/// (numpy's `astype('<f4').tobytes()`), the points back as little-endian `f32` bytes, `x, y,
/// z` per point (for `numpy.frombuffer`).
pub fn points_from_depth_le_bytes(
    depth: &[u8],
    width: usize,
    height: usize,
    k: [[f64; 3]; 3],
    pose: [[f64; 4]; 4],
    max_depth: Option<f32>,
) -> Result<Vec<u8>, String> {
    if !depth.len().is_multiple_of(4) {
        return Err(format!(
            "depth: {} bytes, not a whole number of f32 values",
            depth.len()
        ));
    }
    let image: Vec<f32> = depth
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let points = points_from_depth(&image, width, height, k, pose, max_depth)?;
    let mut out = Vec::with_capacity(points.len() * 12);
    for c in points.iter().flatten() {
        out.extend_from_slice(&c.to_le_bytes());
    }
    Ok(out)
}

fn check_intrinsics(k: &[[f64; 3]; 3]) -> Result<(), String> {
    if k.iter().flatten().any(|x| !x.is_finite()) {
        return Err(format!("K: not finite: {}", show(k.iter().map(|r| &r[..]))));
    }
    let [[fx, _, _], [k10, fy, _], bottom] = *k;
    if k10 != 0.0 || bottom != [0.0, 0.0, 1.0] {
        return Err(format!(
            "K: expected a pinhole matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]], found {}",
            show(k.iter().map(|r| &r[..]))
        ));
    }
    if fx <= 0.0 || fy <= 0.0 {
        return Err(format!(
            "K: focal lengths must be positive (fx = {fx}, fy = {fy}): K is not invertible or flips the image"
        ));
    }
    Ok(())
}

fn check_pose(pose: &[[f64; 4]; 4]) -> Result<(), String> {
    if pose.iter().flatten().any(|x| !x.is_finite()) {
        return Err(format!("pose: not finite: {}", show(pose.iter().map(|r| &r[..]))));
    }
    let bottom = pose[3];
    if bottom
        .iter()
        .zip([0.0, 0.0, 0.0, 1.0])
        .any(|(a, b)| (a - b).abs() > ORTHONORMAL_TOLERANCE)
    {
        return Err(format!("pose: bottom row {bottom:?}, expected [0, 0, 0, 1]"));
    }
    let mut worst = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|r| pose[r][i] * pose[r][j]).sum();
            let expected = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((dot - expected).abs());
        }
    }
    if worst > ORTHONORMAL_TOLERANCE {
        return Err(format!(
            "pose: the rotation (upper-left 3 × 3) is not orthonormal: RᵀR is {worst:.2e} from the identity (tolerance {ORTHONORMAL_TOLERANCE:e})"
        ));
    }
    let r = |i: usize, j: usize| pose[i][j];
    let det = r(0, 0) * (r(1, 1) * r(2, 2) - r(1, 2) * r(2, 1)) - r(0, 1) * (r(1, 0) * r(2, 2) - r(1, 2) * r(2, 0))
        + r(0, 2) * (r(1, 0) * r(2, 1) - r(1, 1) * r(2, 0));
    if det < 0.0 {
        return Err("pose: the rotation is a reflection (determinant −1), expected a proper rotation".into());
    }
    Ok(())
}

fn show<'a>(rows: impl Iterator<Item = &'a [f64]>) -> String {
    let mut s = String::from("[");
    for (i, row) in rows.enumerate() {
        let _ = write!(s, "{}{row:?}", if i == 0 { "" } else { ", " });
    }
    s.push(']');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITY: [[f64; 4]; 4] = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];

    fn k(fx: f64, fy: f64, cx: f64, cy: f64) -> [[f64; 3]; 3] {
        [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]
    }

    fn close(a: [f32; 3], b: [f64; 3]) {
        for (x, y) in a.iter().zip(b) {
            assert!((f64::from(*x) - y).abs() < 1e-6, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn a_plane_at_one_metre_lands_on_z_one_with_pixel_centres_at_integers() {
        let (w, h) = (64, 48);
        let (fx, fy, cx, cy) = (50.0, 40.0, 31.5, 23.5);
        let depth = vec![1.0f32; w * h];
        let pts = points_from_depth(&depth, w, h, k(fx, fy, cx, cy), IDENTITY, None).unwrap();
        assert_eq!(pts.len(), w * h);
        for (i, p) in pts.iter().enumerate() {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            close(*p, [(u - cx) / fx, (v - cy) / fy, 1.0]);
        }
        // Row-major from the top-left pixel: x grows right, y grows down.
        close(pts[0], [-31.5 / 50.0, -23.5 / 40.0, 1.0]);
        close(pts[w * h - 1], [31.5 / 50.0, 23.5 / 40.0, 1.0]);
        // With cx, cy the image's centre the cloud is symmetric about the optical axis.
        let mean: f64 = pts.iter().map(|p| f64::from(p[0])).sum::<f64>() / pts.len() as f64;
        assert!(mean.abs() < 1e-6);
    }

    #[test]
    fn depth_scales_the_ray_and_skew_shears_x() {
        let mut kk = k(100.0, 100.0, 0.0, 0.0);
        kk[0][1] = 10.0;
        let pts = points_from_depth(&[2.0, 2.0, 2.0, 2.0], 2, 2, kk, IDENTITY, None).unwrap();
        // Pixel (1, 1) at 2 m: y = 2 · 1 / 100, x = (2 · 1 − 10 · y) / 100.
        close(pts[3], [(2.0 - 10.0 * 0.02) / 100.0, 0.02, 2.0]);
        close(pts[1], [0.02, 0.0, 2.0]);
    }

    #[test]
    fn the_pose_rotates_and_translates_into_the_world() {
        // A camera at (1, 2, 3) looking down the world's −z, its x along world x (so its y,
        // down in the image, is world −y): rotation diag(1, −1, −1).
        let pose = [
            [1.0, 0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0, 2.0],
            [0.0, 0.0, -1.0, 3.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let pts = points_from_depth(&[0.5; 4], 2, 2, k(10.0, 10.0, 0.0, 0.0), pose, None).unwrap();
        close(pts[0], [1.0, 2.0, 2.5]);
        close(pts[3], [1.05, 1.95, 2.5]);
        // A quarter turn about world z after the translation: camera x → world y.
        let (c, s) = (0.0f64, 1.0f64);
        let turn = [
            [c, -s, 0.0, 0.1],
            [s, c, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let pts = points_from_depth(&[1.0], 1, 1, k(1.0, 1.0, -1.0, 0.0), turn, None).unwrap();
        close(pts[0], [0.1, 1.0, 1.0]);
    }

    #[test]
    fn no_returns_and_far_pixels_are_dropped() {
        let depth = [0.0, f32::NAN, f32::INFINITY, -1.0, 1.0, 3.0];
        let pts = points_from_depth(&depth, 3, 2, k(1.0, 1.0, 0.0, 0.0), IDENTITY, Some(2.0)).unwrap();
        assert_eq!(pts.len(), 1);
        close(pts[0], [1.0, 1.0, 1.0]);
        let all = points_from_depth(&depth, 3, 2, k(1.0, 1.0, 0.0, 0.0), IDENTITY, None).unwrap();
        assert_eq!(all.len(), 2);
        assert!(
            points_from_depth(&[], 0, 0, k(1.0, 1.0, 0.0, 0.0), IDENTITY, None)
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn the_byte_wire_is_little_endian_f32() {
        let depth: Vec<u8> = [1.0f32, 2.0, 0.0].iter().flat_map(|d| d.to_le_bytes()).collect();
        let bytes = points_from_depth_le_bytes(&depth, 3, 1, k(1.0, 1.0, 0.0, 0.0), IDENTITY, None).unwrap();
        let got: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(got, [0.0, 0.0, 1.0, 2.0, 0.0, 2.0]);
        let odd = points_from_depth_le_bytes(&depth[..5], 1, 1, k(1.0, 1.0, 0.0, 0.0), IDENTITY, None);
        assert_eq!(odd.unwrap_err(), "depth: 5 bytes, not a whole number of f32 values");
    }

    #[test]
    fn bad_input_is_an_error_naming_the_argument() {
        let ok = k(1.0, 1.0, 0.0, 0.0);
        let err = |d: &[f32], w, h, kk, pose, m| points_from_depth(d, w, h, kk, pose, m).unwrap_err();
        assert!(err(&[1.0; 5], 2, 3, ok, IDENTITY, None).starts_with("depth: 5 values for a 2 × 3 image"));
        assert!(err(&[1.0], 1, 1, k(0.0, 1.0, 0.0, 0.0), IDENTITY, None).starts_with("K: focal lengths"));
        assert!(err(&[1.0], 1, 1, k(1.0, -1.0, 0.0, 0.0), IDENTITY, None).starts_with("K: focal lengths"));
        assert!(err(&[1.0], 1, 1, k(f64::NAN, 1.0, 0.0, 0.0), IDENTITY, None).starts_with("K: not finite"));
        let mut projective = ok;
        projective[2] = [0.1, 0.0, 1.0];
        assert!(err(&[1.0], 1, 1, projective, IDENTITY, None).starts_with("K: expected a pinhole"));
        let mut scaled = IDENTITY;
        scaled[0][0] = 1.001;
        assert!(err(&[1.0], 1, 1, ok, scaled, None).contains("not orthonormal"));
        // Within the tolerance: accepted.
        scaled[0][0] = 1.00002;
        assert!(points_from_depth(&[1.0], 1, 1, ok, scaled, None).is_ok());
        let mut mirrored = IDENTITY;
        mirrored[2][2] = -1.0;
        mirrored[1][1] = -1.0;
        mirrored[0][0] = -1.0;
        assert!(err(&[1.0], 1, 1, ok, mirrored, None).starts_with("pose: the rotation is a reflection"));
        let mut projective_pose = IDENTITY;
        projective_pose[3][0] = 0.5;
        assert!(err(&[1.0], 1, 1, ok, projective_pose, None).starts_with("pose: bottom row"));
        let mut nan_pose = IDENTITY;
        nan_pose[0][3] = f64::INFINITY;
        assert!(err(&[1.0], 1, 1, ok, nan_pose, None).starts_with("pose: not finite"));
        assert!(err(&[1.0], 1, 1, ok, IDENTITY, Some(0.0)).starts_with("max_depth: 0 is not positive"));
        assert!(err(&[1.0], 1, 1, ok, IDENTITY, Some(f32::NAN)).starts_with("max_depth: NaN"));
        assert!(err(&[1.0], 1, 1, k(1e-40, 1.0, -1.0, 0.0), IDENTITY, None).contains("beyond f32"));
    }
}
