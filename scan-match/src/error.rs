//! What can be wrong with one scan's input.

use thiserror::Error;

/// A scan the front end cannot interpret at all (as opposed to one it cannot match, which
/// is a status of the output, not an error).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InputError {
    /// Shown in the message rather than kept as a source: callers count and log these
    /// one-line reasons per scan.
    #[error("beam geometry is not usable: {0}")]
    Geometry(slam_geom::ScanGeometryError),
    #[error("odometry covariance is not a 3x3 symmetric matrix with a finite diagonal")]
    OdometryCovariance,
}
