//! Collision meshes: read the vertices of a Wavefront `.obj` (per convex piece) or an `.stl`, and
//! fit a tight oriented box.
//!
//! The box is what the costs of EDMP use for a robot body. The original takes the mesh's
//! axis-aligned box in the link frame; we search over orientations for the smallest volume
//! that still holds every vertex, which is never larger and often much smaller.

use crate::math::{self, Mat3, Vec3};
use std::path::Path;

/// An oriented box in some frame: `point = center + rotation · (s ⊙ half_extents)`, `|s_i| ≤ 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientedBox {
    /// Centre of the box.
    pub center: Vec3,
    /// Columns are the box's axes.
    pub rotation: Mat3,
    /// Half of the full extent along each box axis.
    pub half_extents: Vec3,
}

impl OrientedBox {
    /// Volume of the box.
    pub fn volume(&self) -> f64 {
        8.0 * self.half_extents[0] * self.half_extents[1] * self.half_extents[2]
    }
}

/// Reads the `v x y z` lines of an `.obj` file (other records are ignored).
pub fn read_obj_vertices(path: &Path) -> Result<Vec<Vec3>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse_obj_vertices(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses the vertex records of `.obj` text.
pub fn parse_obj_vertices(text: &str) -> Result<Vec<Vec3>, String> {
    let mut vertices = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        vertices.push(parse_coordinates(words, line_no + 1)?);
    }
    at_least_four(vertices)
}

/// The three coordinates after a `v` (OBJ) or `vertex` (ASCII STL) keyword.
fn parse_coordinates<'a>(mut words: impl Iterator<Item = &'a str>, line_no: usize) -> Result<Vec3, String> {
    let mut v = [0.0f64; 3];
    for slot in &mut v {
        let word = words
            .next()
            .ok_or(format!("line {line_no}: vertex with fewer than 3 coordinates"))?;
        *slot = word.parse().map_err(|e| format!("line {line_no}: {e}"))?;
        if !slot.is_finite() {
            return Err(format!("line {line_no}: non-finite coordinate"));
        }
    }
    Ok(v)
}

/// A hull needs four points that are not coplanar; fewer is a broken mesh, not a body.
fn at_least_four(vertices: Vec<Vec3>) -> Result<Vec<Vec3>, String> {
    if vertices.len() < 4 {
        return Err(format!(
            "{} vertices; a collision mesh needs at least 4",
            vertices.len()
        ));
    }
    Ok(vertices)
}

/// Reads the convex pieces of a collision mesh, by extension: `.obj` ([`parse_obj_pieces`]) or
/// `.stl` ([`parse_stl_vertices`], one piece). PyBullet collides the convex hull of each piece.
pub fn read_mesh_pieces(path: &Path) -> Result<Vec<Vec<Vec3>>, String> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let pieces = match extension.as_str() {
        "obj" => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            parse_obj_pieces(&text)
        }
        "stl" => {
            let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
            parse_stl_vertices(&bytes).map(|v| vec![v])
        }
        _ => Err("collision meshes must be .obj or .stl".to_owned()),
    };
    pieces.map_err(|e| format!("{}: {e}", path.display()))
}

/// The vertices of `.obj` text, one list per convex piece: the `v` records split at each `o` or
/// `g` statement, empty runs dropped. V-HACD writes each piece as `o convex_k` followed by its
/// own vertices and faces, which is how PyBullet's OBJ loader splits them too (one convex hull
/// per shape). A file with one object, whether its statement comes before or after the
/// vertices (Blender's `g` after them), is one piece of every `v` record, as
/// [`parse_obj_vertices`] reads it.
pub fn parse_obj_pieces(text: &str) -> Result<Vec<Vec<Vec3>>, String> {
    let mut pieces: Vec<Vec<Vec3>> = vec![Vec::new()];
    for (line_no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let v = parse_coordinates(words, line_no + 1)?;
                if let Some(piece) = pieces.last_mut() {
                    piece.push(v);
                }
            }
            Some("o" | "g") if pieces.last().is_some_and(|p| !p.is_empty()) => pieces.push(Vec::new()),
            _ => {}
        }
    }
    pieces.retain(|p| !p.is_empty());
    if pieces.is_empty() {
        return Err("no vertices; a collision mesh needs at least 4".to_owned());
    }
    pieces
        .into_iter()
        .enumerate()
        .map(|(k, p)| at_least_four(p).map_err(|e| format!("piece {k}: {e}")))
        .collect()
}

