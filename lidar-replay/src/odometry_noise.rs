//! The noise behind the covariance sent with a log's odometry, which carries none; it grows
//! along the motion with [`stage_kit::odometry_covariance::OdometryCovariance`], as
//! lidar-sim's does.

use stage_kit::odometry_covariance::OdometryNoise;

/// A nominal wheel odometry of an indoor robot of the logs' era (a B21, a Pioneer): five
/// times the simulator's forward and heading errors, since real wheels slip and the logs
/// say nothing of their odometry's quality.
pub const LOG_ODOMETRY_NOISE: OdometryNoise = OdometryNoise {
    sigma_forward: 0.05,
    sigma_lateral: 0.025,
    sigma_yaw_per_m: 0.025,
    sigma_yaw_per_rad: 0.1,
};
