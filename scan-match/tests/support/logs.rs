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

/// One scan of a log with the odometry paired to it: the latest odometry record at or
/// before it (a FLASER line yields its odometry just before its scan, same stamp).
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
    let mut covariance = OdometryCovariance::new(LOG_ODOMETRY_NOISE);
    let mut odometry: Option<OdometryInput> = None;
    let mut scans = Vec::new();
    let mut index = 0;
    for record in reader {
        let Ok(record) = record else { continue };
        match record {
            LogRecord::Odometry(o) => {
                let c = covariance.update(o.pose());
                odometry = Some(OdometryInput {
                    odom_from_robot: o.pose(),
                    covariance: Matrix3::from_row_slice(&c),
                });
            }
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
                    odometry,
                });
                if scans.len() >= limit {
                    break;
                }
            }
        }
    }
    Ok(scans)
}
