//! Point-cloud files for `points` obstacles: PLY (the `vertex` element's `x y z`, through
//! `ply.rs`) and PCD (the Point Cloud Library's format, `DATA ascii` or
//! `DATA binary`, fields `x y z`; other properties and fields are dropped). Every coordinate
//! must be a finite `f32`, so a PCD cloud with NaN "no return" points is refused.
//!
//! PCD is read here rather than through a crate: `pcd-rs` reads from files and readers, not
//! slices, and reserves from the header's `POINTS`; a reader of a dozen header keys is short.
//! Format reference: <https://pointclouds.org/documentation/tutorials/pcd_file_format.html>.

use super::file_error::{FileError, Where, coordinate, extension, integer, lines, number, read_file, show, tokens};
use super::ply;
use std::path::Path;

/// Reads a point cloud from a `.ply` or `.pcd` file (by extension, any case).
pub fn read_points(path: &Path) -> Result<Vec<[f32; 3]>, FileError> {
    let parse = match extension(path).as_str() {
        "ply" => parse_ply_points,
        "pcd" => parse_pcd,
        other => {
            let message = format!("unknown point-cloud extension \"{other}\" (ply or pcd)");
            return Err(FileError::new(Where::File, message).in_file(path));
        }
    };
    parse(&read_file(path)?).map_err(|e| e.in_file(path))
}

/// The vertices of a PLY file (ASCII or binary little-endian), as points; faces are ignored.
pub fn parse_ply_points(bytes: &[u8]) -> Result<Vec<[f32; 3]>, FileError> {
    ply::parse(bytes, false).map(|data| data.vertices)
}

/// A PCD field's type: `F` (float), `I` (signed) or `U` (unsigned), and its size in bytes.
#[derive(Clone, Copy, Debug)]
struct Field {
    kind: u8,
    size: usize,
    count: usize,
}

impl Field {
    /// Decodes one little-endian value.
    fn decode(self, b: &[u8]) -> f64 {
        let mut a = [0u8; 8];
        a[..b.len()].copy_from_slice(b);
        match (self.kind, self.size) {
            (b'F', 4) => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            (b'F', _) => f64::from_le_bytes(a),
            (b'U', _) => u64::from_le_bytes(a) as f64,
            // Sign-extend from the field's width.
            (_, size) => (i64::from_le_bytes(a) << (64 - 8 * size) >> (64 - 8 * size)) as f64,
        }
    }
}

