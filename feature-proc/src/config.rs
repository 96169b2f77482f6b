//! The extractor's settings (the scanner's), with defaults that work on the real Hokuyo
//! recording and on simulated scans alike.

use serde::{Deserialize, Serialize};
use stage_kit::settings::{SettingError, check_counts, check_non_negative, check_positive};

/// The extractor's settings: what a user with another scanner changes. Metres and radians
/// throughout (docs/CONVENTIONS.md). The thresholds that describe walls and corners rather
/// than the scanner are constants beside the code that uses them.
///
/// Read from the `[features]` section of a run's TOML file; every field is optional and an
/// unknown key is an error, so a typo cannot silently leave a default in place.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FeatureConfig {
    /// Readings beyond this range are dropped, on top of the scan's own `range_max`, metres.
    /// Far corners are real but flicker more (sparse points); the course code used 15 m.
    pub max_range: f64,
    /// The scanner's range noise, metres: `[front_end] range_sigma`, which feature-proc
    /// copies in (one setting for both; not a key of `[features]`). The extractor allows
    /// [`WALL_SIGMA_FACTOR`] times it ([`FeatureConfig::wall_sigma`]).
    #[serde(skip)]
    pub range_sigma: f64,
    /// Standard deviation of a beam's bearing, radians (small for a spinning mirror).
    pub bearing_sigma: f64,
    /// Fewest points a line is fitted to; a segment or a scan with fewer has no line. Fewer
    /// for a scanner whose beams are further apart.
    pub min_line_points: usize,
}

/// A point's distance to the wall it lies on varies by this many times the scanner's range
/// noise: a Hokuyo's residuals about long flat walls are about its noise, and the rest is
/// room for walls that are not quite flat. It sets the breakpoint margin, how far from a
/// wall a point may lie to be handed to it, and the line and corner covariances.
pub const WALL_SIGMA_FACTOR: f64 = 2.0;

impl Default for FeatureConfig {
    fn default() -> Self {
        Self {
            // Far corners flicker (their two walls are few, far-apart beams), while a short
            // reach loses a building's long sightlines.
            max_range: 25.0,
            range_sigma: scan_match::FrontEndConfig::default().range_sigma,
            bearing_sigma: 0.0002,
            // About four beams fall on a 0.3 m pillar side seen obliquely from 15 m.
            min_line_points: 4,
        }
    }
}

impl FeatureConfig {
    /// Standard deviation of a point's distance to its wall, metres: the scanner's range
    /// noise and the walls' roughness ([`WALL_SIGMA_FACTOR`]).
    pub fn wall_sigma(&self) -> f64 {
        WALL_SIGMA_FACTOR * self.range_sigma
    }

    /// Checks that every setting is usable; [`crate::Extractor::extract`] refuses to run
    /// on a configuration that fails this.
    pub fn validate(&self) -> Result<(), SettingError> {
        check_positive(&stage_kit::named_fields!(self; max_range, range_sigma))?;
        check_non_negative(&stage_kit::named_fields!(self; bearing_sigma))?;
        // Three points are the fewest whose fit has a residual to judge it by.
        check_counts(&stage_kit::named_fields!(self; min_line_points), 3..=1000)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        FeatureConfig::default().validate().unwrap();
    }

    #[test]
    fn toml_fills_in_defaults_and_refuses_unknown_keys() {
        let config: FeatureConfig =
            toml::from_str("min_line_points = 5\nmax_range = 15.0").unwrap();
        assert_eq!(config.min_line_points, 5);
        assert_eq!(config.max_range, 15.0);
        assert_eq!(config.bearing_sigma, FeatureConfig::default().bearing_sigma);
        assert!(toml::from_str::<FeatureConfig>("min_line_pionts = 5").is_err());
        // The range noise is the front end's setting, not one of this section.
        assert!(toml::from_str::<FeatureConfig>("range_sigma = 0.02").is_err());
    }

    #[test]
    fn bad_values_are_named() {
        let config = FeatureConfig {
            min_line_points: 2,
            ..FeatureConfig::default()
        };
        assert_eq!(config.validate().unwrap_err().field, "min_line_points");
        let config = FeatureConfig {
            range_sigma: f64::NAN,
            ..FeatureConfig::default()
        };
        assert_eq!(config.validate().unwrap_err().field, "range_sigma");
    }
}
