//! Log records into the pipeline's shared-memory messages, filled in place.

use ipc_types::{CapacityError, Header, LaserScan, Odometry, Pose2};

use crate::record::{OdometryRecord, ScanRecord};

/// Frame of the scans, as a live driver names it.
pub const SCAN_FRAME: &str = "laser";
/// Frame of the odometry poses.
pub const ODOMETRY_FRAME: &str = "odom";

/// Writes `record` as scan number `seq` into a (zeroed) message.
pub fn fill_scan(scan: &mut LaserScan, seq: u64, record: &ScanRecord) -> Result<(), CapacityError> {
    scan.header = Header::new(seq, record.stamp_ns, SCAN_FRAME);
    scan.set_geometry(&record.geometry);
    scan.robot_from_sensor = record.robot_from_sensor.into();
    // Within the reordering window of each other, so far within an i64.
    scan.source_stamp_offset_ns = record.log_stamp_ns.wrapping_sub(record.stamp_ns) as i64;
    scan.set_beams(&record.ranges, &record.intensities)
}

/// Writes `record` with its row-major (x, y, yaw) `covariance` (see
/// [`stage_kit::odometry_covariance::OdometryCovariance`]) into a (zeroed) message. `seq` is that of the scan the pose
/// goes with: the scan of the same `FLASER` line, else the next scan to be published.
pub fn fill_odometry(
    message: &mut Odometry,
    seq: u64,
    record: &OdometryRecord,
    covariance: [f64; 9],
) {
    message.header = Header::new(seq, record.stamp_ns, ODOMETRY_FRAME);
    message.pose = Pose2::new(record.x, record.y, record.yaw);
    message.covariance = covariance;
    message.linear_velocity = record.linear_velocity;
    message.angular_velocity = record.angular_velocity;
}

#[cfg(test)]
mod tests {
    use ipc_types::Zeroable;

    use super::*;
    use crate::seed_csv::GEOMETRY;

    #[test]
    fn a_scan_fills_every_field() {
        let record = ScanRecord {
            line: 3,
            stamp_ns: 1_134_864_629_895_182_000,
            log_stamp_ns: 1_134_864_629_895_182_000,
            geometry: GEOMETRY,
            ranges: vec![1.0, f32::INFINITY, f32::NAN],
            intensities: Vec::new(),
            robot_from_sensor: slam_geom::Pose2::IDENTITY,
        };
        let mut scan = LaserScan::boxed_zeroed();
        fill_scan(&mut scan, 7, &record).unwrap();
        assert_eq!(scan.header.seq, 7);
        assert_eq!(scan.header.stamp_ns, 1_134_864_629_895_182_000);
        assert_eq!(scan.header.frame_id(), "laser");
        assert_eq!(scan.angle_min, GEOMETRY.angle_min as f32);
        assert_eq!(scan.range_max, 60.0);
        assert_eq!(scan.ranges()[..2], [1.0, f32::INFINITY]);
        assert!(scan.ranges()[2].is_nan());
        assert_eq!(scan.intensities(), [0.0; 3]);
        assert_eq!(scan.source_stamp_offset_ns, 0);
    }

    #[test]
    fn a_restamped_scan_carries_the_logs_own_stamp() {
        let record = ScanRecord {
            line: 9,
            stamp_ns: 1_000_000_000,
            log_stamp_ns: 1_700_000_000,
            geometry: GEOMETRY,
            ranges: vec![1.0],
            intensities: Vec::new(),
            robot_from_sensor: slam_geom::Pose2::IDENTITY,
        };
        let mut scan = LaserScan::boxed_zeroed();
        fill_scan(&mut scan, 0, &record).unwrap();
        assert_eq!(scan.header.stamp_ns, 1_000_000_000);
        assert_eq!(scan.source_stamp_offset_ns, 700_000_000);
        assert_eq!(scan.source_stamp_ns(), 1_700_000_000);
    }

    #[test]
    fn too_many_beams_are_an_error_not_a_panic() {
        let record = ScanRecord {
            line: 1,
            stamp_ns: 0,
            log_stamp_ns: 0,
            geometry: GEOMETRY,
            ranges: vec![1.0; ipc_types::MAX_BEAMS + 1],
            intensities: Vec::new(),
            robot_from_sensor: slam_geom::Pose2::IDENTITY,
        };
        assert!(fill_scan(&mut LaserScan::boxed_zeroed(), 0, &record).is_err());
    }

    #[test]
    fn odometry_fills_pose_covariance_and_velocities() {
        let record = OdometryRecord {
            line: 1,
            stamp_ns: 42,
            x: 1.0,
            y: -2.0,
            yaw: 0.5,
            linear_velocity: 0.3,
            angular_velocity: -0.1,
            log_covariance: [0.0; 9],
        };
        let mut message = Odometry::boxed_zeroed();
        let covariance = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5];
        fill_odometry(&mut message, 4, &record, covariance);
        assert_eq!(message.header.seq, 4);
        assert_eq!(message.header.stamp_ns, 42);
        assert_eq!(message.header.frame_id(), "odom");
        assert_eq!(message.pose, Pose2::new(1.0, -2.0, 0.5));
        assert_eq!(message.covariance, covariance);
        assert_eq!(message.linear_velocity, 0.3);
    }
}
