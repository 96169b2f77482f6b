//! The vehicle: a carrot (pure-pursuit) follower of the waypoint path with a limited yaw
//! rate and acceleration, as a small robot or UAV drives. Fully deterministic.

use serde::{Deserialize, Serialize};

use crate::path::Path;
use crate::{Laps, OdometryConfig, Point2, Pose2, SimError, World, wrap_angle};
use stage_kit::{SettingError, check};

/// Below this speed the vehicle may also turn on the spot towards the carrot, so that a
/// heading error at a standstill is not stuck (pure pursuit alone turns only when moving).
const TURN_ON_SPOT_BELOW: f64 = 0.3;
/// Yaw rate per radian of heading error when turning on the spot, 1/s.
const TURN_ON_SPOT_GAIN: f64 = 2.0;
/// Corner speeds are kept this far below what the yaw-rate limit would just allow.
const CORNER_MARGIN: f64 = 0.8;
/// The vehicle has arrived when this close to the end of the path (or past it) and
/// slow enough to stop within one step, metres.
const ARRIVED: f64 = 1e-3;

/// Vehicle limits and its odometry. The cruise speed comes from the world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VehicleConfig {
    /// rad/s.
    pub max_yaw_rate: f64,
    /// Both speeding up and braking, m/s^2.
    pub max_accel: f64,
    /// Distance of the carrot ahead along the path, metres; larger cuts corners more
    /// widely but turns more smoothly.
    pub lookahead: f64,
    pub odometry: OdometryConfig,
}

impl Default for VehicleConfig {
    fn default() -> Self {
        Self {
            max_yaw_rate: 1.0,
            max_accel: 0.5,
            lookahead: 1.0,
            odometry: OdometryConfig::default(),
        }
    }
}

impl VehicleConfig {
    pub fn validate(&self) -> Result<(), SettingError> {
        for (field, v) in [
            ("max_yaw_rate", self.max_yaw_rate),
            ("max_accel", self.max_accel),
            ("lookahead", self.lookahead),
        ] {
            check(field, v, v.is_finite() && v > 0.0, "must be finite and > 0")?;
        }
        self.odometry.validate()
    }
}

/// The vehicle's state on its path.
#[derive(Debug, Clone)]
pub struct Vehicle {
    path: Path,
    cruise: f64,
    config: VehicleConfig,
    pose: Pose2,
    speed: f64,
    yaw_rate: f64,
    progress: f64,
    /// The leg being driven (see `crate::path`): an open route's laps each end at rest.
    leg: u32,
    finished: bool,
}

impl Vehicle {
    /// At rest on the first waypoint, facing the second, to drive the route once.
    pub fn new(world: &World, config: VehicleConfig) -> Result<Vehicle, SimError> {
        Vehicle::with_laps(world, config, Laps::ONE)
    }

    /// [`Vehicle::new`], to drive the route `laps` times in a row: round again from its end
    /// when it ends where it starts, else back and forth along it, turning at its ends.
    pub fn with_laps(
        world: &World,
        config: VehicleConfig,
        laps: Laps,
    ) -> Result<Vehicle, SimError> {
        world.validate()?;
        config.validate().map_err(SimError::Vehicle)?;
        let path = Path::new(&world.waypoints, laps);
        let start = path.start();
        Ok(Vehicle {
            pose: Pose2::new(start.x, start.y, path.start_heading()),
            path,
            cruise: world.speed,
            config,
            speed: 0.0,
            yaw_rate: 0.0,
            progress: 0.0,
            leg: 0,
            finished: false,
        })
    }

    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Forward speed, m/s.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// rad/s.
    pub fn yaw_rate(&self) -> f64 {
        self.yaw_rate
    }

    /// Arc length of the path covered, metres, over every lap.
    pub fn progress(&self) -> f64 {
        self.progress
    }

    /// At rest at the end of the path's last lap.
    pub fn finished(&self) -> bool {
        self.finished
    }

    /// Advances by `dt` seconds (keep it at 10 ms or below for smooth turns).
    pub fn step(&mut self, dt: f64) {
        if self.finished || dt <= 0.0 {
            return;
        }
        let c = &self.config;
        let (a, lookahead) = (c.max_accel, c.lookahead);
        let pos = Point2::new(self.pose.x, self.pose.y);
        let window = 2.0 * lookahead + self.speed * dt + 0.5;
        self.progress = self.path.project(self.leg, pos, self.progress, window);
        let remaining = self.path.leg_end(self.leg) - self.progress;
        if remaining <= ARRIVED && self.speed <= a * dt {
            self.speed = 0.0;
            self.yaw_rate = 0.0;
            if self.leg + 1 < self.path.legs() {
                self.leg += 1;
            } else {
                self.finished = true;
            }
            return;
        }
        let carrot = self.path.point_at(self.leg, self.progress + lookahead);
        let to_carrot = carrot - pos;
        let alpha = wrap_angle(to_carrot.y.atan2(to_carrot.x) - self.pose.yaw);

        // Speed limit: cruise, slow enough at every corner ahead for the yaw-rate limit
        // (pure pursuit rounds a corner of turn `theta` on a radius of about
        // lookahead / (2 sin(theta / 2))), a braking curve to a stop at the leg's end, and slower
        // while the heading is off.
        // Braking at `a` in steps of `dt` from speed v covers v (v / a + dt) / 2; the
        // largest v that stops within `remaining` (the continuous sqrt(2 a d) would end
        // with one step of harder braking).
        let stop = 0.5 * ((a * dt).powi(2) + 8.0 * a * remaining.max(0.0)).sqrt() - 0.5 * a * dt;
        let mut target = self.cruise.min(stop);
        for (s, theta) in self
            .path
            .turns(self.leg, self.progress - lookahead)
            .filter(|&(s, _)| s + lookahead > self.progress)
        {
            let radius = lookahead / (2.0 * (0.5 * theta).sin()).max(1e-9);
            let corner = CORNER_MARGIN * c.max_yaw_rate * radius;
            let distance = (s - lookahead - self.progress).max(0.0);
            target = target.min((corner * corner + 2.0 * a * distance).sqrt());
        }
        target *= alpha.cos().max(0.0);
        self.speed = (self.speed + (target - self.speed).clamp(-a * dt, a * dt)).max(0.0);

        let curvature = 2.0 * alpha.sin() / to_carrot.norm().max(1e-9);
        let on_spot = 1.0 - (self.speed / TURN_ON_SPOT_BELOW).min(1.0);
        self.yaw_rate = (self.speed * curvature + on_spot * TURN_ON_SPOT_GAIN * alpha)
            .clamp(-c.max_yaw_rate, c.max_yaw_rate);

        let mid = self.pose.yaw + 0.5 * self.yaw_rate * dt;
        self.pose = Pose2::new(
            self.pose.x + self.speed * dt * mid.cos(),
            self.pose.y + self.speed * dt * mid.sin(),
            self.pose.yaw + self.yaw_rate * dt,
        );
    }
}