/// The corner vertices of an `.stl` mesh, each triangle's three in file order (repeats kept, as
/// in an OBJ's records). Binary when the size is exactly 84 bytes plus 50 per triangle the
/// header claims (even if the header begins with `solid`), otherwise ASCII (`vertex x y z`).
pub fn parse_stl_vertices(bytes: &[u8]) -> Result<Vec<Vec3>, String> {
    let claimed = bytes
        .get(80..84)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize);
    let vertices = match claimed {
        Some(n) if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) => {
            let mut vertices = Vec::with_capacity(3 * n);
            for t in 0..n {
                // 12 bytes of normal, then three corners of three little-endian f32 each.
                for corner in 0..3 {
                    let at = 84 + 50 * t + 12 + 12 * corner;
                    let mut v = [0.0f64; 3];
                    for (k, slot) in v.iter_mut().enumerate() {
                        let b = &bytes[at + 4 * k..at + 4 * k + 4];
                        *slot = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                        if !slot.is_finite() {
                            return Err(format!("byte {}: non-finite coordinate", at + 4 * k));
                        }
                    }
                    vertices.push(v);
                }
            }
            vertices
        }
        _ => {
            let text = core::str::from_utf8(bytes)
                .map_err(|_| "neither binary STL (size does not match the triangle count) nor ASCII".to_owned())?;
            if !text.trim_start().starts_with("solid") {
                return Err("neither binary STL (size does not match the triangle count) nor ASCII `solid`".to_owned());
            }
            let mut vertices = Vec::new();
            for (line_no, line) in text.lines().enumerate() {
                let mut words = line.split_whitespace();
                if words.next() == Some("vertex") {
                    vertices.push(parse_coordinates(words, line_no + 1)?);
                }
            }
            vertices
        }
    };
    at_least_four(vertices)
}

/// `points` without exact repeats, first occurrence kept (meshes repeat shared vertices).
pub fn distinct(points: &[Vec3]) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::new();
    for p in points {
        if !out.iter().any(|q| q == p) {
            out.push(*p);
        }
    }
    out
}

/// The vertices of the convex hull of `points`, in their original order: the rest lie inside
/// (or on a face, within 1e-12 m of its plane) and cannot change the hull, so the checker's
/// support function can skip them. Incremental construction in f64 (build time only).
pub fn hull_vertices(points: &[Vec3]) -> Vec<Vec3> {
    let faces = convex_hull(points);
    if faces.is_empty() {
        return points.to_vec();
    }
    let mut keep = vec![false; points.len()];
    for f in &faces {
        for &i in f {
            keep[i] = true;
        }
    }
    points.iter().zip(keep).filter(|(_, k)| *k).map(|(p, _)| *p).collect()
}

/// The edges of the convex hull of `points` (every one a hull vertex, as [`hull_vertices`]
/// keeps them) as each vertex's neighbours in ascending order, and the vertices farthest along
/// +x, −x, +y, −y, +z, −z (the first of equals): where a support query starts climbing
/// (`edmp_core::collision::convex::Hull`). `None` when some point is on no hull edge, so that a
/// climb could not reach it: the checker then scans every point.
pub fn hull_graph(points: &[Vec3]) -> Option<(Vec<Vec<usize>>, [usize; 6])> {
    let faces = convex_hull(points);
    let mut neighbours = vec![Vec::new(); points.len()];
    for f in &faces {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
    }
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    if neighbours.iter().any(|n| n.len() < 3) {
        return None;
    }
    let extreme = |axis: usize, sign: f64| {
        (0..points.len()).fold(0, |best, i| {
            if sign * points[i][axis] > sign * points[best][axis] {
                i
            } else {
                best
            }
        })
    };
    let seeds = [
        extreme(0, 1.0),
        extreme(0, -1.0),
        extreme(1, 1.0),
        extreme(1, -1.0),
        extreme(2, 1.0),
        extreme(2, -1.0),
    ];
    Some((neighbours, seeds))
}

const HULL_EPS: f64 = 1e-12;

