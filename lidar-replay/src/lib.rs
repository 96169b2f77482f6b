//! # lidar-replay
//!
//! Recorded lidar logs replayed onto the pipeline's topics exactly as a live driver would
//! publish them: `LaserScan` on the scan topic and, where the log has it, `Odometry` before
//! the scan it goes with. The `lidar-replay` process is a thin shell around this library.
//!
//! * Readers ([`SeedCsvReader`], [`CarmenReader`], or [`LogReader`] over either) yield
//!   [`LogRecord`]s in publishing order; a malformed line is a [`LineError`] naming its line,
//!   and reading goes on after it.
//! * A CARMEN log that is not quite in time order is put in order within a bounded window of
//!   log time ([`reorder`], [`ReorderConfig`]); what cannot be placed is dropped and counted.
//!   Its scans keep the log's order instead when the scans show that some were stamped late
//!   ([`scan_order`]): those are re-stamped, their own stamps travelling with them for the
//!   run's results.
//! * [`ReplaySummary`] is the block a replay ends with: everything skipped, reordered or
//!   dropped, and why.
//! * A [`Degradation`] makes a harder version of a log on the fly: every n-th scan, ranges
//!   cut to a shorter sensor's; what it left out is in the summary, not counted as lost.
//! * ROS 2 bags ([`rosbag`]): a rosbag2 directory (MCAP or SQLite3 storage) or a bare
//!   `.mcap`, their `sensor_msgs/msg/LaserScan`, odometry (`nav_msgs/msg/Odometry` or
//!   `/tf`) and the laser's mount from `/tf_static`, as one more [`LogReader`].
//! * [`open_log`] refuses a file that is not of its format ([`check_format`]) before anything
//!   is published.
//! * No input can fill the memory or hold up a stop: a line longer than [`MAX_LINE_BYTES`]
//!   is refused (and reading goes on at its end), and [`open_log_until`] takes a stop flag
//!   the reading honours between reads, even within an endless line.
//! * Stamps are the log's own, parsed to nanoseconds exactly ([`slam_geom::parse_stamp_ns`]); the
//!   seed-hall recording has none and is stamped at a nominal 10 Hz
//!   ([`seed_csv::NOMINAL_PERIOD_NS`]).
//! * Ranges follow REP 117 (NaN = error, +inf = no return) in the sensor frame of
//!   docs/CONVENTIONS.md (x forward, y left).
//! * A replay goes in lockstep (rate 0) or at the log's pace scaled by a speed factor
//!   ([`check_rate`]; `stage_kit::pacing::Pacer` keeps the time);
//!   [`fill_scan`] and [`fill_odometry`] write the messages in place, the odometry with a
//!   covariance that grows with the motion ([`OdometryCovariance`]), as the logs give none.

pub mod carmen;
mod degradation;
mod error;
mod fill;
mod format;
mod lines;
pub mod odometry_judge;
mod odometry_noise;
mod pacing;
mod record;
pub mod reorder;
pub mod rosbag;
pub mod scan_order;
pub mod seed_csv;
mod start;
mod summary;
#[cfg(test)]
mod test_log;

pub use carmen::{CarmenReader, OdometryChoice, OdometrySource};
pub use degradation::{Degradation, DegradationError};
pub use error::{CheckError, LineError, Malformation, OpenError, ReadError};
pub use fill::{ODOMETRY_FRAME, SCAN_FRAME, fill_odometry, fill_scan};
pub use format::{
    LOG_INPUT, LogFormat, LogReader, SNIFF_BYTES, SNIFF_LINES, check_format, check_format_until,
    input_kind, open_bag_until, open_log, open_log_until,
};
pub use lines::{MAX_LINE_BYTES, StopFlag};
pub use odometry_judge::Verdict;
pub use odometry_noise::LOG_ODOMETRY_NOISE;
pub use pacing::{RATE_RANGE, SPEED_FACTOR, check_rate, parse_rate};
pub use record::{LogRecord, OdometryRecord, ScanGeometry, ScanRecord};
pub use reorder::{Records, ReorderConfig, ReorderCounts, ScanOrder};
pub use scan_order::OrderVerdict;
pub use seed_csv::SeedCsvReader;
pub use stage_kit::odometry_covariance::{OdometryCovariance, OdometryNoise};
pub use summary::{ReplaySummary, SUMMARY_HEAD};
