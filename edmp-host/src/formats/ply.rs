//! PLY (the Stanford polygon format), the one reader behind point clouds ([`cloud`](super::cloud))
//! and meshes ([`mesh_file`](super::mesh_file)): `format ascii 1.0` or
//! `format binary_little_endian 1.0`, the `vertex` element's `x`, `y`, `z` (any scalar type,
//! float and double in practice) and the `face` element's `vertex_indices` (or `vertex_index`)
//! list, fan-triangulated. Other elements and properties are read past and dropped.
//!
//! Written here rather than taken from `ply-rs` (0.1.3, unchanged since 2018): we need a reader
//! of byte slices that never panics, does not reserve from a header's claimed counts, and says
//! where a file is wrong. Format reference: <https://paulbourke.net/dataformats/ply/>.

use super::file_error::{FileError, Where, coordinate, integer, lines, number, show, tokens};
use rayon::prelude::*;

/// A scalar type of the PLY header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The header's name for it (both the old and the sized spellings).
    fn parse(name: &[u8]) -> Option<Self> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes in the binary encoding.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The inclusive range of an integer type.
    fn range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => (i64::MIN, i64::MAX),
        }
    }

    /// Decodes `self.size()` little-endian bytes.
    fn decode(self, b: &[u8]) -> f64 {
        let mut a = [0u8; 8];
        a[..b.len()].copy_from_slice(b);
        match self {
            Scalar::I8 => f64::from(a[0] as i8),
            Scalar::U8 => f64::from(a[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F64 => f64::from_le_bytes(a),
        }
    }
}

/// A property: a scalar, or a list (its length's type, then its items' type).
#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List(Scalar, Scalar),
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// What a PLY file holds for us: the vertices and, when asked for, the fan-triangulated faces.
#[derive(Debug, Default)]
pub(crate) struct PlyData {
    pub(crate) vertices: Vec<[f32; 3]>,
    pub(crate) triangles: Vec<[u32; 3]>,
}

/// The body of the file, as a stream of scalars: binary little-endian or ASCII words.
enum Body<'a> {
    Binary { bytes: &'a [u8], pos: usize },
    Ascii { bytes: &'a [u8], pos: usize, line: usize },
}

impl Body<'_> {
    fn at(&self) -> Where {
        match *self {
            Body::Binary { pos, .. } => Where::Byte(pos),
            Body::Ascii { line, .. } => Where::Line(line),
        }
    }

    /// Moves past whitespace (ASCII), so that [`Body::at`] names the next value's line.
    fn skip(&mut self) {
        if let Body::Ascii { bytes, pos, line } = self {
            let mut newlines = 0;
            while let Some(&b) = bytes.get(*pos) {
                if !b.is_ascii_whitespace() {
                    // At the end of the file, errors keep naming the last line with a value.
                    *line += newlines;
                    break;
                }
                newlines += usize::from(b == b'\n');
                *pos += 1;
            }
        }
    }

    /// The next value of type `s`, or why there is none.
    fn next(&mut self, s: Scalar) -> Result<f64, String> {
        self.skip();
        match self {
            Body::Binary { bytes, pos } => {
                let end = *pos + s.size();
                let b = bytes.get(*pos..end).ok_or("the file ends early")?;
                *pos = end;
                Ok(s.decode(b))
            }
            Body::Ascii { bytes, pos, .. } => {
                let start = *pos;
                while bytes.get(*pos).is_some_and(|b| !b.is_ascii_whitespace()) {
                    *pos += 1;
                }
                let token = &bytes[start..*pos];
                if token.is_empty() {
                    return Err("the file ends early".into());
                }
                if s.is_integer() {
                    let v = integer(token).ok_or_else(|| format!("expected an integer, found \"{}\"", show(token)))?;
                    let (lo, hi) = s.range();
                    if v < lo || v > hi {
                        return Err(format!("{v} does not fit its type"));
                    }
                    Ok(v as f64)
                } else {
                    number(token).ok_or_else(|| format!("expected a number, found \"{}\"", show(token)))
                }
            }
        }
    }

    /// Bytes left (binary only; ASCII has no fixed size per value).
    fn binary_left(&self) -> Option<usize> {
        match *self {
            Body::Binary { bytes, pos } => Some(bytes.len() - pos),
            Body::Ascii { .. } => None,
        }
    }
}

/// Where one coordinate sits in a row of fixed size: its byte offset, type and property number.
#[derive(Clone, Copy)]
struct Field {
    offset: usize,
    scalar: Scalar,
    property: usize,
}

/// Rows of one size (every property a scalar): the size in bytes and where x, y and z sit.
struct FixedRows {
    stride: usize,
    xyz: [Field; 3],
}

/// `element`'s rows when every property is a scalar, x, y and z being the properties `xyz`.
fn fixed_rows(element: &Element, xyz: [usize; 3]) -> Option<FixedRows> {
    let mut fields = Vec::with_capacity(element.properties.len());
    let mut stride = 0;
    for (property, p) in element.properties.iter().enumerate() {
        let Kind::Scalar(scalar) = p.kind else { return None };
        fields.push(Field {
            offset: stride,
            scalar,
            property,
        });
        stride += scalar.size();
    }
    let at = |i: usize| fields.get(i).copied();
    let xyz = [at(xyz[0])?, at(xyz[1])?, at(xyz[2])?];
    (stride > 0).then_some(FixedRows { stride, xyz })
}

/// The little-endian `f32` at `offset` of a row (NaN past its end: refused as not finite).
fn f32_le_at(chunk: &[u8], offset: usize) -> f32 {
    chunk
        .get(offset..offset + 4)
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(f32::NAN, f32::from_le_bytes)
}

/// Below this many rows a cloud is read on the calling thread.
const ROWS_ON_THREADS: usize = 1 << 15;

/// A large cloud's rows whose x, y and z are `f32` at `offsets`, read on the process's pool of
/// two threads, in row order; `None` when there are few rows, no pool, or a value that is not
/// finite (the one-thread loop then reads them and names the row).
fn f32_rows_on_threads(rows: &[u8], stride: usize, offsets: [usize; 3]) -> Option<Vec<[f32; 3]>> {
    if rows.len() / stride.max(1) < ROWS_ON_THREADS {
        return None;
    }
    let threads = crate::threads::Threads::new(2).ok()?;
    threads.install(|| {
        let mut points = Vec::new();
        rows.par_chunks_exact(stride)
            .map(|chunk| offsets.map(|offset| f32_le_at(chunk, offset)))
            .collect_into_vec(&mut points);
        points
            .par_iter()
            .all(|p| p.iter().all(|v| v.is_finite()))
            .then_some(points)
    })
}

/// The header: the body's encoding, the elements in order, and where the body starts.
fn header(bytes: &[u8]) -> Result<(bool, Vec<Element>, usize), FileError> {
    let mut ascii = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut offset = 0;
    for (n, line) in lines(bytes) {
        offset += line.len() + 1 + usize::from(bytes.get(offset + line.len()) == Some(&b'\r'));
        let err = |m: String| Err(FileError::new(Where::Line(n), m));
        let mut words = tokens(line);
        let first = words.next().unwrap_or(b"");
        if n == 1 {
            if first != b"ply" {
                return err("not a PLY file (it must begin with the line \"ply\")".into());
            }
            continue;
        }
        let rest: Vec<&[u8]> = words.collect();
        match first {
            b"format" => match rest.first().copied() {
                Some(b"ascii") => ascii = Some(true),
                Some(b"binary_little_endian") => ascii = Some(false),
                Some(b"binary_big_endian") => {
                    return err("format binary_big_endian is not supported (ascii or binary_little_endian)".into());
                }
                _ => return err("unknown format (ascii or binary_little_endian)".into()),
            },
            b"comment" | b"obj_info" | b"" => {}
            b"element" => {
                let [name, count] = rest[..] else {
                    return err("expected \"element NAME COUNT\"".into());
                };
                let Some(count) = integer(count).and_then(|c| usize::try_from(c).ok()) else {
                    return err(format!("element \"{}\": bad count \"{}\"", show(name), show(count)));
                };
                elements.push(Element {
                    name: show(name),
                    count,
                    properties: Vec::new(),
                });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return err("a property before any element".into());
                };
                let (kind, name) = match rest[..] {
                    [b"list", len, item, name] => match (Scalar::parse(len), Scalar::parse(item)) {
                        (Some(l), Some(i)) if l.is_integer() => (Kind::List(l, i), name),
                        _ => return err(format!("property \"{}\": bad list types", show(name))),
                    },
                    [ty, name] => match Scalar::parse(ty) {
                        Some(s) => (Kind::Scalar(s), name),
                        None => return err(format!("property \"{}\": unknown type \"{}\"", show(name), show(ty))),
                    },
                    _ => return err("expected \"property TYPE NAME\" or \"property list TYPE TYPE NAME\"".into()),
                };
                element.properties.push(Property { name: show(name), kind });
            }
            b"end_header" => {
                let Some(ascii) = ascii else {
                    return err("no format line before end_header".into());
                };
                return Ok((ascii, elements, offset.min(bytes.len())));
            }
            other => return err(format!("unknown header line \"{}\"", show(other))),
        }
    }
    Err(FileError::new(Where::File, "the header has no end_header line"))
}

