//! Scans as `foxglove.LaserScan`, with what that schema lacks so that a scan can be rebuilt
//! exactly from its record.

use schemars::JsonSchema;
use serde::Serialize;
use serde::ser::SerializeSeq;

use crate::geometry::Pose;
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// A scan: Foxglove's fields first (`timestamp` .. `intensities`), then ours.
///
/// JSON has no NaN or infinity, and Foxglove's `ranges` are numbers: a non-finite range
/// (REP 117: NaN error, +inf no return, -inf too close) is written as 0 there, which the
/// viewer draws at the sensor, and its index is listed under its kind, so nothing is lost.
#[derive(Debug, Serialize, JsonSchema)]
pub struct ScanMessage<'a> {
    pub timestamp: Time,
    pub frame_id: &'a str,
    /// The sensor sits at the origin of its frame.
    pub pose: Pose,
    pub start_angle: f64,
    pub end_angle: f64,
    #[schemars(with = "Vec<f32>")]
    pub ranges: FiniteRanges<'a>,
    pub intensities: &'a [f32],
    // Ours from here on.
    pub seq: u64,
    pub sent_ns: u64,
    /// As sent (f32), so the bearings can be rebuilt bit for bit.
    pub angle_min: f32,
    pub angle_increment: f32,
    pub time_increment: f32,
    pub scan_time: f32,
    pub range_min: f32,
    pub range_max: f32,
    /// Indices of the beams whose range is NaN, +inf and -inf.
    pub nan: Vec<u32>,
    pub inf: Vec<u32>,
    pub neg_inf: Vec<u32>,
}

impl ChannelMessage for ScanMessage<'_> {
    const TOPIC: &'static str = "/lidar/scan";
    const SCHEMA: &'static str = "foxglove.LaserScan";
}

/// Ranges with every non-finite one written as 0.
#[derive(Debug, Clone, Copy)]
pub struct FiniteRanges<'a>(pub &'a [f32]);

impl Serialize for FiniteRanges<'_> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(self.0.len()))?;
        for r in self.0 {
            seq.serialize_element(&if r.is_finite() { *r } else { 0.0 })?;
        }
        seq.end()
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
        let last = ranges.len().saturating_sub(1) as f64;
        let start = f64::from(scan.angle_min);
        Self {
            timestamp: Time::from_ns(scan.header.stamp_ns),
            frame_id: scan.header.frame_id(),
            pose: Pose::IDENTITY,
            start_angle: start,
            end_angle: start + last * f64::from(scan.angle_increment),
            ranges: FiniteRanges(ranges),
            intensities: scan.intensities(),
            seq: scan.header.seq,
            sent_ns: scan.header.sent_ns,
            angle_min: scan.angle_min,
            angle_increment: scan.angle_increment,
            time_increment: scan.time_increment,
            scan_time: scan.scan_time,
            range_min: scan.range_min,
            range_max: scan.range_max,
            nan,
            inf,
            neg_inf,
        }
    }
}
