//! `[foxglove]` / `--foxglove [ADDR]`: the live view (`slam-view`, crate `view-proc`),
//! serving the run to Foxglove over its WebSocket protocol.

use serde::{Deserialize, Serialize};
use view_proc::{DEFAULT_ADDRESS, ViewAddress, ViewError};

/// Whether the run is served live, and where.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ViewSection {
    /// Add `slam-view` to the pipeline (`--foxglove`).
    pub enabled: bool,
    /// `HOST:PORT` it listens on (`--foxglove ADDR`).
    pub addr: String,
}

impl Default for ViewSection {
    fn default() -> Self {
        Self {
            enabled: false,
            addr: DEFAULT_ADDRESS.to_owned(),
        }
    }
}

impl ViewSection {
    /// The address, parsed.
    pub fn address(&self) -> Result<ViewAddress, ViewError> {
        self.addr.parse()
    }

    /// When the view is on: the address resolves and its port is free now, so that a
    /// port in use is said before the run starts rather than by a stage that dies.
    pub fn check(&self) -> Result<(), ViewError> {
        if self.enabled {
            self.address()?.check_free()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::config::RunConfig;

    #[test]
    fn the_foxglove_section_is_read_and_strict() {
        let config: RunConfig =
            toml::from_str("[foxglove]\nenabled = true\naddr = \"0.0.0.0:9000\"").unwrap();
        assert!(config.foxglove.enabled);
        assert_eq!(config.foxglove.address().unwrap().port, 9000);
        let default = RunConfig::default().foxglove;
        assert!(!default.enabled);
        assert_eq!(default.addr, view_proc::DEFAULT_ADDRESS);
        assert!(toml::from_str::<RunConfig>("[foxglove]\nport = 1").is_err());
    }
}
