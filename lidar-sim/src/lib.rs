//! A simulated 2D lidar in a world of walls, the library half of the `lidar-sim` process.
//!
//! - [`World`]: wall polylines, a waypoint path and a speed; built in (`hall`, `office`,
//!   `corridor`) or read from JSON, with errors that name the offending item.
//! - [`World::true_corners`]: the ground-truth corner features (docs/CONVENTIONS.md).
//! - [`RayCaster`]: exact first-hit distances through a uniform grid over the segments.
//! - [`LidarModel`] with [`SensorConfig`] (default: Hokuyo UTM-30LX): noise, dropouts and
//!   REP 117 invalid ranges.
//! - [`Vehicle`]: a pure-pursuit follower of the path with limited yaw rate and
//!   acceleration, once or for several [`Laps`]; [`Odometer`] integrates its motion with
//!   noise.
//! - [`Simulation`]: ties them together into deterministic [`SimulatedScan`]s for a seed.
//! - [`check_rate`]: the real-time rates the process accepts ([`RATE_RANGE`]).
//!
//! Metres, radians and seconds throughout; poses are `world_from_robot` and the sensor sits
//! at the robot origin.

mod builtin;
mod corners;
pub mod geometry;
mod laps;
mod lidar;
mod odometry;
mod outline;
mod path;
mod rate;
mod ray_caster;
mod sensor;
mod settings;
mod sim_error;
mod simulation;
mod vehicle;
mod visibility;
mod world;
mod world_error;

pub use laps::{Laps, MAX_LAPS, parse_laps};
pub use lidar::LidarModel;
pub use odometry::{Odometer, OdometryConfig};
pub use rate::{RATE_RANGE, SCANS_PER_SECOND, check_rate, parse_rate};
pub use ray_caster::RayCaster;
pub use sensor::SensorConfig;
pub use settings::SimSettings;
pub use sim_error::SimError;
pub use simulation::{SimulatedScan, Simulation};
pub use slam_geom::TrueCorner;
pub use slam_geom::{Point2, Pose2, wrap_angle};
pub use stage_kit::SettingError;
pub use vehicle::{Vehicle, VehicleConfig};
pub use visibility::visible_corners;
pub use world::{BUILTIN_WORLDS, World};
pub use world_error::WorldError;
