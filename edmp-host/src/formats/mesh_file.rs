//! Triangle-mesh files for `mesh` obstacles: Wavefront OBJ (`v` and `f`; faces fan-triangulated,
//! negative indices counted back from the last vertex; normals, texture coordinates, groups and
//! materials ignored), STL (ASCII or binary, told apart by the binary size rule, so a binary
//! file whose header begins with `solid` reads as binary) and PLY (through `ply.rs`).
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
    /// skip or report). An index out of range (only in a mesh built by hand) counts too.
    pub fn degenerate_count(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| {
                let [Some(&a), Some(&b), Some(&c)] = t.map(|i| self.vertices.get(i as usize)) else {
                    return true;
                };
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
                let point = match xyz(&mut words) {
                    Ok(p) => p,
                    Err(m) => return err(m),
                };
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
    let size_error = |count: usize| {
        FileError::new(
            Where::Byte(80),
            format!(
                "binary STL: the header claims {count} triangles ({} bytes), the file has {} bytes",
                84 + 50 * count as u64,
                bytes.len()
            ),
        )
    };
    if tokens(bytes.get(..bytes.len().min(256)).unwrap_or(&[])).next() == Some(b"solid") {
        // A binary file of the wrong size whose header begins with "solid": ASCII has no NUL.
        return ascii_stl(bytes).map_err(|e| match claimed {
            Some(count) if bytes.contains(&0) => size_error(count),
            _ => e,
        });
    }
    match claimed {
        Some(count) => Err(size_error(count)),
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
                let point = match xyz(&mut words) {
                    Ok(p) => p,
                    Err(m) => return err(m),
                };
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

/// The three coordinates `x y z` of a vertex line, each a finite `f32`.
fn xyz<'a>(words: &mut impl Iterator<Item = &'a [u8]>) -> Result<[f32; 3], String> {
    let mut point = [0.0f32; 3];
    for slot in &mut point {
        let word = words.next().ok_or("a vertex needs x y z")?;
        let v = number(word).ok_or_else(|| format!("expected a number, found \"{}\"", show(word)))?;
        *slot = coordinate(v)?;
    }
    Ok(point)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(result: Result<TriangleMesh, FileError>) -> String {
        result.expect_err("should be refused").to_string()
    }

    /// A binary STL with the given 80-byte header start and triangles (corners only).
    fn binary(header: &[u8], triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut bytes = [0u8; 80].to_vec();
        bytes[..header.len()].copy_from_slice(header);
        bytes.extend((triangles.len() as u32).to_le_bytes());
        for t in triangles {
            bytes.extend([0.0f32, 0.0, 1.0].iter().flat_map(|v| v.to_le_bytes()));
            bytes.extend(t.iter().flatten().flat_map(|v| v.to_le_bytes()));
            bytes.extend([0u8, 0]);
        }
        bytes
    }

    const SQUARE: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn obj_forms_negative_indices_and_quads() {
        let text = "# a square and a triangle\r\nmtllib box.mtl\no square\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\n\
            v 0 1 0 0.5 0.5 0.5\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\ng side\nusemtl red\ns off\n\
            f 1/1/1 2/2/1 3/3/1 4/4/1\nf 1//1 2//1 3//1\nf 1/1 2/2 3/3\n  f -4 -3 -2\nl 1 2\n";
        let mesh = parse_obj(text.as_bytes()).unwrap();
        assert_eq!(mesh.vertices, SQUARE.to_vec());
        assert_eq!(
            mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 1, 2], [0, 1, 2]]
        );
        assert_eq!(mesh.degenerate_count(), 0);
    }

    #[test]
    fn obj_malformed() {
        let two = "v 0 0 0\nv 1 0 0\n";
        let m = message(parse_obj(format!("{two}f 1 2 3\n").as_bytes()));
        assert_eq!(m, "line 3: vertex index 3 out of range (2 vertices defined above)");
        assert!(message(parse_obj(format!("{two}f 0 1 2\n").as_bytes())).contains("vertex index 0 out of range"));
        assert!(message(parse_obj(format!("{two}f -3 1 2\n").as_bytes())).contains("vertex index -3 out of range"));
        assert!(message(parse_obj(format!("{two}f 1 2\n").as_bytes())).contains("a face of 2 vertices"));
        assert!(
            message(parse_obj(format!("{two}f 1 x 2\n").as_bytes())).contains("expected a vertex index, found \"x\"")
        );
        assert_eq!(message(parse_obj(b"v 0 0\n")), "line 1: a vertex needs x y z");
        assert_eq!(
            message(parse_obj(b"v 0 0 inf\n")),
            "line 1: coordinate inf is not a finite f32"
        );
        assert!(message(parse_obj(b"v 0 0 1e39\n")).contains("not a finite f32"));
    }

    #[test]
    fn stl_ascii_and_binary() {
        let text = "solid square\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n\
            vertex 1 1 0\n    endloop\n  endfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\n\
            vertex 0 1 0\nendloop\nendfacet\nendsolid square\n";
        let ascii = parse_stl(text.as_bytes()).unwrap();
        assert_eq!(ascii.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        assert_eq!(
            ascii.vertices,
            vec![SQUARE[0], SQUARE[1], SQUARE[2], SQUARE[0], SQUARE[2], SQUARE[3]]
        );

        let triangles = [[SQUARE[0], SQUARE[1], SQUARE[2]], [SQUARE[0], SQUARE[2], SQUARE[3]]];
        assert_eq!(parse_stl(&binary(b"made by hand", &triangles)).unwrap(), ascii);
        // Many exporters begin a binary header with "solid": the size decides.
        assert_eq!(
            parse_stl(&binary(b"solid exported by a CAD tool", &triangles)).unwrap(),
            ascii
        );
        assert_eq!(parse_stl(&binary(b"", &[])).unwrap(), TriangleMesh::default());
    }

    #[test]
    fn stl_malformed() {
        let t = [[SQUARE[0], SQUARE[1], SQUARE[2]]];
        let mut truncated = binary(b"", &t);
        truncated.pop();
        assert_eq!(
            message(parse_stl(&truncated)),
            "byte 80: binary STL: the header claims 1 triangles (134 bytes), the file has 133 bytes"
        );
        let mut solid = binary(b"solid but binary", &t);
        solid.truncate(120);
        assert!(
            message(parse_stl(&solid)).contains("the header claims 1 triangles (134 bytes), the file has 120 bytes")
        );
        let mut nan = binary(b"", &t);
        nan[84 + 12 + 4..84 + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(
            message(parse_stl(&nan)),
            "byte 100: triangle 0: coordinate NaN is not a finite f32"
        );
        assert!(message(parse_stl(b"abc")).contains("not an STL file (3 bytes)"));
        let open =
            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n";
        assert_eq!(
            message(parse_stl(open.as_bytes())),
            "line 9: the file ends inside a solid (no endsolid)"
        );
        let two = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n";
        assert_eq!(
            message(parse_stl(two.as_bytes())),
            "line 7: a facet with 2 vertices (3)"
        );
        let nan = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\n";
        assert!(message(parse_stl(nan.as_bytes())).starts_with("line 4: coordinate NaN"));
        assert!(message(parse_stl(b"solid x\nvertex 0 0 0\n")).contains("line 2: unexpected \"vertex\""));
    }

    #[test]
    fn ply_meshes() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
            property uchar red\nelement face 2\nproperty list uchar int vertex_indices\nproperty uchar flags\n\
            end_header\n0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n4 0 1 2 3 9\n3 0 0 1 9\n";
        let mesh = parse_ply_mesh(text.as_bytes()).unwrap();
        assert_eq!(mesh.vertices, SQUARE.to_vec());
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 0, 1]]);
        assert_eq!(mesh.degenerate_count(), 1);

        // Binary, doubles, `vertex_index` with uint8 length and uint32 items.
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n\
            property double y\nproperty double z\nelement face 1\nproperty list uint8 uint32 vertex_index\nend_header\n"
            .to_vec();
        bytes.extend(SQUARE[..3].iter().flatten().flat_map(|&v| f64::from(v).to_le_bytes()));
        bytes.push(3);
        bytes.extend([0u32, 1, 2].iter().flat_map(|v| v.to_le_bytes()));
        let mesh = parse_ply_mesh(&bytes).unwrap();
        assert_eq!((mesh.vertices, mesh.triangles), (SQUARE[..3].to_vec(), vec![[0, 1, 2]]));

        let out = text.replace("3 0 0 1 9", "3 0 0 4 9");
        let m = message(parse_ply_mesh(out.as_bytes()));
        assert_eq!(
            m,
            "line 17: element \"face\" row 1 property \"vertex_indices\": vertex index 4 out of range (4 vertices)"
        );
        let short = text.replace("3 0 0 1 9", "2 0 1 9");
        assert!(message(parse_ply_mesh(short.as_bytes())).contains("a face of 2 vertices"));
        let no_faces = "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
        assert_eq!(message(parse_ply_mesh(no_faces.as_bytes())), "no \"face\" element");
        let mut cut = bytes.clone();
        cut.truncate(bytes.len() - 2);
        assert!(message(parse_ply_mesh(&cut)).contains("the file ends early"));
    }

    #[test]
    fn files_by_extension() {
        let dir = std::env::temp_dir().join(format!("edmp-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = dir.join("m.OBJ");
        std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(read_mesh(&obj).unwrap().triangles, vec![[0, 1, 2]]);
        let stl = dir.join("m.stl");
        std::fs::write(&stl, "solid\nfacet\n").unwrap();
        assert_eq!(
            message(read_mesh(&stl)),
            format!("{}: line 3: the file ends inside a solid (no endsolid)", stl.display())
        );
        let dae = dir.join("m.dae");
        std::fs::write(&dae, "<COLLADA/>").unwrap();
        assert!(message(read_mesh(&dae)).ends_with("unknown mesh extension \"dae\" (obj, stl or ply)"));
        assert!(message(read_mesh(&dir.join("none"))).contains("unknown mesh extension \"\""));
        assert!(message(read_mesh(&dir.join("gone.stl"))).contains("gone.stl: cannot read: "));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
