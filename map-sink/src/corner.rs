//! A corner of the SLAM map, independent of the IPC message types.

/// A map corner (docs/CONVENTIONS.md): the walls' intersection point, the heading of the
/// bisector towards the tip, the opening angle, a row-major 4x4 covariance over
/// `(x, y, heading, angle)` and the number of scans that saw it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapCorner {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    pub angle: f64,
    pub covariance: [f64; 16],
    pub observations: u32,
}
