//! The motion prior of one step: the odometry increment with the growth of its covariance,
//! or constant velocity when there is no (believable) odometry.

use nalgebra::{Matrix3, Vector3};
use slam_geom::Pose2;

use crate::config::FrontEndConfig;
use crate::input::OdometryInput;

/// Constant velocity is extrapolated over at most this long a step, seconds.
pub const MAX_EXTRAPOLATION_S: f64 = 1.0;

/// Floor of the odometry step's standard deviation, metres: encoder quantisation and the
/// timing between the odometry and the scan, which a stopped robot's zero growth of
/// covariance would hide: millimetres, for any wheeled robot.
pub const ODOMETRY_MIN_SIGMA_XY: f64 = 0.005;
/// The same floor for yaw, radians.
pub const ODOMETRY_MIN_SIGMA_YAW: f64 = 0.005;

/// An increment in the previous robot frame and its covariance over `(x, y, yaw)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    pub increment: Pose2,
    pub covariance: Matrix3<f64>,
}

/// Why an odometry step was not believed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdometryRejection {
    /// A pose or covariance value is NaN or infinite.
    NotFinite,
    /// Faster than any robot moves or turns (see `max_linear_speed`, `max_angular_speed`).
    Implausible,
    /// Far outside the scan match: the squared Mahalanobis distance.
    Inconsistent { mahalanobis_squared: f64 },
    /// A change of pace no robot makes (see `max_linear_acceleration`): the acceleration
    /// it would take, m/s^2. A reading that lags the scan, stale.
    Stale { acceleration: f64 },
}

/// The odometry step between two readings, or why it cannot be one.
pub fn odometry_step(
    previous: &OdometryInput,
    current: &OdometryInput,
    dt: f64,
    config: &FrontEndConfig,
) -> Result<Step, OdometryRejection> {
    let finite = |o: &OdometryInput| {
        o.odom_from_robot.x.is_finite()
            && o.odom_from_robot.y.is_finite()
            && o.odom_from_robot.yaw.is_finite()
            && o.covariance.iter().all(|v| v.is_finite())
    };
    if !finite(previous) || !finite(current) {
        return Err(OdometryRejection::NotFinite);
    }
    let increment = previous.odom_from_robot.between(&current.odom_from_robot);
    if !(increment.translation_norm().is_finite() && increment.yaw.is_finite()) {
        return Err(OdometryRejection::NotFinite);
    }
    // A little slack for stamps that round or jitter: a step of a centimetre or a degree
    // is never implausible.
    if increment.translation_norm() > config.max_linear_speed * dt + 0.01
        || increment.yaw.abs() > config.max_angular_speed * dt + 0.02
    {
        return Err(OdometryRejection::Implausible);
    }
    // The growth of the integrated pose's covariance, expressed in the previous robot
    // frame, symmetrised; its diagonal floored and the off-diagonal clipped so the
    // result is positive definite whatever the publisher sent.
    let growth = current.covariance - previous.covariance;
    let rotation = previous.odom_from_robot.rotation();
    let mut to_robot = Matrix3::identity();
    to_robot
        .fixed_view_mut::<2, 2>(0, 0)
        .copy_from(&rotation.transpose());
    let growth = to_robot * growth * to_robot.transpose();
    let floors = Vector3::new(
        ODOMETRY_MIN_SIGMA_XY.powi(2),
        ODOMETRY_MIN_SIGMA_XY.powi(2),
        ODOMETRY_MIN_SIGMA_YAW.powi(2),
    );
    Ok(Step {
        increment,
        covariance: positive_definite(&growth, &floors),
    })
}

/// The constant-velocity step over `dt` from the velocity `(vx, vy, yaw rate)` in the robot
/// frame, its uncertainty that of a velocity change of the configured sigmas.
pub fn constant_velocity_step(velocity: &Vector3<f64>, dt: f64, config: &FrontEndConfig) -> Step {
    // Across a gap in the data (seconds of lost scans) the last velocity says little:
    // extrapolating a turn for seconds would seed far worse than standing still.
    let moving = if dt <= MAX_EXTRAPOLATION_S { dt } else { 0.0 };
    let increment = Pose2::new(
        velocity.x * moving,
        velocity.y * moving,
        slam_geom::wrap_angle(velocity.z * moving),
    );
    let linear = (config.velocity_sigma_linear * dt).max(ODOMETRY_MIN_SIGMA_XY);
    let angular = (config.velocity_sigma_angular * dt).max(ODOMETRY_MIN_SIGMA_YAW);
    Step {
        increment,
        covariance: Matrix3::from_diagonal(&Vector3::new(
            linear * linear,
            linear * linear,
            angular * angular,
        )),
    }
}

/// `m` made symmetric positive definite: diagonal at least `floors`, correlations clipped
/// below one.
pub fn positive_definite(m: &Matrix3<f64>, floors: &Vector3<f64>) -> Matrix3<f64> {
    let mut out = 0.5 * (m + m.transpose());
    for i in 0..3 {
        out[(i, i)] = out[(i, i)].abs().max(floors[i]);
    }
    for i in 0..3 {
        for j in 0..3 {
            if i != j {
                let limit = 0.9 * (out[(i, i)] * out[(j, j)]).sqrt();
                out[(i, j)] = out[(i, j)].clamp(-limit, limit);
            }
        }
    }
    if out.cholesky().is_none() {
        // Clipped pairwise correlations can still combine to an indefinite matrix.
        out = Matrix3::from_diagonal(&out.diagonal());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(x: f64, variance: f64) -> OdometryInput {
        OdometryInput {
            odom_from_robot: Pose2::new(x, 0.0, 0.0),
            covariance: Matrix3::identity() * variance,
        }
    }

    #[test]
    fn steps_are_checked_and_covariances_are_growth() {
        let config = FrontEndConfig::default();
        let step =
            odometry_step(&reading(1.0, 0.1), &reading(1.2, 0.1 + 1e-3), 0.1, &config).unwrap();
        assert!((step.increment.x - 0.2).abs() < 1e-12);
        assert!((step.covariance[(0, 0)] - 1e-3).abs() < 1e-12);
        assert_eq!(
            odometry_step(&reading(1.0, 0.1), &reading(1001.0, 0.1), 0.1, &config),
            Err(OdometryRejection::Implausible)
        );
        assert!(odometry_step(&reading(1.0, 0.1), &reading(1e300, 0.1), 0.1, &config).is_err());
        assert_eq!(
            odometry_step(&reading(1.0, 0.1), &reading(f64::NAN, 0.1), 0.1, &config),
            Err(OdometryRejection::NotFinite)
        );
        // No growth (a stopped robot) still gives an invertible covariance.
        let still = odometry_step(&reading(1.0, 0.1), &reading(1.0, 0.1), 0.1, &config).unwrap();
        assert!(still.covariance.cholesky().is_some());
    }
}
