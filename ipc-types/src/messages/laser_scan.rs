//! One sweep of a planar lidar, modelled on ROS `sensor_msgs/LaserScan`.

use std::borrow::Cow;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use slam_geom::ScanGeometry;
use zerocopy::FromZeros;

use crate::capacity::{CapacityError, MAX_BEAMS, fill, used};
use crate::header::Header;
use crate::messages::pose::Pose2;

/// One sweep of a planar lidar.
///
/// Beam `i` has bearing `angle_min + i * angle_increment` in the sensor frame (x forward,
/// y left). Invalid readings follow REP 117: NaN = measurement error, +inf = no return,
/// -inf = too close. A consumer treats any non-finite range, or one outside
/// `[range_min, range_max]`, as invalid.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
#[type_name("slam::LaserScan::v3")]
pub struct LaserScan {
    pub header: Header,
    /// Bearing of the first beam, radians.
    pub angle_min: f32,
    /// Bearing step between beams, radians (negative for a clockwise sensor).
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Where the sensor sits on the robot: the sensor frame in the robot frame (`base_link`).
    /// All zero for a sensor at the robot's origin, as the simulator's.
    pub robot_from_sensor: Pose2,
    /// The source's own stamp of this scan minus `header.stamp_ns`, nanoseconds: 0 unless
    /// the source re-stamped the scan so that stamps increase on the topic (a log's scan
    /// stamped late, replayed in the log's order). The pipeline works by `header.stamp_ns`;
    /// what a run writes for the user carries the source's stamp ([`Self::source_stamp_ns`]),
    /// the one the log's ground truth names.
    pub source_stamp_offset_ns: i64,
    /// Beams used in `ranges` and `intensities`.
    pub beam_count: u32,
    /// Keeps the layout free of implicit padding; always 0.
    pub reserved: u32,
    /// Ranges in metres; only the first `beam_count` are meaningful.
    pub ranges: [f32; MAX_BEAMS],
    /// Intensities in sensor units (0 when the sensor gives none).
    pub intensities: [f32; MAX_BEAMS],
}

impl LaserScan {
    /// Where the beams point and which ranges are valid, in `f64`.
    pub fn geometry(&self) -> ScanGeometry {
        ScanGeometry {
            angle_min: f64::from(self.angle_min),
            angle_increment: f64::from(self.angle_increment),
            time_increment: f64::from(self.time_increment),
            scan_time: f64::from(self.scan_time),
            range_min: f64::from(self.range_min),
            range_max: f64::from(self.range_max),
        }
    }

    /// Sets the angles, timing and range limits (rounded to the message's `f32`).
    pub fn set_geometry(&mut self, geometry: &ScanGeometry) {
        self.angle_min = geometry.angle_min as f32;
        self.angle_increment = geometry.angle_increment as f32;
        self.time_increment = geometry.time_increment as f32;
        self.scan_time = geometry.scan_time as f32;
        self.range_min = geometry.range_min as f32;
        self.range_max = geometry.range_max as f32;
    }

    /// The stamp the source gave this scan: `header.stamp_ns` unless the source re-stamped
    /// it (see [`Self::source_stamp_offset_ns`]).
    pub fn source_stamp_ns(&self) -> u64 {
        self.header
            .stamp_ns
            .saturating_add_signed(self.source_stamp_offset_ns)
    }

    /// The ranges of the beams in use.
    pub fn ranges(&self) -> &[f32] {
        used(&self.ranges, self.beam_count)
    }

    /// The intensities of the beams in use.
    pub fn intensities(&self) -> &[f32] {
        used(&self.intensities, self.beam_count)
    }

    /// Replaces the beams; intensities default to zero when `intensities` is empty.
    pub fn set_beams(&mut self, ranges: &[f32], intensities: &[f32]) -> Result<(), CapacityError> {
        if !intensities.is_empty() && intensities.len() != ranges.len() {
            return Err(CapacityError {
                what: "intensities (must match the ranges)",
                len: intensities.len(),
                capacity: ranges.len(),
            });
        }
        self.beam_count = fill("ranges", &mut self.ranges, ranges)?;
        // `fill` checked the capacity, so the ranges' length indexes the intensities too.
        self.intensities[..ranges.len()].fill(0.0);
        fill("intensities", &mut self.intensities, intensities)?;
        Ok(())
    }

    /// The compact, serialisable form of this scan (only the beams in use).
    pub fn to_record(&self) -> LaserScanRecord<'_> {
        LaserScanRecord {
            header: self.header,
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            time_increment: self.time_increment,
            scan_time: self.scan_time,
            range_min: self.range_min,
            range_max: self.range_max,
            robot_from_sensor: self.robot_from_sensor,
            source_stamp_offset_ns: self.source_stamp_offset_ns,
            ranges: Cow::Borrowed(self.ranges()),
            intensities: Cow::Borrowed(self.intensities()),
        }
    }

    /// Rebuilds a scan from its record, on the heap.
    pub fn from_record(record: &LaserScanRecord<'_>) -> Result<Box<Self>, CapacityError> {
        let mut scan = <Self as crate::Zeroable>::boxed_zeroed();
        scan.header = record.header;
        scan.angle_min = record.angle_min;
        scan.angle_increment = record.angle_increment;
        scan.time_increment = record.time_increment;
        scan.scan_time = record.scan_time;
        scan.range_min = record.range_min;
        scan.range_max = record.range_max;
        scan.robot_from_sensor = record.robot_from_sensor;
        scan.source_stamp_offset_ns = record.source_stamp_offset_ns;
        scan.set_beams(&record.ranges, &record.intensities)?;
        Ok(scan)
    }
}

/// A [`LaserScan`] without its unused capacity: what gets written to disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LaserScanRecord<'a> {
    pub header: Header,
    pub angle_min: f32,
    pub angle_increment: f32,
    pub time_increment: f32,
    pub scan_time: f32,
    pub range_min: f32,
    pub range_max: f32,
    /// Absent in records written before the mount was sent: the robot's origin.
    #[serde(default)]
    pub robot_from_sensor: Pose2,
    /// Absent in records written before scans could be re-stamped: 0.
    #[serde(default)]
    pub source_stamp_offset_ns: i64,
    pub ranges: Cow<'a, [f32]>,
    pub intensities: Cow<'a, [f32]>,
}

impl LaserScanRecord<'_> {
    /// The same record owning its beams, to keep after the scan it was made from is gone.
    pub fn into_owned(self) -> LaserScanRecord<'static> {
        LaserScanRecord {
            ranges: Cow::Owned(self.ranges.into_owned()),
            intensities: Cow::Owned(self.intensities.into_owned()),
            ..self
        }
    }
}

impl Serialize for LaserScan {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_record().serialize(serializer)
    }
}
