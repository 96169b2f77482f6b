//! Why a simulation could not be set up.

use crate::{SettingError, WorldError};

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    World(#[from] WorldError),
    #[error("sensor config: {0}")]
    Sensor(SettingError),
    #[error("vehicle config: {0}")]
    Vehicle(SettingError),
}
