//! The covariance a source sends with its odometry, as a random walk along the motion.
//!
//! Consumers (feature-proc, slam-proc) read an odometry message's covariance as that of the
//! integrated pose, and the uncertainty of the increment between two messages as its growth
//! (docs/CONVENTIONS.md, "Odometry"). A source that knows only per-step noise (the
//! simulator's wheels, a log that carries none) integrates it here, so the covariance grows
//! with the distance driven and the angle turned, whatever the message rate.

use slam_geom::{Pose2, wrap_angle};

/// Random-walk standard deviations of wheel odometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryNoise {
    /// Forward error, metres per sqrt(metre driven).
    pub sigma_forward: f64,
    /// Sideways error, metres per sqrt(metre driven).
    pub sigma_lateral: f64,
    /// Heading error from driving, radians per sqrt(metre driven).
    pub sigma_yaw_per_m: f64,
    /// Heading error from turning, radians per sqrt(radian turned).
    pub sigma_yaw_per_rad: f64,
}

/// Integrates [`OdometryNoise`] along the odometry poses it is given, in order.
#[derive(Debug, Clone)]
pub struct OdometryCovariance {
    noise: OdometryNoise,
    /// Variances of position (each axis) and heading so far.
    position: f64,
    yaw: f64,
    last: Option<Pose2>,
}

impl OdometryCovariance {
    pub fn new(noise: OdometryNoise) -> Self {
        Self {
            noise,
            position: 0.0,
            yaw: 0.0,
            last: None,
        }
    }

    /// The row-major (x, y, yaw) covariance of `pose`, after the motion since the previous
    /// pose. Position variance is the same on both axes: the forward and sideways errors
    /// mix as the robot turns, so neither world axis knows which is which.
    pub fn update(&mut self, pose: Pose2) -> [f64; 9] {
        if let Some(last) = self.last {
            let driven = (pose.x - last.x).hypot(pose.y - last.y);
            let turned = wrap_angle(pose.yaw - last.yaw).abs();
            let n = &self.noise;
            self.position += (n.sigma_forward.powi(2) + n.sigma_lateral.powi(2)) * driven;
            self.yaw += n.sigma_yaw_per_m.powi(2) * driven + n.sigma_yaw_per_rad.powi(2) * turned;
        }
        self.last = Some(pose);
        let (p, y) = (self.position, self.yaw);
        [p, 0.0, 0.0, 0.0, p, 0.0, 0.0, 0.0, y]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covariance_grows_with_distance_and_turn_only() {
        let noise = OdometryNoise {
            sigma_forward: 0.1,
            sigma_lateral: 0.2,
            sigma_yaw_per_m: 0.3,
            sigma_yaw_per_rad: 0.4,
        };
        let mut covariance = OdometryCovariance::new(noise);
        assert_eq!(
            covariance.update(Pose2::new(5.0, 5.0, 3.0)),
            [0.0; 9],
            "the start"
        );
        let standing = covariance.update(Pose2::new(5.0, 5.0, 3.0));
        assert_eq!(standing, [0.0; 9], "standing still adds nothing");
        // 5 m driven and a 0.5 rad turn across the +-pi seam.
        let moved = covariance.update(Pose2::new(8.0, 9.0, 3.0 + 0.5 - std::f64::consts::TAU));
        let position = (0.01 + 0.04) * 5.0;
        let yaw = 0.09 * 5.0 + 0.16 * 0.5;
        assert!((moved[0] - position).abs() < 1e-12 && moved[4] == moved[0]);
        assert!((moved[8] - yaw).abs() < 1e-12);
        assert_eq!([moved[1], moved[2], moved[3], moved[5]], [0.0; 4]);
    }
}
