//! # test-data
//!
//! Where the tests and benches of every crate find the shared real recordings, and the
//! seed-hall scans read by lidar-replay's own reader: a test of the recording sees the
//! geometry and the REP 117 ranges the pipeline replays, not a second reading of the file.
//!
//! The recordings are never copied into the repository (docs/CONVENTIONS.md, "Real data").
//!
//! Test support only (a dev-dependency): it panics where a test should fail.

use std::path::{Path, PathBuf};

pub use lidar_replay::ScanRecord;
use lidar_replay::{LogFormat, LogRecord, ReorderConfig, open_log};

/// The shared data directory: `$SLAM_DATA_DIR`, else `../shared/data` beside the workspace.
/// Not checked: a bench that can do without a recording looks for it itself.
pub fn data_dir() -> PathBuf {
    std::env::var_os("SLAM_DATA_DIR").map_or_else(
        || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data")),
        PathBuf::from,
    )
}

/// `relative` (a file or a directory) in the shared data directory. Panics, naming the
/// path, when it is not there: a test of a recording must not pass without it.
pub fn recording(relative: impl AsRef<Path>) -> PathBuf {
    let path = data_dir().join(relative);
    assert!(
        path.exists(),
        "the shared recording {} is missing: set SLAM_DATA_DIR to the shared data directory",
        path.display()
    );
    path
}

/// The seed-hall recording: 400 scans of a Hokuyo UTM-30LX-class lidar, 1081 ranges in
/// millimetres a line, no stamps, no odometry (its FORMAT.md).
pub fn seed_hall_csv() -> PathBuf {
    recording("seed-hall/scans.csv")
}

/// The directory of the CARMEN benchmark logs, each `NAME.clf` beside its ground-truth
/// `NAME.relations` (as slam-bench takes it).
pub fn carmen_dir() -> PathBuf {
    recording("carmen")
}

/// The CARMEN benchmark log `carmen/NAME.clf` (`aces`, `mit-csail`).
pub fn carmen_log(name: &str) -> PathBuf {
    recording(format!("carmen/{name}.clf"))
}

/// Every seed-hall scan as `lidar-replay --format seed-csv` publishes it: the sensor's
/// geometry, ranges in metres with the error codes as NaN and +inf, a nominal 10 Hz stamp.
/// Panics on a line the replay would skip: the tests count on all 400 scans.
pub fn seed_hall_scans() -> Vec<ScanRecord> {
    let path = seed_hall_csv();
    let log = open_log(LogFormat::SeedCsv, &path, ReorderConfig::default())
        .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
    log.map(|record| match record {
        Ok(LogRecord::Scan(scan)) => scan,
        Ok(LogRecord::Odometry(_)) => panic!("{}: odometry in a seed-hall log", path.display()),
        Err(e) => panic!("{}: {e:#}", path.display()),
    })
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[should_panic(expected = "no-such-recording.csv is missing: set SLAM_DATA_DIR")]
    fn a_missing_recording_is_named_with_the_variable_to_set() {
        recording("no-such-recording.csv");
    }
}
