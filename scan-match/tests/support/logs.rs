//! Loading the shared recordings into front-end inputs, for the example, the bench and the
//! real-data tests (included with `#[path]`: lidar-replay is a dev-dependency only).

#![allow(dead_code)]

use std::path::Path;

use anyhow::{Context, Result};
use lidar_replay::{
    Degradation, LOG_ODOMETRY_NOISE, LogFormat, LogRecord, OdometryCovariance, ReorderConfig,
    open_log,
};
use nalgebra::Matrix3;
use scan_match::{OdometryInput, ScanInput};
use slam_geom::ScanGeometry;
use stage_kit::odometry_buffer::{OdometryBuffer, OdometryReading};

/// One scan of a log with the odometry paired to it as feature-proc pairs it: interpolated
/// to the scan's stamp between the readings around it (a FLASER line's own odometry has
/// the scan's stamp; a log with ODOM lines has its readings between the scans).
#[derive(Debug, Clone)]
pub struct LoggedScan {
    /// The stamp the scan is processed under (stamps increase).
    pub stamp_ns: u64,
    /// The log's own stamp, which its relations name: `stamp_ns` unless the replay
    /// re-stamped a scan stamped late.
    pub log_stamp_ns: u64,
    pub geometry: ScanGeometry,
    pub ranges: Vec<f32>,
    /// Where the sensor sits on the robot.
    pub robot_from_sensor: slam_geom::Pose2,
    /// The sensor's odometry (the robot's, carried to the mount as feature-proc does).
    pub odometry: Option<OdometryInput>,
}

impl LoggedScan {
    pub fn input(&self, with_odometry: bool) -> ScanInput<'_> {
        ScanInput {
            stamp_ns: self.stamp_ns,
            geometry: self.geometry,
            ranges: &self.ranges,
            odometry: if with_odometry { self.odometry } else { None },
        }
    }
}

/// `geometry` as feature-proc gets it: the message carries it in `f32`s.
fn as_sent(geometry: &ScanGeometry) -> ScanGeometry {
    let sent = |value: f64| f64::from(value as f32);
    ScanGeometry {
        angle_min: sent(geometry.angle_min),
        angle_increment: sent(geometry.angle_increment),
        time_increment: sent(geometry.time_increment),
        scan_time: sent(geometry.scan_time),
        range_min: sent(geometry.range_min),
        range_max: sent(geometry.range_max),
    }
}

/// Reads at most `limit` scans of a log, each with the odometry at its stamp and that
/// odometry's covariance as lidar-replay publishes it (a random walk with the motion).
pub fn load(path: &Path, format: LogFormat, limit: usize) -> Result<Vec<LoggedScan>> {
    load_degraded(path, format, limit, Degradation::NONE)
}

/// [`load`] for the harder version of the log that lidar-replay makes with `degradation`:
/// the scans it leaves out are not read, the ranges beyond its reach are no-returns (all
/// the odometry is kept).
pub fn load_degraded(
    path: &Path,
    format: LogFormat,
    limit: usize,
    degradation: Degradation,
) -> Result<Vec<LoggedScan>> {
    let reader = open_log(format, path, ReorderConfig::default())
        .with_context(|| format!("opening {}", path.display()))?;
    if let Some(verdict) = reader.odometry_verdict() {
        eprintln!("{}", verdict.describe());
    }
    if let Some(order) = reader
        .order_verdict()
        .and_then(|verdict| verdict.describe())
    {
        eprintln!("{order}");
    }
    let mut covariance = OdometryCovariance::new(LOG_ODOMETRY_NOISE);
    let mut track = OdometryBuffer::new();
    let mut scans = Vec::new();
    let mut index = 0;
    for record in reader {
        let Ok(record) = record else { continue };
        match record {
            LogRecord::Odometry(o) => {
                let c = covariance.update(o.pose());
                // A reading the pipeline would refuse (out of order, a repeated stamp) is
                // left out here too.
                let _ = track.push(OdometryReading {
                    stamp_ns: o.stamp_ns,
                    pose: o.pose(),
                    covariance: Matrix3::from_row_slice(&c),
                });
                // The last scan's odometry is final once a reading at or after it is in.
                if scans.len() >= limit
                    && scans
                        .last()
                        .is_none_or(|s: &LoggedScan| o.stamp_ns >= s.stamp_ns)
                {
                    break;
                }
            }
            LogRecord::Scan(_) if scans.len() >= limit => {}
            LogRecord::Scan(mut s) => {
                index += 1;
                if !degradation.keeps(index - 1) {
                    continue;
                }
                degradation.shorten(&mut s);
                scans.push(LoggedScan {
                    stamp_ns: s.stamp_ns,
                    log_stamp_ns: s.log_stamp_ns,
                    geometry: as_sent(&s.geometry),
                    ranges: s.ranges,
                    // The message carries the mount in f64: as it is.
                    robot_from_sensor: s.robot_from_sensor,
                    odometry: None,
                });
            }
        }
    }
    track.end();
    for scan in &mut scans {
        scan.odometry = track.at(scan.stamp_ns).reading().map(|reading| {
            OdometryInput::of_sensor(reading.pose, reading.covariance, &scan.robot_from_sensor)
        });
    }
    Ok(scans)
}
