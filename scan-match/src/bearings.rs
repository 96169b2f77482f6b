//! The unit direction of every beam, kept between scans: a scan's geometry seldom changes,
//! and two trigonometric calls per beam were a good share of turning ranges into points.

use nalgebra::Vector2;

use slam_geom::ScanGeometry;

/// Beam directions `(cos, sin)` of the bearings `angle_min + i * angle_increment`, for the
/// last geometry asked for; recomputed when it changes or more beams come.
#[derive(Debug, Clone, Default)]
pub struct Bearings {
    key: Option<(u64, u64)>,
    directions: Vec<Vector2<f64>>,
}

impl Bearings {
    /// The directions of the first `count` beams of `geometry`.
    pub fn directions(&mut self, geometry: &ScanGeometry, count: usize) -> &[Vector2<f64>] {
        let key = (
            geometry.angle_min.to_bits(),
            geometry.angle_increment.to_bits(),
        );
        if self.key != Some(key) || self.directions.len() < count {
            self.key = Some(key);
            self.directions.clear();
            self.directions.extend((0..count).map(|i| {
                let (s, c) = (geometry.angle_min + i as f64 * geometry.angle_increment).sin_cos();
                Vector2::new(c, s)
            }));
        }
        &self.directions[..count]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_follow_the_geometry() {
        let mut bearings = Bearings::default();
        let mut geometry = ScanGeometry {
            angle_min: 0.0,
            angle_increment: std::f64::consts::FRAC_PI_2,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.1,
            range_max: 10.0,
        };
        let d = bearings.directions(&geometry, 3).to_vec();
        assert!((d[1] - Vector2::new(0.0, 1.0)).norm() < 1e-12);
        assert!((d[2] - Vector2::new(-1.0, 0.0)).norm() < 1e-12);
        geometry.angle_min = std::f64::consts::FRAC_PI_2;
        let d = bearings.directions(&geometry, 4);
        assert_eq!(d.len(), 4);
        assert!((d[0] - Vector2::new(0.0, 1.0)).norm() < 1e-12);
        assert!((d[2] - Vector2::new(0.0, -1.0)).norm() < 1e-12);
    }
}
