//! What the back end's integration tests share: the simulated scanner.

use slam_geom::ScanGeometry;

/// A 270-degree scanner of 541 beams reaching 20 m.
pub fn geometry() -> ScanGeometry {
    ScanGeometry {
        angle_min: -0.75 * std::f64::consts::PI,
        angle_increment: 1.5 * std::f64::consts::PI / 540.0,
        time_increment: 0.0,
        scan_time: 0.025,
        range_min: 0.1,
        range_max: 20.0,
    }
}
