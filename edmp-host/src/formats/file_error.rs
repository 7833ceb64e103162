//! The one error of the geometry file readers ([`cloud`](super::cloud),
//! [`mesh_file`](super::mesh_file), `ply.rs`): what is wrong, where in the file (a
//! line of a text file, a byte offset of a binary one) and, once read from disk, which file.
//! The scene reader prefixes the obstacle's path, so a message names obstacle, file and place.
//! Also the small text helpers the text formats share (lines, tokens, numbers).

use core::fmt;
use std::path::{Path, PathBuf};

/// Where in a file a problem is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Where {
    /// The whole file (it is missing, empty, of an unknown kind).
    File,
    /// A 1-based line of a text file or text header.
    Line(usize),
    /// A 0-based byte offset into a binary file.
    Byte(usize),
}

/// A geometry file that cannot be read: missing, unreadable or malformed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileError {
    /// The file, once the error came from reading one from disk.
    pub file: Option<PathBuf>,
    /// Where in the file.
    pub at: Where,
    /// What is wrong, e.g. `element "face" row 3: vertex index 9 out of range (8 vertices)`.
    pub message: String,
}

impl FileError {
    /// An error at a place in bytes not (yet) tied to a file.
    pub fn new(at: Where, message: impl Into<String>) -> Self {
        FileError {
            file: None,
            at,
            message: message.into(),
        }
    }

    /// The same error, naming the file it is in.
    pub fn in_file(mut self, file: &Path) -> Self {
        self.file = Some(file.to_path_buf());
        self
    }
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}: ", file.display())?;
        }
        match self.at {
            Where::File => {}
            Where::Line(n) => write!(f, "line {n}: ")?,
            Where::Byte(n) => write!(f, "byte {n}: ")?,
        }
        f.write_str(&self.message)
    }
}

impl core::error::Error for FileError {}

/// Reads a whole file, or says why it cannot.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, FileError> {
    std::fs::read(path).map_err(|e| FileError::new(Where::File, format!("cannot read: {e}")).in_file(path))
}

/// The file's extension, lower case ("" when it has none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// The lines of a text, 1-based numbers with each line (without `\n` and a trailing `\r`).
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, line)| (i + 1, line.strip_suffix(b"\r").unwrap_or(line)))
}

/// The whitespace-separated words of a line.
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty())
}

/// A word as text for messages (lossy, shortened).
pub(crate) fn show(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(&token[..token.len().min(40)]).into_owned();
    if token.len() > 40 { format!("{text}…") } else { text }
}

/// A decimal number (any form Rust's `f64` parser takes, `nan` and `inf` included: the callers
/// check finiteness after narrowing to `f32`).
pub(crate) fn number(token: &[u8]) -> Option<f64> {
    core::str::from_utf8(token).ok()?.parse().ok()
}

/// A decimal integer.
pub(crate) fn integer(token: &[u8]) -> Option<i64> {
    core::str::from_utf8(token).ok()?.parse().ok()
}

/// A coordinate as `f32`, or why it is not one (not finite, also after narrowing from `f64`).
pub(crate) fn coordinate(value: f64) -> Result<f32, String> {
    let narrow = value as f32;
    if narrow.is_finite() {
        Ok(narrow)
    } else {
        Err(format!("coordinate {value} is not a finite f32"))
    }
}
