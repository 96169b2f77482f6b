//! The line format both inputs share: whitespace-separated fields, `#` comments, blank
//! lines, and errors that name the line.

use std::path::Path;

use crate::error::EvalError;
use slam_geom::parse_stamp_ns;

/// Reads `path` and hands each data line (1-based number, fields) to `parse`; a reason it
/// returns becomes [`EvalError::Malformed`] naming the line.
pub(crate) fn parse_lines<T>(
    path: &Path,
    kind: &stage_kit::InputKind,
    mut parse: impl FnMut(&[&str]) -> Result<T, String>,
) -> Result<Vec<(usize, T)>, EvalError> {
    let text = kind.read_to_string(path)?;
    let mut items = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let item = parse(&fields).map_err(|reason| EvalError::Malformed {
            path: path.to_path_buf(),
            line: index + 1,
            reason,
        })?;
        items.push((index + 1, item));
    }
    Ok(items)
}

/// Checks the field count: `names` lists what each field is, for the message.
pub(crate) fn expect_fields(fields: &[&str], names: &str) -> Result<(), String> {
    let expected = names.split_whitespace().count();
    if fields.len() == expected {
        Ok(())
    } else {
        Err(format!(
            "{} fields, expected {expected} ({names})",
            fields.len()
        ))
    }
}

/// A finite number.
pub(crate) fn number(field: &str, what: &str) -> Result<f64, String> {
    field
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{what}: {field:?} is not a number"))
}

/// A stamp in seconds, in nanoseconds.
pub(crate) fn stamp(field: &str, what: &str) -> Result<u64, String> {
    parse_stamp_ns(field).map_err(|e| format!("{what}: {e}"))
}
