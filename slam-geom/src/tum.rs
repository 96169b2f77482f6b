//! The TUM trajectory format: one pose a line, `stamp x y z qx qy qz qw`, stamps in decimal
//! seconds, `#` comments and blank lines allowed. Written by map-sink, read by the scorer,
//! the recorder's tests and the end-to-end tests, all through these functions.

use std::io;
use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::{Pose2, StampError, format_stamp, parse_stamp_ns};

/// One pose of a TUM file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TumPose {
    pub stamp_ns: u64,
    pub position: [f64; 3],
    /// `[qx, qy, qz, qw]`.
    pub orientation: [f64; 4],
}

impl TumPose {
    /// The rotation about z, for planar poses.
    pub fn yaw(&self) -> f64 {
        let [qx, qy, qz, qw] = self.orientation;
        (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz))
    }
}

/// A malformed TUM line: its 1-based number and what is wrong.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("line {line}: {problem}")]
pub struct TumError {
    pub line: usize,
    pub problem: TumProblem,
}

/// What is wrong with a TUM line.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TumProblem {
    #[error("{found} fields, expected 8 (stamp x y z qx qy qz qw)")]
    FieldCount { found: usize },
    #[error(transparent)]
    Stamp(#[from] StampError),
    #[error("{field}: {text:?} is not a finite number")]
    Number { field: &'static str, text: String },
}

/// The unit quaternion `[qx, qy, qz, qw]` of a rotation by `yaw` about z.
pub fn yaw_quaternion(yaw: f64) -> [f64; 4] {
    let (s, c) = (yaw / 2.0).sin_cos();
    [0.0, 0.0, s, c]
}

/// One TUM line for a planar pose (z = 0), newline included. `f64`s print in Rust's shortest
/// round-trip form and the stamp with nine decimals, so reading the line back gives the same
/// numbers.
pub fn format_tum_line(stamp_ns: u64, pose: &Pose2) -> String {
    let [qx, qy, qz, qw] = yaw_quaternion(pose.yaw);
    format!(
        "{} {} {} 0 {qx} {qy} {qz} {qw}\n",
        format_stamp(stamp_ns),
        pose.x,
        pose.y
    )
}

/// Parses one data line (not blank, not a comment).
pub fn parse_tum_line(line: &str) -> Result<TumPose, TumProblem> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    let [stamp, rest @ ..] = fields.as_slice() else {
        return Err(TumProblem::FieldCount { found: 0 });
    };
    if rest.len() != 7 {
        return Err(TumProblem::FieldCount {
            found: fields.len(),
        });
    }
    let stamp_ns = parse_stamp_ns(stamp)?;
    let mut numbers = [0.0; 7];
    for ((number, text), field) in numbers
        .iter_mut()
        .zip(rest)
        .zip(["x", "y", "z", "qx", "qy", "qz", "qw"])
    {
        *number = text
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| TumProblem::Number {
                field,
                text: (*text).to_owned(),
            })?;
    }
    let [x, y, z, qx, qy, qz, qw] = numbers;
    Ok(TumPose {
        stamp_ns,
        position: [x, y, z],
        orientation: [qx, qy, qz, qw],
    })
}

/// Parses a TUM file's text into its poses with their 1-based line numbers. Blank lines and
/// `#` comments are skipped. A last line without a newline is kept if it parses and dropped
/// if not: a writer cut off mid-line (a crash, a full disk) leaves exactly that, and the
/// poses before it are good.
pub fn parse_tum(text: &str) -> Result<Vec<(usize, TumPose)>, TumError> {
    let mut lines: Vec<&str> = text.split('\n').collect();
    // After the last '\n' comes either "" or an unterminated line.
    let unterminated = lines.pop().filter(|line| !line.trim().is_empty());
    let mut poses = Vec::with_capacity(lines.len() + 1);
    for (index, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let pose = parse_tum_line(line).map_err(|problem| TumError {
            line: index + 1,
            problem,
        })?;
        poses.push((index + 1, pose));
    }
    if let Some(line) = unterminated.map(str::trim)
        && !line.starts_with('#')
        && let Ok(pose) = parse_tum_line(line)
    {
        poses.push((lines.len() + 1, pose));
    }
    Ok(poses)
}

