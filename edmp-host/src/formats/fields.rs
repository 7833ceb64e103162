//! Reading JSON fields with the path of each: the errors of every reader name the bad field
//! by its JSON path (`obstacles[3].quaternion: norm 0.71, expected 1`).

use edmp_core::scene::QUATERNION_NORM_TOLERANCE;
use serde_json::{Map, Value};
use std::fmt;

/// A field of the input that is wrong, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputError {
    path: String,
    message: String,
}

impl InputError {
    pub(crate) fn at(path: &str, message: impl Into<String>) -> Self {
        Self {
            path: path.to_string(),
            message: message.into(),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

pub(crate) fn object<'a>(v: &'a Value, path: &str, allowed: &[&str]) -> Result<&'a Map<String, Value>, InputError> {
    let map = v
        .as_object()
        .ok_or_else(|| InputError::at(path, "expected an object"))?;
    for key in map.keys() {
        if !allowed.contains(&key.as_str()) {
            let at = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            return Err(InputError::at(
                &at,
                format!("unknown field (expected one of: {})", allowed.join(", ")),
            ));
        }
    }
    Ok(map)
}

pub(crate) fn field<'a>(map: &'a Map<String, Value>, path: &str, key: &str) -> Result<(&'a Value, String), InputError> {
    let at = if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    };
    map.get(key)
        .map(|v| (v, at.clone()))
        .ok_or_else(|| InputError::at(&at, "missing"))
}

pub(crate) fn number(v: &Value, path: &str) -> Result<f32, InputError> {
    let x = v
        .as_f64()
        .ok_or_else(|| InputError::at(path, format!("expected a number, found {v}")))?;
    let y = x as f32;
    if !y.is_finite() {
        return Err(InputError::at(path, format!("{x} is not a finite f32")));
    }
    Ok(y)
}

pub(crate) fn numbers<const K: usize>(v: &Value, path: &str) -> Result<[f32; K], InputError> {
    let items = v
        .as_array()
        .ok_or_else(|| InputError::at(path, format!("expected an array of {K} numbers")))?;
    if items.len() != K {
        return Err(InputError::at(
            path,
            format!("expected {K} numbers, found {}", items.len()),
        ));
    }
    let mut out = [0.0; K];
    for (i, (slot, item)) in out.iter_mut().zip(items).enumerate() {
        *slot = number(item, &format!("{path}[{i}]"))?;
    }
    Ok(out)
}

pub(crate) fn quaternion(v: &Value, path: &str) -> Result<[f32; 4], InputError> {
    let q = numbers::<4>(v, path)?;
    let norm = q.iter().map(|x| x * x).sum::<f32>().sqrt();
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(InputError::at(path, format!("norm {norm:.2}, expected 1")));
    }
    Ok(q)
}
