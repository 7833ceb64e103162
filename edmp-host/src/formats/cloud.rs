//! Point-cloud files for `points` obstacles: PLY (the `vertex` element's `x y z`, through
//! [`ply`](super::ply)) and PCD (the Point Cloud Library's format, `DATA ascii` or
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