fn sub(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: &Vec3, b: &Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: &Vec3, b: &Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Signed distance-like height of `p` above the plane of face `f` (outward positive).
fn height(points: &[Vec3], f: &[usize; 3], p: &Vec3) -> f64 {
    let n = cross(&sub(&points[f[1]], &points[f[0]]), &sub(&points[f[2]], &points[f[0]]));
    let len = math::norm(&n);
    if len == 0.0 {
        0.0
    } else {
        dot(&n, &sub(p, &points[f[0]])) / len
    }
}

/// Triangles (outward, counter-clockwise) of the hull; empty if the points are degenerate.
pub fn convex_hull(points: &[Vec3]) -> Vec<[usize; 3]> {
    if points.len() < 4 {
        return Vec::new();
    }
    // Initial tetrahedron from extreme points.
    let i0 = (0..points.len())
        .min_by(|&a, &b| points[a][0].total_cmp(&points[b][0]))
        .unwrap_or(0);
    let far = |from: &dyn Fn(usize) -> f64| {
        (0..points.len())
            .max_by(|&a, &b| from(a).total_cmp(&from(b)))
            .unwrap_or(0)
    };
    let i1 = far(&|i| math::norm(&sub(&points[i], &points[i0])));
    let line = sub(&points[i1], &points[i0]);
    let i2 = far(&|i| math::norm(&cross(&line, &sub(&points[i], &points[i0]))));
    let normal = cross(&line, &sub(&points[i2], &points[i0]));
    let i3 = far(&|i| dot(&normal, &sub(&points[i], &points[i0])).abs());
    if math::norm(&normal) == 0.0 || dot(&normal, &sub(&points[i3], &points[i0])).abs() < HULL_EPS {
        return Vec::new();
    }
    let mut faces: Vec<[usize; 3]> = vec![[i0, i1, i2], [i0, i3, i1], [i1, i3, i2], [i2, i3, i0]];
    // Orient outwards: the centroid of the tetrahedron must be below every face.
    let c = [0, 1, 2].map(|k| (points[i0][k] + points[i1][k] + points[i2][k] + points[i3][k]) / 4.0);
    for f in &mut faces {
        if height(points, f, &c) > 0.0 {
            f.swap(1, 2);
        }
    }
    for (i, p) in points.iter().enumerate() {
        if [i0, i1, i2, i3].contains(&i) {
            continue;
        }
        let visible: Vec<bool> = faces.iter().map(|f| height(points, f, p) > HULL_EPS).collect();
        if !visible.iter().any(|&v| v) {
            continue;
        }
        // Horizon: edges of visible faces whose twin belongs to a face that stays.
        let mut horizon = Vec::new();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, v)| **v) {
            for e in 0..3 {
                let (a, b) = (f[e], f[(e + 1) % 3]);
                let twin_visible = faces
                    .iter()
                    .zip(&visible)
                    .any(|(g, &v)| v && (0..3).any(|k| g[k] == b && g[(k + 1) % 3] == a));
                if !twin_visible {
                    horizon.push((a, b));
                }
            }
        }
        let mut kept: Vec<[usize; 3]> = faces
            .iter()
            .zip(&visible)
            .filter(|(_, v)| !**v)
            .map(|(f, _)| *f)
            .collect();
        kept.extend(horizon.into_iter().map(|(a, b)| [a, b, i]));
        faces = kept;
    }
    faces
}

/// The axis-aligned box of `points` (what the original EDMP uses).
pub fn aabb(points: &[Vec3]) -> OrientedBox {
    box_with_axes(points, &math::IDENTITY)
}

/// The smallest box with the given axes (columns of `rotation`) that holds every point.
pub fn box_with_axes(points: &[Vec3], rotation: &Mat3) -> OrientedBox {
    let rt = math::transpose(rotation);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        let local = math::mul_vec(&rt, p);
        for i in 0..3 {
            lo[i] = lo[i].min(local[i]);
            hi[i] = hi[i].max(local[i]);
        }
    }
    let mid = [0, 1, 2].map(|i| 0.5 * (lo[i] + hi[i]));
    OrientedBox {
        center: math::mul_vec(rotation, &mid),
        rotation: *rotation,
        half_extents: [0, 1, 2].map(|i| 0.5 * (hi[i] - lo[i])),
    }
}

/// A tight oriented box: a deterministic multi-start local search over orientations for the
/// smallest volume. Starts: the link-frame axes, the principal axes of the vertices, and turns
/// of the link frame about each axis in 10° steps. Never larger than [`aabb`].
pub fn tight_box(points: &[Vec3]) -> OrientedBox {
    let mut starts = vec![math::IDENTITY, principal_axes(points)];
    for axis in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        for k in 1..9 {
            starts.push(math::axis_angle(&axis, f64::from(k) * 10f64.to_radians()));
        }
    }
    let mut best = aabb(points);
    for start in starts {
        let candidate = refine(points, start);
        if candidate.volume() < best.volume() * (1.0 - 1e-12) {
            best = candidate;
        }
    }
    canonical(points, &best)
}

fn principal_axes(points: &[Vec3]) -> Mat3 {
    let n = points.len() as f64;
    let mean = [0, 1, 2].map(|i| points.iter().map(|p| p[i]).sum::<f64>() / n);
    let mut cov = [[0.0; 3]; 3];
    for p in points {
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += (p[i] - mean[i]) * (p[j] - mean[j]) / n;
            }
        }
    }
    let mut v = math::symmetric_eigenvectors(&cov);
    if math::det(&v) < 0.0 {
        for row in &mut v {
            row[2] = -row[2];
        }
    }
    v
}