/// Reads a PLY file's vertices and, with `faces`, its fan-triangulated faces. Without `faces`
/// the reading stops after the vertex element.
pub(crate) fn parse(bytes: &[u8], faces: bool) -> Result<PlyData, FileError> {
    let (ascii, elements, start) = header(bytes)?;
    let Some(vertex) = elements.iter().find(|e| e.name == "vertex") else {
        return Err(FileError::new(Where::File, "no \"vertex\" element"));
    };
    let n_vertices = vertex.count;
    let mut xyz = [None; 3];
    for (i, p) in vertex.properties.iter().enumerate() {
        if let Some(axis) = ["x", "y", "z"].iter().position(|a| *a == p.name) {
            if matches!(p.kind, Kind::List(..)) {
                return Err(FileError::new(
                    Where::File,
                    format!("vertex property \"{}\" is a list", p.name),
                ));
            }
            xyz[axis] = Some(i);
        }
    }
    let [Some(ix), Some(iy), Some(iz)] = xyz else {
        return Err(FileError::new(Where::File, "the vertex element lacks x, y or z"));
    };
    let index_property = |e: &Element| {
        e.properties
            .iter()
            .position(|p| matches!(p.kind, Kind::List(..)) && (p.name == "vertex_indices" || p.name == "vertex_index"))
    };
    if faces {
        match elements.iter().find(|e| e.name == "face") {
            None => return Err(FileError::new(Where::File, "no \"face\" element")),
            Some(face) if index_property(face).is_none() => {
                return Err(FileError::new(
                    Where::File,
                    "the face element has no vertex_indices list",
                ));
            }
            Some(_) => {}
        }
    }
    if u32::try_from(n_vertices).is_err() {
        return Err(FileError::new(
            Where::File,
            format!("{n_vertices} vertices: more than a u32 index reaches"),
        ));
    }

    let mut body = if ascii {
        let line = bytes[..start].iter().filter(|&&b| b == b'\n').count() + 1;
        Body::Ascii {
            bytes,
            pos: start,
            line,
        }
    } else {
        Body::Binary { bytes, pos: start }
    };
    let mut data = PlyData::default();
    let (mut have_vertices, mut have_faces) = (false, !faces);
    let mut values = Vec::new();
    for element in &elements {
        if have_vertices && have_faces {
            break;
        }
        let is_vertex = element.name == "vertex" && !have_vertices;
        let is_face = faces && element.name == "face" && !have_faces;
        let indices = if is_face { index_property(element) } else { None };
        if element.properties.is_empty() {
            continue;
        }
        // Every row takes at least this many bytes: refuse a claimed count the file cannot hold.
        if let Some(left) = body.binary_left() {
            let min_row: usize = element
                .properties
                .iter()
                .map(|p| match p.kind {
                    Kind::Scalar(s) | Kind::List(s, _) => s.size(),
                })
                .sum();
            if element.count.checked_mul(min_row).is_none_or(|need| need > left) {
                return Err(FileError::new(
                    body.at(),
                    format!(
                        "element \"{}\": {} rows do not fit in the {left} bytes left",
                        element.name, element.count
                    ),
                ));
            }
        }
        if is_vertex {
            // A binary count was checked against the bytes above; an ASCII row takes at
            // least two bytes a property.
            let rows = element.count.min(bytes.len() / (2 * element.properties.len()));
            data.vertices.reserve(rows);
        }
        if is_vertex
            && let Body::Binary { bytes, pos } = &mut body
            && let Some(FixedRows { stride, xyz }) = fixed_rows(element, [ix, iy, iz])
        {
            // Every row the same size: x, y and z read straight from each row's bytes.
            let start = *pos;
            let need = element.count.saturating_mul(stride);
            let rows = bytes.get(start..start.saturating_add(need)).unwrap_or(&[]);
            // The usual cloud, x, y and z as f32: read as they are (the general path below
            // gives the same values, and the error of a row that is not finite).
            let all_f32 = xyz.iter().all(|f| f.scalar == Scalar::F32);
            if all_f32 && let Some(points) = f32_rows_on_threads(rows, stride, xyz.map(|f| f.offset)) {
                data.vertices = points;
                *pos = start + need;
                have_vertices = true;
                continue;
            }
            for (row, chunk) in rows.chunks_exact(stride).enumerate() {
                if all_f32 {
                    let point = xyz.map(|f| f32_le_at(chunk, f.offset));
                    if point.iter().all(|v| v.is_finite()) {
                        data.vertices.push(point);
                        continue;
                    }
                }
                let mut point = [0.0f32; 3];
                for (slot, field) in point.iter_mut().zip(&xyz) {
                    let (offset, s) = (field.offset, field.scalar);
                    let value = chunk.get(offset..offset + s.size()).map_or(f64::NAN, |b| s.decode(b));
                    *slot = coordinate(value).map_err(|m| {
                        let name = element.properties.get(field.property).map_or("", |p| p.name.as_str());
                        FileError::new(
                            Where::Byte(start + row * stride + offset),
                            format!("element \"vertex\" row {row} property \"{name}\": {m}"),
                        )
                    })?;
                }
                data.vertices.push(point);
            }
            *pos = start + need;
            have_vertices = true;
            continue;
        }
        for row in 0..element.count {
            let mut point = [0.0f32; 3];
            for (i, property) in element.properties.iter().enumerate() {
                body.skip();
                let at = body.at();
                let fail = |m: String| {
                    FileError::new(
                        at,
                        format!(
                            "element \"{}\" row {row} property \"{}\": {m}",
                            element.name, property.name
                        ),
                    )
                };
                match property.kind {
                    Kind::Scalar(s) => {
                        let v = body.next(s).map_err(fail)?;
                        if is_vertex && let Some(axis) = [ix, iy, iz].iter().position(|&a| a == i) {
                            point[axis] = coordinate(v).map_err(fail)?;
                        }
                    }
                    Kind::List(len, item) => {
                        let n = body.next(len).map_err(fail)?;
                        if n < 0.0 {
                            return Err(fail(format!("negative list length {n}")));
                        }
                        let keep = indices == Some(i);
                        values.clear();
                        for _ in 0..n as u64 {
                            let v = body.next(item).map_err(fail)?;
                            if keep {
                                if v.fract() != 0.0 || v < 0.0 || v >= n_vertices as f64 {
                                    return Err(fail(format!("vertex index {v} out of range ({n_vertices} vertices)")));
                                }
                                values.push(v as u32);
                            }
                        }
                        if keep {
                            if values.len() < 3 {
                                return Err(fail(format!("a face of {} vertices (at least 3)", values.len())));
                            }
                            for k in 1..values.len() - 1 {
                                data.triangles.push([values[0], values[k], values[k + 1]]);
                            }
                        }
                    }
                }
            }
            if is_vertex {
                data.vertices.push(point);
            }
        }
        have_vertices |= is_vertex;
        have_faces |= is_face;
    }
    Ok(data)
}
