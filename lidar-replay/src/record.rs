//! What a log yields: scans and odometry, in log order, with the line they came from.

use slam_geom::Pose2;
pub use slam_geom::ScanGeometry;

/// One scan of a log, ranges already in REP 117 form (NaN = error, +inf = no return).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRecord {
    /// 1-based line of the log it was read from.
    pub line: u64,
    /// Acquisition time in the log's clock, nanoseconds: the stamp it is published with.
    pub stamp_ns: u64,
    /// The log's own stamp of the scan: `stamp_ns` unless the replay re-stamped a scan the
    /// log stamped late (see [`crate::reorder`]). What a run writes carries this one.
    pub log_stamp_ns: u64,
    pub geometry: ScanGeometry,
    /// Ranges in metres, beam by beam from `angle_min`.
    pub ranges: Vec<f32>,
    /// Intensities, one per beam, or empty when the log has none.
    pub intensities: Vec<f32>,
    /// Where the sensor sits on the robot (the identity when the log does not say).
    pub robot_from_sensor: Pose2,
}

/// One odometry pose of a log (`odom_from_robot`), yaw wrapped to `[-pi, pi)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryRecord {
    /// 1-based line of the log it was read from.
    pub line: u64,
    /// Time of the pose in the log's clock, nanoseconds.
    pub stamp_ns: u64,
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
    /// Forward speed, m/s (0 when the log does not say).
    pub linear_velocity: f64,
    /// Yaw rate, rad/s (0 when the log does not say).
    pub angular_velocity: f64,
    /// The pose's covariance as the log gives it, row-major over (x, y, yaw); all zero when
    /// it gives none. The replay adds it to the covariance its model of the odometry's
    /// noise grows along the motion ([`crate::OdometryCovariance`]).
    pub log_covariance: [f64; 9],
}

impl OdometryRecord {
    /// The pose `odom_from_robot`.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x, self.y, self.yaw)
    }
}

/// A record of a log, in the order it is to be published.
#[derive(Debug, Clone, PartialEq)]
pub enum LogRecord {
    Scan(ScanRecord),
    Odometry(OdometryRecord),
}

impl LogRecord {
    /// The record's time in the log's clock, nanoseconds.
    pub fn stamp_ns(&self) -> u64 {
        match self {
            Self::Scan(scan) => scan.stamp_ns,
            Self::Odometry(odometry) => odometry.stamp_ns,
        }
    }

    /// The 1-based line of the log it was read from.
    pub fn line(&self) -> u64 {
        match self {
            Self::Scan(scan) => scan.line,
            Self::Odometry(odometry) => odometry.line,
        }
    }
}
