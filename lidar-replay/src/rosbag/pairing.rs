//! Odometry at each scan's stamp, as a driver that reads the odometry when its laser
//! fires would give it: the pose interpolated between the readings around the stamp
//! (`stage_kit::odometry_buffer`, the rule feature-proc pairs by), published right before
//! its scan with the scan's stamp, as a CARMEN `FLASER` line's reading is.

use std::collections::VecDeque;

use stage_kit::odometry_buffer::{OdometryAt, OdometryBuffer, OdometryReading};

use crate::record::{LogRecord, OdometryRecord, ScanRecord};

/// Records in stamp order in, each scan with its odometry out.
#[derive(Debug, Default)]
pub(crate) struct Pairing {
    readings: OdometryBuffer,
    /// (stamp, forward speed, turn rate) of the readings held, for the rates at a scan:
    /// those of the last reading at or before it.
    rates: VecDeque<(u64, f64, f64)>,
    /// Scans waiting for the reading at or after their stamp.
    waiting: VecDeque<ScanRecord>,
    ready: VecDeque<LogRecord>,
    /// Readings refused as not later than the one before (the window let them through at
    /// the same stamp as another source's).
    pub refused: u64,
}

impl Pairing {
    pub fn odometry(&mut self, record: OdometryRecord) {
        let reading = OdometryReading {
            stamp_ns: record.stamp_ns,
            pose: record.pose(),
            covariance: ipc_types::covariance_from_row_major(&record.log_covariance),
        };
        if self.readings.push(reading).is_err() {
            self.refused += 1;
            return;
        }
        self.rates.push_back((
            record.stamp_ns,
            record.linear_velocity,
            record.angular_velocity,
        ));
        self.release();
    }

    pub fn scan(&mut self, scan: ScanRecord) {
        self.waiting.push_back(scan);
        self.release();
    }

    /// No more odometry will come: every scan waiting goes out.
    pub fn end(&mut self) {
        self.readings.end();
        self.release();
    }

    pub fn next(&mut self) -> Option<LogRecord> {
        self.ready.pop_front()
    }

    /// Lets the oldest scans out with the pose the readings held give (odometry that
    /// stopped, or lags far behind) while more than `most` wait.
    pub fn limit_waiting(&mut self, most: usize) {
        while self.waiting.len() > most {
            let Some(scan) = self.waiting.pop_front() else {
                return;
            };
            let reading = self.readings.at(scan.stamp_ns).reading();
            self.emit(scan, reading);
        }
    }

    fn release(&mut self) {
        while let Some(scan) = self.waiting.front() {
            let reading = match self.readings.at(scan.stamp_ns) {
                OdometryAt::NotYet { .. } => return,
                OdometryAt::Final(reading) => Some(reading),
                OdometryAt::NoReadings => None,
            };
            if let Some(scan) = self.waiting.pop_front() {
                self.emit(scan, reading);
            }
        }
    }

