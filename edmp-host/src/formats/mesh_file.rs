//! Triangle-mesh files for `mesh` obstacles: Wavefront OBJ (`v` and `f`; faces fan-triangulated,
//! negative indices counted back from the last vertex; normals, texture coordinates, groups and
//! materials ignored), STL (ASCII or binary, told apart by the binary size rule, so a binary
//! file whose header begins with `solid` reads as binary) and PLY (through [`ply`](super::ply)).
//!
//! Written here rather than with `tobj` or `stl_io`: `tobj`'s errors carry no line number and
//! it resolves material files; `stl_io` iterates as many triangles as a binary header claims
//! and its errors carry no offset. Each format's subset we need is short. Degenerate triangles
//! (a repeated index or zero area) are kept: [`TriangleMesh::degenerate_count`] counts them for
//! the caller, which may skip them. References: <https://paulbourke.net/dataformats/obj/>,
//! <https://paulbourke.net/dataformats/stl/>.

use super::file_error::{FileError, Where, coordinate, extension, integer, lines, number, read_file, show, tokens};
use super::ply;
use std::path::Path;

/// A triangle mesh: vertices and triangles as indices into them (each index in range).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// The vertices, in the file's units and frame.
    pub vertices: Vec<[f32; 3]>,
    /// The triangles, three vertex indices each.
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// How many triangles have a repeated vertex index or zero area (kept, for the caller to
    /// skip or report).
    pub fn degenerate_count(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                let (u, v) = (
                    [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                    [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                );
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || n == [0.0; 3]
            })
            .count()
    }
}

/// Reads a triangle mesh from a `.obj`, `.stl` or `.ply` file (by extension, any case).
pub fn read_mesh(path: &Path) -> Result<TriangleMesh, FileError> {
    let parse = match extension(path).as_str() {
        "obj" => parse_obj,
        "stl" => parse_stl,
        "ply" => parse_ply_mesh,
        other => {
            let message = format!("unknown mesh extension \"{other}\" (obj, stl or ply)");
            return Err(FileError::new(Where::File, message).in_file(path));
        }
    };
    parse(&read_file(path)?).map_err(|e| e.in_file(path))
}

/// A PLY file's vertices and its `face` element's polygons, fan-triangulated.
pub fn parse_ply_mesh(bytes: &[u8]) -> Result<TriangleMesh, FileError> {
    ply::parse(bytes, true).map(|data| TriangleMesh {
        vertices: data.vertices,
        triangles: data.triangles,
    })
}

