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
    pub stamp_ns: u64,
    pub geometry: ScanGeometry,
    pub ranges: Vec<f32>,
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
                    geometry: s.geometry,
                    ranges: s.ranges,
                    odometry: None,
                });
            }
        }
    }
    track.end();
    for scan in &mut scans {
        scan.odometry = track
            .at(scan.stamp_ns)
            .reading()
            .map(|reading| OdometryInput {
                odom_from_robot: reading.pose,
                covariance: reading.covariance,
            });
    }
    Ok(scans)
}
