//! Where the beams of a planar scan point, when they were taken, and which ranges are valid.

/// The geometry of a planar lidar's scan, as a `LaserScan` carries it (ROS
/// `sensor_msgs/LaserScan`; docs/CONVENTIONS.md): beam `i` has bearing
/// `angle_min + i * angle_increment` in the sensor frame (x forward, y left). Metres,
/// radians, seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "json-schema",
    derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)
)]
pub struct ScanGeometry {
    /// Bearing of the first beam, radians.
    pub angle_min: f64,
    /// Bearing step between beams, radians (counter-clockwise when positive).
    pub angle_increment: f64,
    /// Time between two beams, seconds (0 when unknown).
    pub time_increment: f64,
    /// Time between scans, seconds (0 when unknown).
    pub scan_time: f64,
    /// Shortest valid range, metres.
    pub range_min: f64,
    /// Longest valid range, metres.
    pub range_max: f64,
}

/// Why a [`ScanGeometry`] cannot place any beam.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ScanGeometryError {
    #[error("angle_min is not finite")]
    AngleMin,
    #[error("angle_increment is zero or not finite")]
    AngleIncrement,
    #[error("range_max is not above range_min")]
    RangeLimits,
}

impl ScanGeometry {
    /// The bearing of beam `index` in the sensor frame (not wrapped: a scan may span more
    /// than a turn's worth of bearings from `angle_min`).
    pub fn bearing(&self, index: usize) -> f64 {
        self.angle_min + index as f64 * self.angle_increment
    }

    /// `Err` when the bearings are not defined or no range could ever be valid.
    pub fn check(&self) -> Result<(), ScanGeometryError> {
        if !self.angle_min.is_finite() {
            return Err(ScanGeometryError::AngleMin);
        }
        if !self.angle_increment.is_finite() || self.angle_increment == 0.0 {
            return Err(ScanGeometryError::AngleIncrement);
        }
        if self.range_min.is_nan() || self.range_max.is_nan() || self.range_max <= self.range_min {
            return Err(ScanGeometryError::RangeLimits);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hokuyo() -> ScanGeometry {
        ScanGeometry {
            angle_min: -135f64.to_radians(),
            angle_increment: 0.25f64.to_radians(),
            time_increment: 0.025 / 1440.0,
            scan_time: 0.025,
            range_min: 0.1,
            range_max: 30.0,
        }
    }

    #[test]
    fn bearings_step_from_the_first_beam() {
        let g = hokuyo();
        assert_eq!(g.bearing(0), g.angle_min);
        assert!((g.bearing(1080) - 135f64.to_radians()).abs() < 1e-12);
        assert!(g.check().is_ok());
    }

    #[test]
    fn unusable_geometries_are_named() {
        let bad = |edit: fn(&mut ScanGeometry)| {
            let mut g = hokuyo();
            edit(&mut g);
            g.check().unwrap_err()
        };
        assert_eq!(bad(|g| g.angle_min = f64::NAN), ScanGeometryError::AngleMin);
        assert_eq!(
            bad(|g| g.angle_increment = 0.0),
            ScanGeometryError::AngleIncrement
        );
        assert_eq!(
            bad(|g| g.range_max = g.range_min),
            ScanGeometryError::RangeLimits
        );
        assert_eq!(
            bad(|g| g.range_min = f64::NAN),
            ScanGeometryError::RangeLimits
        );
    }
}
