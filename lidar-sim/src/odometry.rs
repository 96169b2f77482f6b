//! Noisy wheel odometry: true motion increments with random-walk errors, integrated.

use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::Pose2;
use stage_kit::odometry_covariance::OdometryNoise;
use stage_kit::settings::{SettingError, check_non_negative};

/// Odometry error as random walks: each standard deviation grows with the square root of
/// the distance travelled (or angle turned), so it does not depend on the time step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OdometryConfig {
    /// Forward error, metres per sqrt(metre travelled).
    pub sigma_forward: f64,
    /// Sideways error, metres per sqrt(metre travelled).
    pub sigma_lateral: f64,
    /// Heading error from driving, radians per sqrt(metre travelled).
    pub sigma_yaw_per_m: f64,
    /// Heading error from turning, radians per sqrt(radian turned).
    pub sigma_yaw_per_rad: f64,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            sigma_forward: 0.01,
            sigma_lateral: 0.005,
            sigma_yaw_per_m: 0.005,
            sigma_yaw_per_rad: 0.02,
        }
    }
}

impl OdometryConfig {
    /// The noise as the covariance sent with the odometry integrates it.
    pub fn noise(&self) -> OdometryNoise {
        OdometryNoise {
            sigma_forward: self.sigma_forward,
            sigma_lateral: self.sigma_lateral,
            sigma_yaw_per_m: self.sigma_yaw_per_m,
            sigma_yaw_per_rad: self.sigma_yaw_per_rad,
        }
    }

    pub fn validate(&self) -> Result<(), SettingError> {
        check_non_negative(&[
            ("odometry.sigma_forward", self.sigma_forward),
            ("odometry.sigma_lateral", self.sigma_lateral),
            ("odometry.sigma_yaw_per_m", self.sigma_yaw_per_m),
            ("odometry.sigma_yaw_per_rad", self.sigma_yaw_per_rad),
        ])?;
        Ok(())
    }
}

/// Integrates noisy increments of the true motion. Starts at the true start pose.
#[derive(Debug, Clone)]
pub struct Odometer {
    config: OdometryConfig,
    pose: Pose2,
    last_truth: Pose2,
    speed: f64,
    yaw_rate: f64,
}

impl Odometer {
    pub fn new(config: OdometryConfig, start: Pose2) -> Odometer {
        Odometer {
            config,
            pose: start,
            last_truth: start,
            speed: 0.0,
            yaw_rate: 0.0,
        }
    }

    /// The odometry pose (drifts away from the truth).
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Forward speed and yaw rate measured over the last update.
    pub fn velocity(&self) -> (f64, f64) {
        (self.speed, self.yaw_rate)
    }

    /// Adds the noisy increment from the previous true pose to `truth`, `dt` seconds later.
    pub fn update(&mut self, truth: Pose2, dt: f64, rng: &mut impl Rng) {
        let c = &self.config;
        let delta = self.last_truth.inverse().compose(&truth);
        let ds = delta.x.hypot(delta.y);
        let z: [f64; 3] = [
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
        ];
        let yaw_sigma =
            (c.sigma_yaw_per_m.powi(2) * ds + c.sigma_yaw_per_rad.powi(2) * delta.yaw.abs()).sqrt();
        let noisy = Pose2::new(
            delta.x + c.sigma_forward * ds.sqrt() * z[0],
            delta.y + c.sigma_lateral * ds.sqrt() * z[1],
            delta.yaw + yaw_sigma * z[2],
        );
        self.pose = self.pose.compose(&noisy);
        self.last_truth = truth;
        if dt > 0.0 {
            self.speed = noisy.x / dt;
            self.yaw_rate = noisy.yaw / dt;
        }
    }
}
