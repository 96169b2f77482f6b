//! The TUM trajectory format (`stamp x y z qx qy qz qw`, one pose a line), written as a run
//! grows and read back for scoring and tests.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use slam_geom::{format_stamp, parse_stamp_ns};

use crate::error::SinkError;
use slam_geom::Pose2;

/// The unit quaternion `[qx, qy, qz, qw]` of a rotation by `yaw` about z.
pub fn yaw_quaternion(yaw: f64) -> [f64; 4] {
    let (s, c) = (yaw / 2.0).sin_cos();
    [0.0, 0.0, s, c]
}

/// One TUM line for a planar pose (z = 0), newline included. `f64`s print in Rust's
/// shortest round-trip form, so reading the line back gives the same numbers.
pub fn format_tum_line(stamp_ns: u64, pose: Pose2) -> String {
    let [qx, qy, qz, qw] = yaw_quaternion(pose.yaw);
    format!(
        "{} {} {} 0 {qx} {qy} {qz} {qw}\n",
        format_stamp(stamp_ns),
        pose.x,
        pose.y
    )
}

/// Appends poses to a TUM file, each line flushed to the kernel as it is written.
///
/// Durability: a trajectory is *appended* line by line instead of being written to a
/// temporary name and renamed like the other results, because a killed run must keep the
/// poses it had. Each line goes to the kernel in one `write` call on an unbuffered file, so
/// a killed process leaves only whole lines; a power cut or a full disk can still cut the
/// last line short, which is why [`read_tum`] skips a final line without a newline.
#[derive(Debug)]
pub struct TumWriter {
    // Deliberately unbuffered: a BufWriter would hold lines back and could split one across
    // two writes, so a killed run would lose poses or leave half a line.
    file: File,
    path: PathBuf,
}

impl TumWriter {
    /// Creates (or empties) the file at `path`.
    pub fn create(path: &Path) -> Result<Self, SinkError> {
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)
            .map_err(|e| SinkError::io("create", path, e))?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Appends one pose as one line, in one write.
    pub fn append(&mut self, stamp_ns: u64, pose: Pose2) -> Result<(), SinkError> {
        let line = format_tum_line(stamp_ns, pose);
        self.file
            .write_all(line.as_bytes())
            .map_err(|e| SinkError::io("append to", &self.path, e))
    }

    /// Forces what was written onto the disk, for the end of a run.
    pub fn sync(&self) -> Result<(), SinkError> {
        self.file
            .sync_all()
            .map_err(|e| SinkError::io("sync", &self.path, e))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// One pose read from a TUM file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TumPose {
    pub stamp_ns: u64,
    pub position: [f64; 3],
    /// `[qx, qy, qz, qw]`.
    pub orientation: [f64; 4],
}

impl TumPose {
    /// The rotation about z, for the planar poses this crate writes.
    pub fn yaw(&self) -> f64 {
        let [qx, qy, qz, qw] = self.orientation;
        (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz))
    }
}

/// Reads a TUM file. Blank lines and `#` comments are skipped, and so is a last line without
/// a newline (a line cut short by a crash); any other malformed line is an error naming it.
pub fn read_tum(path: &Path) -> Result<Vec<TumPose>, SinkError> {
    let text = fs::read_to_string(path).map_err(|e| SinkError::io("read", path, e))?;
    parse_tum(&text).map_err(|(line, reason)| SinkError::Malformed {
        path: path.to_path_buf(),
        line,
        reason,
    })
}

/// Parses TUM text; an error is `(1-based line number, reason)`.
fn parse_tum(text: &str) -> Result<Vec<TumPose>, (usize, String)> {
    let mut lines: Vec<&str> = text.split('\n').collect();
    // After the last '\n' comes either "" or an unterminated, possibly truncated line.
    lines.pop();
    let mut poses = Vec::with_capacity(lines.len());
    for (index, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        poses.push(parse_line(line).map_err(|reason| (index + 1, reason))?);
    }
    Ok(poses)
}

fn parse_line(line: &str) -> Result<TumPose, String> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    let [stamp, rest @ ..] = fields.as_slice() else {
        return Err("empty line".to_owned());
    };
    if rest.len() != 7 {
        return Err(format!("expected 8 fields, found {}", fields.len()));
    }
    let stamp_ns = parse_stamp_ns(stamp).map_err(|e| e.to_string())?;
    let mut numbers = [0.0; 7];
    for (number, field) in numbers.iter_mut().zip(rest) {
        *number = field
            .parse::<f64>()
            .map_err(|_| format!("{field:?} is not a number"))?;
    }
    let [x, y, z, qx, qy, qz, qw] = numbers;
    Ok(TumPose {
        stamp_ns,
        position: [x, y, z],
        orientation: [qx, qy, qz, qw],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn malformed_line_is_reported_with_its_number() {
        let text = "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n";
        let err = parse_tum(text).err();
        assert_eq!(err.map(|(line, _)| line), Some(3));
        let err = parse_tum("1.0 0 x 0 0 0 0 1\n").err();
        assert_eq!(err.map(|(line, _)| line), Some(1));
    }
}
