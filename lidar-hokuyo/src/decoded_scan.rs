//! One decoded scan, ready to become a `LaserScan`.

use ipc_types::{CapacityError, Header, LaserScan};

use crate::geometry::RangingPlan;

/// A scan with everything a `LaserScan` needs.
#[derive(Debug, Clone, Copy)]
pub struct DecodedScan<'a> {
    /// Published scans before this one: 0, 1, 2, ... without gaps, across reconnections.
    pub seq: u64,
    /// Host time (CLOCK_REALTIME, ns) of the first beam.
    pub stamp_ns: u64,
    pub frame_id: &'a str,
    pub plan: &'a RangingPlan,
    /// Metres, REP 117 codes for errors.
    pub ranges: &'a [f32],
    /// Sensor units; empty when the sensor sends none.
    pub intensities: &'a [f32],
}

impl DecodedScan<'_> {
    /// Writes the scan into a (zeroed) `LaserScan`.
    pub fn fill(&self, scan: &mut LaserScan) -> Result<(), CapacityError> {
        scan.header = Header::new(self.seq, self.stamp_ns, self.frame_id);
        scan.set_geometry(&self.plan.geometry);
        scan.set_beams(self.ranges, self.intensities)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ScanRequest;
    use crate::scip::SensorParams;
    use ipc_types::Zeroable;

    #[test]
    fn fills_every_field() {
        let plan = RangingPlan::new(&SensorParams::utm_30lx(), &ScanRequest::default()).unwrap();
        let ranges = vec![1.5f32; 1081];
        let decoded = DecodedScan {
            seq: 7,
            stamp_ns: 123_456_789,
            frame_id: "laser",
            plan: &plan,
            ranges: &ranges,
            intensities: &[],
        };
        let mut scan = LaserScan::boxed_zeroed();
        decoded.fill(&mut scan).unwrap();
        assert_eq!(scan.header.seq, 7);
        assert_eq!(scan.header.stamp_ns, 123_456_789);
        assert_eq!(scan.header.frame_id(), "laser");
        assert_eq!(scan.angle_min, (-0.75 * std::f64::consts::PI) as f32);
        assert_eq!(scan.angle_increment, (std::f64::consts::PI / 720.0) as f32);
        assert_eq!(scan.scan_time, 0.025);
        assert_eq!(scan.range_min, 0.023);
        assert_eq!(scan.range_max, 60.0);
        assert_eq!(scan.ranges(), &ranges[..]);
        assert!(scan.intensities().iter().all(|&i| i == 0.0));
    }
}
