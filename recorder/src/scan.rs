//! Scans as `foxglove.LaserScan`, with what that schema lacks so that a scan can be rebuilt
//! exactly from its record; and the rebuilding.

use std::borrow::Cow;

use schemars::JsonSchema;
use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Serialize};
use slam_geom::ScanGeometry;

use crate::decode::DecodeError;
use crate::geometry::Pose;
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// A scan: Foxglove's fields first (`timestamp` .. `intensities`), then ours.
///
/// JSON has no NaN or infinity, and Foxglove's `ranges` are numbers: a non-finite range
/// (REP 117: NaN error, +inf no return, -inf too close) is written as 0 there, which the
/// viewer draws at the sensor, and its index is listed under its kind, so nothing is lost.
/// Each range is an `f32` written in its shortest form that reads back to the same `f32`.
#[derive(Debug, Serialize, Deserialize, JsonSchema)]
pub struct ScanMessage<'a> {
    pub timestamp: Time,
    pub frame_id: Cow<'a, str>,
    /// The sensor sits at the origin of its frame.
    pub pose: Pose,
    pub start_angle: f64,
    pub end_angle: f64,
    #[schemars(with = "Vec<f32>")]
    pub ranges: FiniteRanges<'a>,
    /// Empty when every beam's intensity is 0 (a sensor that gives none), as ROS's
    /// `sensor_msgs/LaserScan` asks; a scan rebuilt from it has zero intensities again.
    pub intensities: Cow<'a, [f32]>,
    // Ours from here on.
    pub seq: u64,
    pub sent_ns: u64,
    /// The angles, timing and range limits as sent: the message's `f32`s, exact in `f64`,
    /// so the scan is rebuilt bit for bit.
    #[serde(flatten)]
    pub geometry: ScanGeometry,
    /// Indices of the beams whose range is NaN, +inf and -inf.
    pub nan: Vec<u32>,
    pub inf: Vec<u32>,
    pub neg_inf: Vec<u32>,
    /// Where the sensor sits on the robot, `[x, y, yaw]` (absent in older recordings: the
    /// robot's origin).
    #[serde(default)]
    pub robot_from_sensor: [f64; 3],
    /// The source's own stamp of the scan minus `timestamp`, nanoseconds: 0 (and absent in
    /// older recordings) unless the source re-stamped the scan to keep stamps increasing.
    #[serde(default)]
    pub source_stamp_offset_ns: i64,
}

impl ChannelMessage for ScanMessage<'_> {
    const TOPIC: &'static str = "/lidar/scan";
    const SCHEMA: &'static str = "foxglove.LaserScan";
}

/// Ranges with every non-finite one written as 0.
#[derive(Debug, Clone)]
pub struct FiniteRanges<'a>(pub Cow<'a, [f32]>);

impl Serialize for FiniteRanges<'_> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(self.0.len()))?;
        for r in self.0.iter() {
            seq.serialize_element(&if r.is_finite() { *r } else { 0.0 })?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for FiniteRanges<'_> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Ranges;
        impl<'de> Visitor<'de> for Ranges {
            type Value = Vec<f32>;

            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("an array of ranges")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                // The hint comes from the input: trust it only up to a scan's capacity.
                let mut ranges =
                    Vec::with_capacity(seq.size_hint().unwrap_or(0).min(ipc_types::MAX_BEAMS));
                while let Some(r) = seq.next_element::<f32>()? {
                    ranges.push(r);
                }
                Ok(ranges)
            }
        }
        deserializer
            .deserialize_seq(Ranges)
            .map(|r| FiniteRanges(Cow::Owned(r)))
    }
}

impl<'a> ScanMessage<'a> {
    pub fn new(scan: &'a ipc_types::LaserScan) -> Self {
        let ranges = scan.ranges();
        let (mut nan, mut inf, mut neg_inf) = (Vec::new(), Vec::new(), Vec::new());
        for (i, r) in ranges.iter().enumerate() {
            // MAX_BEAMS is far below u32::MAX.
            let i = i as u32;
            if r.is_nan() {
                nan.push(i);
            } else if *r == f32::INFINITY {
                inf.push(i);
            } else if *r == f32::NEG_INFINITY {
                neg_inf.push(i);
            }
        }
        let intensities = scan.intensities();
        // Bit patterns, so that a -0.0 intensity is kept as it is.
        let intensities = if intensities.iter().all(|i| i.to_bits() == 0) {
            &[]
        } else {
            intensities
        };
        let geometry = scan.geometry();
        let last = ranges.len().saturating_sub(1) as f64;
        Self {
            timestamp: Time::from_ns(scan.header.stamp_ns),
            frame_id: Cow::Borrowed(scan.header.frame_id()),
            pose: Pose::IDENTITY,
            start_angle: geometry.angle_min,
            end_angle: geometry.angle_min + last * geometry.angle_increment,
            ranges: FiniteRanges(Cow::Borrowed(ranges)),
            intensities: Cow::Borrowed(intensities),
            seq: scan.header.seq,
            sent_ns: scan.header.sent_ns,
            geometry,
            nan,
            inf,
            neg_inf,
            robot_from_sensor: {
                let m = scan.robot_from_sensor;
                [m.x, m.y, m.yaw]
            },
            source_stamp_offset_ns: scan.source_stamp_offset_ns,
        }
    }

    /// The scan this message was made from, bit for bit (a NaN range comes back as
    /// `f32::NAN`, whatever its payload was), `flags` 0 (end-of-stream markers are not
    /// recorded).
    pub fn to_laser_scan(&self) -> Result<Box<ipc_types::LaserScan>, DecodeError> {
        let stamp_ns = self.timestamp.to_ns().ok_or(DecodeError::Stamp {
            sec: self.timestamp.sec,
            nsec: self.timestamp.nsec,
        })?;
        let mut ranges = self.ranges.0.to_vec();
        for (indices, value) in [
            (&self.nan, f32::NAN),
            (&self.inf, f32::INFINITY),
            (&self.neg_inf, f32::NEG_INFINITY),
        ] {
            for &i in indices {
                let slot = ranges.get_mut(i as usize).ok_or(DecodeError::BeamIndex {
                    index: i,
                    beams: self.ranges.0.len(),
                })?;
                *slot = value;
            }
        }
        let mut scan = <ipc_types::LaserScan as ipc_types::Zeroable>::boxed_zeroed();
        scan.header = ipc_types::Header::new(self.seq, stamp_ns, &self.frame_id);
        scan.header.sent_ns = self.sent_ns;
        scan.set_geometry(&self.geometry);
        let [x, y, yaw] = self.robot_from_sensor;
        scan.robot_from_sensor = ipc_types::Pose2::new(x, y, yaw);
        scan.source_stamp_offset_ns = self.source_stamp_offset_ns;
        scan.set_beams(&ranges, &self.intensities)?;
        Ok(scan)
    }
}
