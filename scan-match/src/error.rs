//! What can be wrong with a configuration or with one scan's input.

use thiserror::Error;

/// A [`crate::FrontEndConfig`] field out of range.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ConfigError {
    #[error("{name} must be finite and positive, not {value}")]
    NotPositive { name: &'static str, value: f64 },
    #[error("{name} = {value} is outside {range}")]
    OutOfRange {
        name: &'static str,
        value: f64,
        range: &'static str,
    },
    #[error("{name} must be at least 1")]
    ZeroCount { name: &'static str },
}

/// A scan the front end cannot interpret at all (as opposed to one it cannot match, which
/// is a status of the output, not an error).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InputError {
    #[error("beam geometry is not usable: {0}")]
    Geometry(&'static str),
    #[error("odometry covariance is not a 3x3 symmetric matrix with a finite diagonal")]
    OdometryCovariance,
}