    /// The scan, after the odometry `reading` at its stamp if there is one.
    fn emit(&mut self, scan: ScanRecord, reading: Option<OdometryReading>) {
        let stamp = scan.stamp_ns;
        if let Some(reading) = reading {
            let (linear_velocity, angular_velocity) = self
                .rates
                .iter()
                .rev()
                .find(|(at, _, _)| *at <= stamp)
                .or(self.rates.front())
                .map_or((0.0, 0.0), |&(_, v, w)| (v, w));
            self.ready.push_back(LogRecord::Odometry(OdometryRecord {
                line: scan.line,
                stamp_ns: stamp,
                x: reading.pose.x,
                y: reading.pose.y,
                yaw: reading.pose.yaw,
                linear_velocity,
                angular_velocity,
                log_covariance: ipc_types::covariance_to_row_major(&reading.covariance),
            }));
        }
        self.readings.forget_before(stamp);
        let keep_from = self
            .rates
            .iter()
            .rposition(|(at, _, _)| *at <= stamp)
            .unwrap_or(0);
        self.rates.drain(..keep_from);
        self.ready.push_back(LogRecord::Scan(scan));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::ScanGeometry;
    use slam_geom::Pose2;

    fn scan(stamp_ns: u64) -> ScanRecord {
        ScanRecord {
            line: stamp_ns,
            stamp_ns,
            log_stamp_ns: stamp_ns,
            geometry: ScanGeometry {
                angle_min: 0.0,
                angle_increment: 0.1,
                time_increment: 0.0,
                scan_time: 0.0,
                range_min: 0.0,
                range_max: 10.0,
            },
            ranges: vec![1.0],
            intensities: Vec::new(),
            robot_from_sensor: Pose2::IDENTITY,
        }
    }

    fn odometry(stamp_ns: u64, x: f64, variance: f64) -> OdometryRecord {
        OdometryRecord {
            line: stamp_ns,
            stamp_ns,
            x,
            y: 0.0,
            yaw: 0.0,
            linear_velocity: x,
            angular_velocity: 0.0,
            log_covariance: [variance, 0.0, 0.0, 0.0, variance, 0.0, 0.0, 0.0, variance],
        }
    }

    fn drain(pairing: &mut Pairing) -> Vec<LogRecord> {
        std::iter::from_fn(|| pairing.next()).collect()
    }

    #[test]
    fn a_scan_waits_for_the_reading_after_it_and_gets_the_pose_between() {
        let mut pairing = Pairing::default();
        pairing.odometry(odometry(100, 1.0, 0.1));
        pairing.scan(scan(150));
        assert!(
            drain(&mut pairing).is_empty(),
            "the reading after 150 has not come"
        );
        pairing.odometry(odometry(200, 2.0, 0.3));
        let out = drain(&mut pairing);
        let [LogRecord::Odometry(at_scan), LogRecord::Scan(published)] = &out[..] else {
            panic!("{out:?}");
        };
        assert_eq!(published.stamp_ns, 150);
        assert_eq!(at_scan.stamp_ns, 150);
        assert!((at_scan.x - 1.5).abs() < 1e-12);
        assert!((at_scan.log_covariance[0] - 0.2).abs() < 1e-12);
        // The rates of the reading before the scan.
        assert_eq!(at_scan.linear_velocity, 1.0);
    }

    #[test]
    fn at_the_end_the_last_scans_go_out_and_without_odometry_alone() {
        let mut pairing = Pairing::default();
        pairing.odometry(odometry(100, 1.0, 0.0));
        pairing.odometry(odometry(200, 2.0, 0.0));
        pairing.scan(scan(250));
        assert!(drain(&mut pairing).is_empty());
        pairing.end();
        let out = drain(&mut pairing);
        let [LogRecord::Odometry(at_scan), LogRecord::Scan(_)] = &out[..] else {
            panic!("{out:?}");
        };
        // Extrapolated at the last readings' speed.
        assert!((at_scan.x - 2.5).abs() < 1e-12);

        let mut none = Pairing::default();
        none.scan(scan(10));
        none.end();
        assert!(matches!(&drain(&mut none)[..], [LogRecord::Scan(_)]));
    }

    #[test]
    fn a_repeated_reading_is_refused_and_counted() {
        let mut pairing = Pairing::default();
        pairing.odometry(odometry(100, 1.0, 0.0));
        pairing.odometry(odometry(100, 5.0, 0.0));
        assert_eq!(pairing.refused, 1);
    }

    #[test]
    fn scans_do_not_wait_without_bound_for_odometry_that_stopped() {
        let mut pairing = Pairing::default();
        pairing.odometry(odometry(100, 1.0, 0.0));
        pairing.odometry(odometry(200, 2.0, 0.0));
        for stamp in 1..=5 {
            pairing.scan(scan(1000 * stamp));
            pairing.limit_waiting(3);
        }
        let out = drain(&mut pairing);
        // Two let out, each with the pose held (extrapolated no further than the limit).
        assert_eq!(out.len(), 4, "{out:?}");
        assert!(matches!(out[0], LogRecord::Odometry(_)));
    }
}