/// The points of a PCD file (`DATA ascii` or `DATA binary`).
pub fn parse_pcd(bytes: &[u8]) -> Result<Vec<[f32; 3]>, FileError> {
    let mut names: Vec<String> = Vec::new();
    let (mut sizes, mut types, mut counts) = (None, None, None);
    let (mut width, mut height, mut points) = (None, None, None);
    let mut offset = 0;
    let mut data = None;
    for (n, line) in lines(bytes) {
        offset += line.len() + 1 + usize::from(bytes.get(offset + line.len()) == Some(&b'\r'));
        let err = |m: String| Err(FileError::new(Where::Line(n), m));
        let mut words = tokens(line);
        let Some(key) = words.next() else { continue };
        if key.starts_with(b"#") {
            continue;
        }
        let rest: Vec<&[u8]> = words.collect();
        let one = |what: &str| -> Result<usize, FileError> {
            match rest[..] {
                [v] => integer(v).and_then(|v| usize::try_from(v).ok()).ok_or_else(|| {
                    FileError::new(
                        Where::Line(n),
                        format!("{what}: expected a count, found \"{}\"", show(v)),
                    )
                }),
                _ => Err(FileError::new(Where::Line(n), format!("{what}: expected one count"))),
            }
        };
        match key {
            b"VERSION" | b"VIEWPOINT" => {}
            b"FIELDS" => names = rest.iter().map(|w| show(w)).collect(),
            b"SIZE" => sizes = Some(rest.iter().map(|w| integer(w).unwrap_or(0)).collect::<Vec<_>>()),
            b"TYPE" => {
                types = Some(
                    rest.iter()
                        .map(|w| if w.len() == 1 { w[0] } else { b'?' })
                        .collect::<Vec<_>>(),
                )
            }
            b"COUNT" => counts = Some(rest.iter().map(|w| integer(w).unwrap_or(-1)).collect::<Vec<_>>()),
            b"WIDTH" => width = Some(one("WIDTH")?),
            b"HEIGHT" => height = Some(one("HEIGHT")?),
            b"POINTS" => points = Some(one("POINTS")?),
            b"DATA" => {
                match rest.first().copied() {
                    Some(b"ascii") => data = Some((true, n)),
                    Some(b"binary") => data = Some((false, n)),
                    Some(b"binary_compressed") => {
                        return err(
                            "DATA binary_compressed is not supported (save the cloud as ascii or binary)".into(),
                        );
                    }
                    _ => return err("DATA: expected ascii or binary".into()),
                }
                break;
            }
            other => return err(format!("unknown header key \"{}\"", show(other))),
        }
    }
    let Some((ascii, data_line)) = data else {
        return Err(FileError::new(Where::File, "the header has no DATA line"));
    };
    let header_err = |m: String| Err(FileError::new(Where::Line(data_line), m));

    // The fields, checked against each other.
    let sizes = sizes.unwrap_or_default();
    let types = types.unwrap_or_default();
    let counts = counts.unwrap_or_else(|| vec![1; names.len()]);
    if names.is_empty() || sizes.len() != names.len() || types.len() != names.len() || counts.len() != names.len() {
        return header_err(format!(
            "FIELDS, SIZE, TYPE and COUNT must name the same number of fields ({}, {}, {}, {})",
            names.len(),
            sizes.len(),
            types.len(),
            counts.len()
        ));
    }
    let mut fields = Vec::with_capacity(names.len());
    for (i, name) in names.iter().enumerate() {
        let (kind, size, count) = (types[i], sizes[i], counts[i]);
        let valid = match kind {
            b'F' => size == 4 || size == 8,
            b'I' | b'U' => matches!(size, 1 | 2 | 4 | 8),
            _ => false,
        };
        if !valid || !(1..=1 << 20).contains(&count) {
            return header_err(format!("field \"{name}\": bad TYPE, SIZE or COUNT"));
        }
        fields.push(Field {
            kind,
            size: size as usize,
            count: count as usize,
        });
    }
    let mut xyz = [0usize; 3];
    for (axis, want) in ["x", "y", "z"].iter().enumerate() {
        match names.iter().position(|n| n == want) {
            Some(i) if fields[i].count == 1 => xyz[axis] = i,
            Some(_) => return header_err(format!("field \"{want}\" must have COUNT 1")),
            None => return header_err(format!("no field \"{want}\" (FIELDS {})", names.join(" "))),
        }
    }
    let n_points = match (points, width, height) {
        (Some(p), _, _) => p,
        (None, Some(w), Some(h)) => w
            .checked_mul(h)
            .ok_or_else(|| FileError::new(Where::File, "WIDTH × HEIGHT overflows"))?,
        _ => return header_err("neither POINTS nor WIDTH and HEIGHT".into()),
    };

    let body = bytes.get(offset..).unwrap_or(&[]);
    if ascii {
        return ascii_points(body, data_line, &fields, xyz, n_points);
    }
    // Binary: the points one after another, each field's values in order (row major).
    let starts: Vec<usize> = fields
        .iter()
        .scan(0, |at, f| {
            let start = *at;
            *at += f.size * f.count;
            Some(start)
        })
        .collect();
    let row: usize = fields.iter().map(|f| f.size * f.count).sum();
    if n_points.checked_mul(row).is_none_or(|need| need > body.len()) {
        return Err(FileError::new(
            Where::Byte(offset.min(bytes.len())),
            format!(
                "{n_points} points of {row} bytes do not fit in the {} bytes of data",
                body.len()
            ),
        ));
    }
    let mut cloud = Vec::with_capacity(n_points);
    for (p, chunk) in body.chunks_exact(row).take(n_points).enumerate() {
        let mut point = [0.0f32; 3];
        for (axis, &i) in xyz.iter().enumerate() {
            let b = &chunk[starts[i]..starts[i] + fields[i].size];
            point[axis] = coordinate(fields[i].decode(b))
                .map_err(|m| FileError::new(Where::Byte(offset + p * row + starts[i]), format!("point {p}: {m}")))?;
        }
        cloud.push(point);
    }
    Ok(cloud)
}

