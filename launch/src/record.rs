//! `[record]` / `--record`: the recording stage (`slam-record`, writing `OUT/run.mcap`).

use serde::{Deserialize, Serialize};

/// Whether the run is recorded as MCAP.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RecordSection {
    /// Add `slam-record` to the pipeline (`--record`).
    pub enabled: bool,
}

impl RecordSection {
    /// Subscribers the recorder adds to each topic it records: in lockstep a publisher
    /// waits for that many more before its first message, so the recording misses nothing
    /// and every send waits for its room, as for any stage.
    pub fn extra_subscribers(&self) -> usize {
        usize::from(self.enabled)
    }
}

#[cfg(test)]
mod tests {
    use crate::config::RunConfig;

    #[test]
    fn the_record_section_is_read_and_strict() {
        let config: RunConfig = toml::from_str("[record]\nenabled = true").unwrap();
        assert!(config.record.enabled);
        assert_eq!(config.record.extra_subscribers(), 1);
        assert!(!RunConfig::default().record.enabled);
        assert!(toml::from_str::<RunConfig>("[record]\nfile = \"x\"").is_err());
    }
}
