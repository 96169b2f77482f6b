//! The seed-hall recording (shared data, `seed-hall/scans.csv`): 400 scans of a Hokuyo
//! UTM-30LX-class lidar in a large hall, 1081 ranges in millimetres each. See its FORMAT.md.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use slam_geom::ScanGeometry;

use crate::scan::ScanInput;

/// Beams per scan.
pub const BEAMS: usize = 1081;
/// Bearing of the first beam in the sensor frame. The recording's own frame has +y forward;
/// subtracting pi/2 puts forward on +x (docs/CONVENTIONS.md).
pub const ANGLE_MIN: f64 = -3.0 * PI / 4.0;
/// Bearing step, a quarter degree, counter-clockwise.
pub const ANGLE_INCREMENT: f64 = PI / 720.0;
/// Readings below 20 mm are the sensor's error codes (1 = no return, 19), not ranges.
pub const RANGE_MIN: f64 = 0.02;
/// Above the longest reading in the file (36.881 m).
pub const RANGE_MAX: f64 = 40.0;

/// Why the recording could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SeedHallError {
    #[error("cannot read {path}: {source} (set SLAM_DATA_DIR to the shared data directory)")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("line {line}, beam {beam}: {text:?} is not a range in millimetres")]
    Parse {
        line: usize,
        beam: usize,
        text: String,
    },
    #[error("line {line} has {found} ranges, {BEAMS} expected")]
    BeamCount { line: usize, found: usize },
}

/// The shared data directory: `$SLAM_DATA_DIR`, else `../shared/data` beside the workspace.
pub fn data_dir() -> PathBuf {
    std::env::var_os("SLAM_DATA_DIR").map_or_else(
        || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data")),
        PathBuf::from,
    )
}

/// Where the recording is expected: `data_dir()/seed-hall/scans.csv`.
pub fn default_path() -> PathBuf {
    data_dir().join("seed-hall").join("scans.csv")
}

/// Reads every scan, ranges in metres. Error codes are kept as their (tiny) values, which
/// fall below [`RANGE_MIN`] and are therefore invalid to any consumer (REP 117).
pub fn load(path: &Path) -> Result<Vec<Vec<f32>>, SeedHallError> {
    let text = std::fs::read_to_string(path).map_err(|source| SeedHallError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut scans = Vec::new();
    for (index, row) in text.lines().enumerate() {
        let line = index + 1;
        if row.trim().is_empty() {
            continue;
        }
        let mut ranges = Vec::with_capacity(BEAMS);
        for (beam, field) in row.split(',').enumerate() {
            let field = field.trim();
            let millimetres: u32 = field.parse().map_err(|_| SeedHallError::Parse {
                line,
                beam: beam + 1,
                text: field.to_owned(),
            })?;
            ranges.push(millimetres as f32 / 1000.0);
        }
        if ranges.len() != BEAMS {
            return Err(SeedHallError::BeamCount {
                line,
                found: ranges.len(),
            });
        }
        scans.push(ranges);
    }
    Ok(scans)
}

/// The recording's beam geometry around `ranges`.
pub fn scan_input(ranges: &[f32]) -> ScanInput<'_> {
    ScanInput {
        geometry: ScanGeometry {
            angle_min: ANGLE_MIN,
            angle_increment: ANGLE_INCREMENT,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: RANGE_MIN,
            range_max: RANGE_MAX,
        },
        ranges,
    }
}