/// `DATA ascii`: one point per line, each field's values as words.
fn ascii_points(
    body: &[u8],
    data_line: usize,
    fields: &[Field],
    xyz: [usize; 3],
    n_points: usize,
) -> Result<Vec<[f32; 3]>, FileError> {
    // Word index of each field's first value.
    let starts: Vec<usize> = fields
        .iter()
        .scan(0, |at, f| {
            let start = *at;
            *at += f.count;
            Some(start)
        })
        .collect();
    let words: usize = fields.iter().map(|f| f.count).sum();
    let mut cloud = Vec::new();
    let mut last = data_line;
    for (n, line) in lines(body) {
        let n = n + data_line;
        last = n;
        let row: Vec<&[u8]> = tokens(line).take(words + 1).collect();
        if row.is_empty() {
            continue;
        }
        let err = |m: String| Err(FileError::new(Where::Line(n), m));
        if cloud.len() == n_points {
            return err(format!("more points than POINTS {n_points}"));
        }
        if row.len() != words {
            return err(format!("expected {words} values, found {}", tokens(line).count()));
        }
        let mut point = [0.0f32; 3];
        for (axis, &i) in xyz.iter().enumerate() {
            let word = row[starts[i]];
            let Some(v) = number(word) else {
                return err(format!("expected a number, found \"{}\"", show(word)));
            };
            point[axis] = match coordinate(v) {
                Ok(c) => c,
                Err(m) => return err(format!("point {}: {m}", cloud.len())),
            };
        }
        cloud.push(point);
    }
    if cloud.len() < n_points {
        return Err(FileError::new(
            Where::Line(last),
            format!("{} points, but POINTS says {n_points}", cloud.len()),
        ));
    }
    Ok(cloud)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A binary little-endian PLY: the header, then the rows' bytes.
    fn binary_ply(header: &str, body: &[u8]) -> Vec<u8> {
        let mut bytes = format!("ply\nformat binary_little_endian 1.0\n{header}end_header\n").into_bytes();
        bytes.extend_from_slice(body);
        bytes
    }

    fn message(result: Result<Vec<[f32; 3]>, FileError>) -> String {
        result.expect_err("should be refused").to_string()
    }

    #[test]
    fn ply_ascii_with_normals_colour_and_faces() {
        let text = "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nelement vertex 3\r\n\
            property float nx\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n\
            property uchar red\r\nproperty list uchar float extra\r\nelement face 1\r\n\
            property list uchar int vertex_indices\r\nend_header\r\n\
            0 1 2 3 255 2 0.5 0.5\r\n0 4 5 6 0 0\r\n0 -7 8.5 9e-1 7 1 1\r\n3 0 1 2\r\n";
        let points = parse_ply_points(text.as_bytes()).unwrap();
        assert_eq!(points, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [-7.0, 8.5, 0.9]]);
    }

    #[test]
    fn ply_binary_float_and_double() {
        let mut body = Vec::new();
        for (i, p) in [[1.0f32, 2.0, 3.0], [-4.0, 0.5, 6.0]].iter().enumerate() {
            body.extend(p.iter().flat_map(|v| v.to_le_bytes()));
            body.extend([0.0f32, 0.0, 1.0].iter().flat_map(|v| v.to_le_bytes())); // normal
            body.extend([10 * i as u8, 20, 30]); // colour
        }
        let header = "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
            property float nx\nproperty float ny\nproperty float nz\n\
            property uchar red\nproperty uchar green\nproperty uchar blue\n";
        let points = parse_ply_points(&binary_ply(header, &body)).unwrap();
        assert_eq!(points, vec![[1.0, 2.0, 3.0], [-4.0, 0.5, 6.0]]);

        // Doubles, after an element of another name with a list (read past).
        let mut body = vec![2u8, 7, 0, 0, 0, 8, 0, 0, 0];
        body.extend([0.25f64, -1.5, 1e3].iter().flat_map(|v| v.to_le_bytes()));
        body.extend(0.5f32.to_le_bytes()); // confidence
        let header = "element camera 1\nproperty list uchar int stuff\nelement vertex 1\n\
            property double x\nproperty double y\nproperty double z\nproperty float confidence\n";
        assert_eq!(
            parse_ply_points(&binary_ply(header, &body)).unwrap(),
            vec![[0.25, -1.5, 1000.0]]
        );
    }

    #[test]
    fn a_large_binary_ply_reads_the_same_on_threads_and_names_a_bad_row() {
        // Above `ply::ROWS_ON_THREADS` rows the pool reads them; a colour after x, y, z.
        let rows = 40_000;
        let point = |i: usize| [i as f32 * 1e-3, -(i as f32), 0.5 + i as f32];
        let mut body = Vec::new();
        for i in 0..rows {
            body.extend(point(i).iter().flat_map(|v| v.to_le_bytes()));
            body.push(7);
        }
        let header = format!(
            "element vertex {rows}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
        );
        let points = parse_ply_points(&binary_ply(&header, &body)).unwrap();
        assert_eq!(points.len(), rows);
        assert!(points.iter().enumerate().all(|(i, p)| *p == point(i)));
        // A value that is not finite in a late row: the row and the property are named.
        let bad = 33_333;
        let at = bad * 13 + 4;
        body[at..at + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
        let m = message(parse_ply_points(&binary_ply(&header, &body)));
        assert!(m.contains("row 33333 property \"y\""), "{m}");
    }

    #[test]
    fn ply_malformed() {
        let header = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
        let two = [0u8; 24];
        let m = message(parse_ply_points(&binary_ply(header, &two)));
        assert!(
            m.contains("element \"vertex\": 3 rows do not fit in the 24 bytes left"),
            "{m}"
        );
        // A claimed count far beyond the bytes present is refused before anything is reserved.
        let huge = "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n";
        assert!(message(parse_ply_points(&binary_ply(huge, &two))).contains("do not fit"));
        let m = message(parse_ply_points(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n"));
        assert!(m.contains("row 1 property \"x\": the file ends early"), "{m}");
        let m = message(parse_ply_points(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 nan 3\n"));
        assert_eq!(
            m,
            "line 8: element \"vertex\" row 0 property \"y\": coordinate NaN is not a finite f32"
        );
        let m = message(parse_ply_points(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\nend_header\n1 2 1e300\n"));
        assert!(m.contains("not a finite f32"), "{m}");
        let nan = binary_ply(
            header.replace('3', "1").as_str(),
            &[0, 0, 0, 0, 0, 0, 0xc0, 0x7f, 0, 0, 0, 0],
        );
        let m = message(parse_ply_points(&nan));
        assert!(
            m.starts_with("byte ") && m.contains("row 0 property \"y\": coordinate NaN"),
            "{m}"
        );
        assert!(message(parse_ply_points(b"plyx\n")).contains("not a PLY file"));
        assert!(
            message(parse_ply_points(b"ply\nformat binary_big_endian 1.0\nend_header\n")).contains("not supported")
        );
        assert!(
            message(parse_ply_points(
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            ))
            .contains("end_header")
        );
        assert!(
            message(parse_ply_points(
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n"
            ))
            .contains("lacks x, y or z")
        );
        assert!(
            message(parse_ply_points(
                b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n"
            ))
            .contains("bad count")
        );
        assert!(message(parse_ply_points(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty uchar x\nproperty uchar y\nproperty uchar z\nend_header\n1 2 300\n")).contains("does not fit its type"));
    }

    fn pcd_header(fields: &str, size: &str, ty: &str, count: &str, points: usize, data: &str) -> String {
        format!(
            "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {fields}\nSIZE {size}\nTYPE {ty}\n\
             COUNT {count}\nWIDTH {points}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\nDATA {data}\n"
        )
    }

    #[test]
    fn pcd_ascii_and_binary() {
        let mut text = pcd_header("x y z rgb normal", "4 4 4 4 4", "F F F F F", "1 1 1 1 3", 2, "ascii");
        text.push_str("1 2 3 4.2108e+06 0 0 1\n\n-0.5 0.25 1e2 4.2108e+06 0 1 0\n");
        assert_eq!(
            parse_pcd(text.as_bytes()).unwrap(),
            vec![[1.0, 2.0, 3.0], [-0.5, 0.25, 100.0]]
        );

        // Binary: a u8 label first, x y z as doubles, y before x, an i16 after.
        let mut bytes = pcd_header("label y x z t", "1 8 8 8 2", "U F F F I", "1 1 1 1 1", 2, "binary").into_bytes();
        for (x, y, z) in [(1.0f64, 2.0f64, 3.0f64), (4.0, -5.0, 6.5)] {
            bytes.push(9);
            bytes.extend(y.to_le_bytes());
            bytes.extend(x.to_le_bytes());
            bytes.extend(z.to_le_bytes());
            bytes.extend((-3i16).to_le_bytes());
        }
        assert_eq!(parse_pcd(&bytes).unwrap(), vec![[1.0, 2.0, 3.0], [4.0, -5.0, 6.5]]);

        // Integer coordinates, signed, and COUNT omitted (1 each).
        let mut bytes = b"FIELDS x y z\nSIZE 2 1 4\nTYPE I I U\nWIDTH 1\nHEIGHT 1\nDATA binary\n".to_vec();
        bytes.extend((-300i16).to_le_bytes());
        bytes.push(0xff);
        bytes.extend(7u32.to_le_bytes());
        assert_eq!(parse_pcd(&bytes).unwrap(), vec![[-300.0, -1.0, 7.0]]);
    }

    #[test]
    fn pcd_malformed() {
        let compressed = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, "binary_compressed");
        let m = message(parse_pcd(compressed.as_bytes()));
        assert_eq!(
            m,
            "line 11: DATA binary_compressed is not supported (save the cloud as ascii or binary)"
        );
        let mut truncated = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 2, "binary").into_bytes();
        truncated.extend([0u8; 20]);
        assert!(message(parse_pcd(&truncated)).contains("2 points of 12 bytes do not fit in the 20 bytes"));
        let huge = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", usize::MAX / 2, "binary");
        assert!(message(parse_pcd(huge.as_bytes())).contains("do not fit"));
        let mut few = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 3, "ascii");
        few.push_str("1 2 3\n4 5 6\n");
        assert!(message(parse_pcd(few.as_bytes())).contains("2 points, but POINTS says 3"));
        let mut many = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, "ascii");
        many.push_str("1 2 3\n4 5 6\n");
        assert_eq!(
            message(parse_pcd(many.as_bytes())),
            "line 13: more points than POINTS 1"
        );
        let mut nan = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, "ascii");
        nan.push_str("nan nan nan\n");
        assert!(message(parse_pcd(nan.as_bytes())).contains("line 12: point 0: coordinate NaN"));
        let mut short = pcd_header("x y z rgb", "4 4 4 4", "F F F F", "1 1 1 1", 1, "ascii");
        short.push_str("1 2 3\n");
        assert!(message(parse_pcd(short.as_bytes())).contains("expected 4 values, found 3"));
        let no_z = pcd_header("x y", "4 4", "F F", "1 1", 1, "ascii");
        assert!(message(parse_pcd(no_z.as_bytes())).contains("no field \"z\""));
        let bad_size = pcd_header("x y z", "4 4 3", "F F F", "1 1 1", 1, "ascii");
        assert!(message(parse_pcd(bad_size.as_bytes())).contains("field \"z\": bad TYPE, SIZE or COUNT"));
        assert!(message(parse_pcd(b"VERSION 0.7\nFIELDS x y z\n")).contains("no DATA line"));
    }

    #[test]
    fn files_by_extension() {
        let dir = std::env::temp_dir().join(format!("edmp-cloud-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pcd = dir.join("cloud.PCD");
        let mut text = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, "ascii");
        text.push_str("1 2 3\n");
        std::fs::write(&pcd, &text).unwrap();
        assert_eq!(read_points(&pcd).unwrap(), vec![[1.0, 2.0, 3.0]]);
        let ply = dir.join("cloud.ply");
        std::fs::write(&ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2\n").unwrap();
        let m = message(read_points(&ply));
        assert!(m.starts_with(&format!("{}: line 8: ", ply.display())), "{m}");
        let xyz = dir.join("cloud.xyz");
        std::fs::write(&xyz, "1 2 3\n").unwrap();
        assert!(message(read_points(&xyz)).ends_with("unknown point-cloud extension \"xyz\" (ply or pcd)"));
        let m = message(read_points(&dir.join("missing.pcd")));
        assert!(m.contains("missing.pcd: cannot read: "), "{m}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
