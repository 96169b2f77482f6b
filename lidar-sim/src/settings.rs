//! What a simulation's settings file (`lidar-sim --config`, `[sim]` in slam-launch's) holds
//! besides the world: the sensor and the vehicle.

use serde::{Deserialize, Serialize};

use crate::{SensorConfig, VehicleConfig};

/// The sensor and the vehicle, each section and every field optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimSettings {
    pub sensor: SensorConfig,
    pub vehicle: VehicleConfig,
}