/// A Wavefront OBJ file's vertices (`v x y z [w | r g b]`, the first three numbers) and faces
/// (`f` with `v`, `v/vt`, `v//vn` or `v/vt/vn` words, at least three). Other statements are
/// ignored. A face may only use vertices defined above it.
pub fn parse_obj(bytes: &[u8]) -> Result<TriangleMesh, FileError> {
    let mut mesh = TriangleMesh::default();
    let mut polygon = Vec::new();
    for (n, line) in lines(bytes) {
        let err = |m: String| Err(FileError::new(Where::Line(n), m));
        let mut words = tokens(line);
        match words.next() {
            Some(b"v") => {
                let mut point = [0.0f32; 3];
                for slot in &mut point {
                    let Some(word) = words.next() else {
                        return err("a vertex needs x y z".into());
                    };
                    let Some(v) = number(word) else {
                        return err(format!("expected a number, found \"{}\"", show(word)));
                    };
                    *slot = match coordinate(v) {
                        Ok(c) => c,
                        Err(m) => return err(m),
                    };
                }
                if mesh.vertices.len() == u32::MAX as usize {
                    return err("more vertices than a u32 index reaches".into());
                }
                mesh.vertices.push(point);
            }
            Some(b"f") => {
                polygon.clear();
                let defined = mesh.vertices.len() as i64;
                for word in words {
                    let first = word.split(|&b| b == b'/').next().unwrap_or(b"");
                    let Some(i) = integer(first) else {
                        return err(format!("expected a vertex index, found \"{}\"", show(word)));
                    };
                    // 1-based; negative counts back from the last vertex defined (-1 is it).
                    let index = if i < 0 { defined + i } else { i - 1 };
                    if i == 0 || !(0..defined).contains(&index) {
                        return err(format!(
                            "vertex index {i} out of range ({defined} vertices defined above)"
                        ));
                    }
                    polygon.push(index as u32);
                }
                if polygon.len() < 3 {
                    return err(format!("a face of {} vertices (at least 3)", polygon.len()));
                }
                for k in 1..polygon.len() - 1 {
                    mesh.triangles.push([polygon[0], polygon[k], polygon[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(mesh)
}

/// An STL file, binary or ASCII. Binary when the size is exactly 84 bytes plus 50 per
/// triangle the header claims (whatever the header's first bytes say); otherwise ASCII when it
/// begins with `solid`; otherwise a binary file of the wrong size. STL repeats vertices per
/// triangle: vertex `3k + j` is triangle `k`'s `j`th corner.
pub fn parse_stl(bytes: &[u8]) -> Result<TriangleMesh, FileError> {
    let claimed = bytes
        .get(80..84)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
    if let Some(count) = claimed
        && count.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len())
    {
        return binary_stl(bytes, count);
    }
    if tokens(bytes.get(..bytes.len().min(256)).unwrap_or(&[])).next() == Some(b"solid") {
        return ascii_stl(bytes);
    }
    match claimed {
        Some(count) => Err(FileError::new(
            Where::Byte(80),
            format!(
                "binary STL: the header claims {count} triangles ({} bytes), the file has {} bytes",
                84 + 50 * count as u64,
                bytes.len()
            ),
        )),
        None => Err(FileError::new(
            Where::File,
            format!("not an STL file ({} bytes)", bytes.len()),
        )),
    }
}

/// Binary STL: an 80-byte header, a little-endian `u32` count, then 50 bytes per triangle (a
/// normal, three corners as `f32`, a 2-byte attribute). The caller checked the size.
fn binary_stl(bytes: &[u8], count: usize) -> Result<TriangleMesh, FileError> {
    if count.checked_mul(3).is_none_or(|v| v > u32::MAX as usize) {
        return Err(FileError::new(
            Where::Byte(80),
            "more vertices than a u32 index reaches",
        ));
    }
    let mut mesh = TriangleMesh {
        vertices: Vec::with_capacity(3 * count),
        triangles: Vec::with_capacity(count),
    };
    for (k, record) in bytes[84..].chunks_exact(50).enumerate() {
        for j in 0..3 {
            let mut point = [0.0f32; 3];
            for (axis, slot) in point.iter_mut().enumerate() {
                let at = 12 + 12 * j + 4 * axis;
                let v = f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]]);
                *slot = coordinate(f64::from(v))
                    .map_err(|m| FileError::new(Where::Byte(84 + 50 * k + at), format!("triangle {k}: {m}")))?;
            }
            mesh.vertices.push(point);
        }
        let v = 3 * k as u32;
        mesh.triangles.push([v, v + 1, v + 2]);
    }
    Ok(mesh)
}

/// ASCII STL: `solid NAME`, then `facet normal nx ny nz`, `outer loop`, three
/// `vertex x y z`, `endloop`, `endfacet` per triangle, then `endsolid NAME`. Several solids in
/// one file are read as one mesh.
fn ascii_stl(bytes: &[u8]) -> Result<TriangleMesh, FileError> {
    let mut mesh = TriangleMesh::default();
    // Corners of the open facet; None outside a facet.
    let mut facet: Option<Vec<[f32; 3]>> = None;
    let mut in_solid = false;
    let mut last = 0;
    for (n, line) in lines(bytes) {
        last = n;
        let err = |m: String| Err(FileError::new(Where::Line(n), m));
        let mut words = tokens(line);
        let Some(key) = words.next() else { continue };
        match (key, in_solid, facet.is_some()) {
            (b"solid", false, _) => in_solid = true,
            (b"endsolid", true, false) => in_solid = false,
            (b"facet", true, false) => facet = Some(Vec::with_capacity(3)),
            (b"outer" | b"endloop", true, true) => {}
            (b"vertex", true, true) => {
                let mut point = [0.0f32; 3];
                for slot in &mut point {
                    let Some(word) = words.next() else {
                        return err("a vertex needs x y z".into());
                    };
                    let Some(v) = number(word) else {
                        return err(format!("expected a number, found \"{}\"", show(word)));
                    };
                    *slot = match coordinate(v) {
                        Ok(c) => c,
                        Err(m) => return err(m),
                    };
                }
                if let Some(corners) = &mut facet {
                    if corners.len() == 3 {
                        return err("a facet with more than 3 vertices".into());
                    }
                    corners.push(point);
                }
            }
            (b"endfacet", true, true) => {
                let corners = facet.take().unwrap_or_default();
                if corners.len() != 3 {
                    return err(format!("a facet with {} vertices (3)", corners.len()));
                }
                if mesh.vertices.len() > u32::MAX as usize - 3 {
                    return err("more vertices than a u32 index reaches".into());
                }
                let v = mesh.vertices.len() as u32;
                mesh.vertices.extend(corners);
                mesh.triangles.push([v, v + 1, v + 2]);
            }
            (other, ..) => return err(format!("unexpected \"{}\"", show(other))),
        }
    }
    if in_solid {
        return Err(FileError::new(
            Where::Line(last),
            "the file ends inside a solid (no endsolid)",
        ));
    }
    Ok(mesh)
}