/// Why a TUM file could not be read.
#[derive(Debug, Error)]
pub enum TumReadError {
    // The cause is the source, not part of the message: `{:#}` would print it twice.
    #[error("cannot read {}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("{}, line {line}: {problem}", path.display())]
    Malformed {
        path: PathBuf,
        line: usize,
        problem: TumProblem,
    },
}

/// Reads a TUM file with [`parse_tum`]'s rules (a last line cut short by a crash is
/// dropped): its poses with their 1-based line numbers; a malformed line is an error naming
/// the file and the line.
pub fn read_tum(path: &Path) -> Result<Vec<(usize, TumPose)>, TumReadError> {
    let text = std::fs::read_to_string(path).map_err(|source| TumReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_tum(&text).map_err(|e| TumReadError::Malformed {
        path: path.to_path_buf(),
        line: e.line,
        problem: e.problem,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_lines_read_back_exactly() {
        let pose = Pose2::new(1.0 / 3.0, -2.5e-7, 2.9);
        let line = format_tum_line(1_134_864_629_895_182_000, &pose);
        assert!(line.starts_with("1134864629.895182000 0.3333333333333333 -0.00000025 0 0 0 "));
        let read = parse_tum(&line).unwrap();
        assert_eq!(read.len(), 1);
        let (number, tum) = read[0];
        assert_eq!(number, 1);
        assert_eq!(tum.stamp_ns, 1_134_864_629_895_182_000);
        assert_eq!(tum.position, [pose.x, pose.y, 0.0]);
        assert!((tum.yaw() - pose.yaw).abs() < 1e-15);
    }

    #[test]
    fn malformed_lines_are_named_and_a_cut_off_last_line_is_dropped() {
        let text = "# header\n\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n";
        let error = parse_tum(text).unwrap_err();
        assert_eq!(error.line, 4);
        assert_eq!(error.problem, TumProblem::FieldCount { found: 7 });
        let error = parse_tum("1.0 0 x 0 0 0 0 1\n").unwrap_err();
        assert_eq!(error.to_string(), "line 1: y: \"x\" is not a finite number");
        let error = parse_tum("1.0 0 nan 0 0 0 0 1\n").unwrap_err();
        assert!(matches!(
            error.problem,
            TumProblem::Number { field: "y", .. }
        ));
        let error = parse_tum("5. 0 0 0 0 0 0 1\n").unwrap_err();
        assert!(matches!(error.problem, TumProblem::Stamp(_)));
        // A crash mid-line: the complete lines stand.
        let cut = parse_tum("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0").unwrap();
        assert_eq!(cut.len(), 1);
        // A file whose writer left out the last newline keeps its last pose.
        let whole = parse_tum("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1").unwrap();
        assert_eq!(whole.len(), 2);
        assert_eq!(whole[1].0, 2);
    }

    #[test]
    fn a_file_is_read_and_its_errors_name_it() {
        let dir = std::env::temp_dir().join(format!("slam-geom-tum-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.tum");
        std::fs::write(&good, format_tum_line(5, &Pose2::new(1.0, 2.0, 0.5))).unwrap();
        let poses = read_tum(&good).unwrap();
        assert_eq!(poses.len(), 1);
        assert_eq!(poses[0].1.stamp_ns, 5);
        let bad = dir.join("bad.tum");
        std::fs::write(&bad, "# header\n1.0 0 0\n").unwrap();
        let error = read_tum(&bad).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "{}, line 2: 3 fields, expected 8 (stamp x y z qx qy qz qw)",
                bad.display()
            )
        );
        let missing = read_tum(&dir.join("missing.tum")).unwrap_err();
        assert!(matches!(missing, TumReadError::Io { .. }), "{missing}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