/// Coordinate descent on small turns about the box's own axes, halving the step when stuck.
fn refine(points: &[Vec3], start: Mat3) -> OrientedBox {
    let mut best = box_with_axes(points, &start);
    let mut step = 0.1f64;
    while step > 1e-6 {
        let mut improved = false;
        for axis in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            for sign in [1.0, -1.0] {
                let turn = math::axis_angle(&axis, sign * step);
                let candidate = box_with_axes(points, &math::mul(&best.rotation, &turn));
                if candidate.volume() < best.volume() * (1.0 - 1e-12) {
                    best = candidate;
                    improved = true;
                }
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    best
}

/// Re-expresses the same box with its axes permuted and flipped to lie closest to the
/// frame's x, y, z (readable tables: a box that is an AABB gets the identity), right-handed.
fn canonical(points: &[Vec3], b: &OrientedBox) -> OrientedBox {
    let mut used = [false; 3];
    let mut columns = [[0.0; 3]; 3];
    for (frame_axis, column) in columns.iter_mut().enumerate() {
        let mut pick = 0;
        let mut pick_abs = -1.0;
        for (c, &taken) in used.iter().enumerate() {
            let v = b.rotation[frame_axis][c].abs();
            if !taken && v > pick_abs {
                pick = c;
                pick_abs = v;
            }
        }
        used[pick] = true;
        let sign = b.rotation[frame_axis][pick].signum();
        *column = [0, 1, 2].map(|r| sign * b.rotation[r][pick]);
    }
    let mut rotation = math::transpose(&columns);
    if math::det(&rotation) < 0.0 {
        for row in &mut rotation {
            row[2] = -row[2];
        }
    }
    box_with_axes(points, &orthonormalise(&rotation))
}

/// Gram-Schmidt on the columns, so accumulated turns stay a rotation to f64 precision.
fn orthonormalise(m: &Mat3) -> Mat3 {
    let col = |j: usize| [m[0][j], m[1][j], m[2][j]];
    let unit = |v: Vec3| {
        let n = math::norm(&v);
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let dot = |a: &Vec3, b: &Vec3| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let x = unit(col(0));
    let y0 = col(1);
    let d = dot(&x, &y0);
    let y = unit([y0[0] - d * x[0], y0[1] - d * x[1], y0[2] - d * x[2]]);
    let z = [
        x[1] * y[2] - x[2] * y[1],
        x[2] * y[0] - x[0] * y[2],
        x[0] * y[1] - x[1] * y[0],
    ];
    math::transpose(&[x, y, z])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_corners(rotation: &Mat3, half: Vec3, center: Vec3) -> Vec<Vec3> {
        let mut out = Vec::new();
        for i in 0..8 {
            let s = [0, 1, 2].map(|k| if i >> k & 1 == 1 { 1.0 } else { -1.0 });
            let local = [0, 1, 2].map(|k| s[k] * half[k]);
            out.push(math::add(&center, &math::mul_vec(rotation, &local)));
        }
        out
    }

    #[test]
    fn recovers_a_rotated_box() {
        let r = math::mul(
            &math::axis_angle(&[0.0, 0.0, 1.0], 0.3),
            &math::axis_angle(&[1.0, 0.0, 0.0], 0.2),
        );
        let pts = cube_corners(&r, [0.05, 0.1, 0.2], [0.1, -0.2, 0.3]);
        let b = tight_box(&pts);
        assert!((b.volume() - 8.0 * 0.05 * 0.1 * 0.2).abs() < 1e-6 * b.volume(), "{b:?}");
        assert!(b.volume() < aabb(&pts).volume());
    }

    #[test]
    fn aligned_box_stays_aligned() {
        let pts = cube_corners(&math::IDENTITY, [0.05, 0.1, 0.2], [0.0, 0.0, 0.0]);
        let b = tight_box(&pts);
        for i in 0..3 {
            assert!((b.rotation[i][i] - 1.0).abs() < 1e-9, "{b:?}");
        }
    }

    #[test]
    fn hull_drops_interior_points_only() {
        let mut pts = cube_corners(
            &math::axis_angle(&[0.3, 0.4, 0.5], 0.7),
            [0.1, 0.2, 0.3],
            [0.5, 0.0, -0.2],
        );
        let corners = pts.clone();
        // Interior points and points on faces and edges.
        pts.push([0.5, 0.0, -0.2]);
        pts.push([0.5, 0.01, -0.19]);
        pts.push([
            (corners[0][0] + corners[1][0]) / 2.0,
            (corners[0][1] + corners[1][1]) / 2.0,
            (corners[0][2] + corners[1][2]) / 2.0,
        ]);
        let kept = hull_vertices(&pts);
        assert_eq!(kept, corners);
        // Every dropped point is inside every face of the hull.
        let faces = convex_hull(&pts);
        assert_eq!(faces.len(), 12);
        for p in &pts {
            for f in &faces {
                assert!(height(&pts, f, p) <= 1e-9);
            }
        }
    }

    #[test]
    fn hull_graph_joins_each_corner_of_a_box_to_its_edges() {
        let pts = cube_corners(&math::IDENTITY, [0.1, 0.2, 0.3], [0.0, 0.0, 0.0]);
        let (neighbours, seeds) = hull_graph(&pts).unwrap();
        for (i, n) in neighbours.iter().enumerate() {
            // Three box edges at each corner, and the triangles' diagonals on its faces.
            let along_edges = n
                .iter()
                .filter(|&&j| (0..3).filter(|&k| pts[i][k] != pts[j][k]).count() == 1);
            assert_eq!(along_edges.count(), 3, "{i}: {n:?}");
            assert!(n.iter().all(|&j| j != i && neighbours[j].contains(&i)));
        }
        for (s, (axis, sign)) in seeds
            .iter()
            .zip([(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)])
        {
            assert!(pts.iter().all(|p| sign * p[axis] <= sign * pts[*s][axis]));
        }
        // A point inside the hull is on no edge: no graph, so the checker scans.
        let mut inside = pts.clone();
        inside.push([0.0; 3]);
        assert!(hull_graph(&inside).is_none());
    }

    #[test]
    fn splits_obj_pieces_at_objects() {
        let text = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\no b\nv 2 0 0\nv 3 0 0\nv 2 1 0\nv 2 0 1\nv 3 1 1\nf 5 6 7\n";
        let pieces = parse_obj_pieces(text).unwrap();
        assert_eq!(pieces.iter().map(Vec::len).collect::<Vec<_>>(), [4, 5]);
        assert_eq!(pieces[1][0], [2.0, 0.0, 0.0]);
        // Blender's layout: vertices first, then the group statement and the faces: one piece.
        let blender = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng mesh\nusemtl m\nf 1 2 3\n";
        let pieces = parse_obj_pieces(blender).unwrap();
        assert_eq!(pieces, [parse_obj_vertices(blender).unwrap()]);
        assert!(parse_obj_pieces("o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\no b\nv 0 0 0\n").is_err());
        assert!(parse_obj_pieces("o a\n").is_err());
    }

    fn binary_stl(triangles: &[[Vec3; 3]]) -> Vec<u8> {
        let mut bytes = b"solid but binary".to_vec();
        bytes.resize(80, b' ');
        bytes.extend((triangles.len() as u32).to_le_bytes());
        for t in triangles {
            bytes.extend([0u8; 12]);
            for c in t {
                for x in c {
                    bytes.extend((*x as f32).to_le_bytes());
                }
            }
            bytes.extend([0u8; 2]);
        }
        bytes
    }

    #[test]
    fn reads_binary_and_ascii_stl() {
        let tetra = [
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.0, 0.0, 0.0], [0.0, 0.0, 0.5], [1.0, 0.0, 0.0]],
        ];
        let binary = parse_stl_vertices(&binary_stl(&tetra)).unwrap();
        assert_eq!(binary.len(), 6);
        assert_eq!(binary[4], [0.0, 0.0, 0.5]);
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n\
                     facet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 0 0 0.5\nvertex 1 0 0\nendloop\nendfacet\nendsolid t\n";
        assert_eq!(parse_stl_vertices(ascii.as_bytes()).unwrap(), binary);
        // A binary file cut short is neither binary nor ASCII.
        let mut cut = binary_stl(&tetra);
        cut.pop();
        assert!(parse_stl_vertices(&cut).is_err());
        assert!(parse_stl_vertices(b"solid x\nvertex 0 0 nan\n").is_err());
    }

    #[test]
    fn parses_vertices_and_rejects_junk() {
        let v = parse_obj_vertices("# c\nv 0 0 0\nv 1 0 0\nvn 0 0 1\nv 0 1 0\nv 0 0 1\nf 1 2 3\n").unwrap();
        assert_eq!(v.len(), 4);
        assert!(parse_obj_vertices("v 0 0\n").is_err());
        assert!(parse_obj_vertices("v 0 0 x\n").is_err());
        assert!(parse_obj_vertices("v 0 0 0\n").is_err());
    }
}
