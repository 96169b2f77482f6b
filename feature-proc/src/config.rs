//! Every threshold of the extractor, with defaults that work on the real Hokuyo recording and
//! on simulated scans alike.

use serde::{Deserialize, Serialize};
use stage_kit::settings::{SettingError, check, check_counts, check_non_negative, check_positive};

/// Extraction thresholds. Metres and radians throughout (docs/CONVENTIONS.md).
///
/// Read from the `[features]` section of a run's TOML file; every field is optional and an
/// unknown key is an error, so a typo cannot silently leave a default in place.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FeatureConfig {
    /// Readings beyond this range are dropped, on top of the scan's own `range_max`, metres.
    /// Far corners are real but flicker more (sparse points); the course code used 15 m.
    pub max_range: f64,
    /// Standard deviation of a range reading, metres. Sets the breakpoint margin, how far
    /// from a wall a point may lie to be handed to it, and the line and corner covariances.
    pub range_sigma: f64,
    /// Standard deviation of a beam's bearing, radians (small for a spinning mirror).
    pub bearing_sigma: f64,
    /// Adaptive breakpoint detector (Borges & Aldon): the shallowest angle between a beam and
    /// a surface that is still followed as one segment. Neighbouring points further apart
    /// than `r * sin(dphi) / sin(lambda - dphi) + 3 * range_sigma` start a new segment.
    pub breakpoint_lambda: f64,
    /// Invalid beams bridged inside a segment: a dark patch on a wall should not cut it.
    pub max_invalid_gap: usize,
    /// Split a run of points at the one farthest from its chord when it is farther than this.
    /// Also the largest residual a merged line may have.
    pub split_threshold: f64,
    /// Neighbouring lines whose directions differ by less than this are merged when their
    /// union is still straight. Kept far below any corner angle so a merge never undoes one.
    pub merge_angle: f64,
    /// Largest gap between neighbouring lines that a merge may bridge (dropouts, grazing
    /// incidence), metres.
    pub merge_max_gap: f64,
    /// Fewest points a line is fitted to.
    pub min_line_points: usize,
    /// Shortest arm of a corner: the distance from the intersection to the far end of each
    /// line, metres.
    pub min_line_length: f64,
    /// Smallest opening angle of a corner, radians.
    pub corner_min_angle: f64,
    /// Largest opening angle of a corner, radians.
    pub corner_max_angle: f64,
    /// Largest gap between the end of one line and the start of the next for them to form a
    /// corner, metres.
    pub corner_max_gap: f64,
    /// Largest distance from either line's near end to the intersection, metres. A line that
    /// stops short of the intersection ends at an occlusion or a doorway, not a corner.
    pub corner_max_extension: f64,
}

impl Default for FeatureConfig {
    fn default() -> Self {
        Self {
            // Far corners flicker (their two walls are few, far-apart beams), while a short
            // reach loses a building's long sightlines.
            max_range: 25.0,
            // A Hokuyo's residuals about long flat walls are about a centimetre; the rest
            // is room for walls that are not quite flat.
            range_sigma: 0.02,
            bearing_sigma: 0.0002,
            // Below Borges & Aldon's 10 degrees: walls seen at a grazing angle (pillar
            // sides far away) stay whole; split-and-merge still cuts real jumps.
            breakpoint_lambda: 0.1,
            max_invalid_gap: 2,
            split_threshold: 0.1,
            merge_angle: 6f64.to_radians(),
            merge_max_gap: 0.5,
            // About four beams fall on a 0.3 m pillar side seen obliquely from 15 m.
            min_line_points: 4,
            min_line_length: 0.3,
            // Wider than the course's 60..120 degrees, with both limits clear of the common
            // 45, 120 and 135 degree corners so that none of them flickers at a limit.
            corner_min_angle: 40f64.to_radians(),
            corner_max_angle: 130f64.to_radians(),
            corner_max_gap: 0.3,
            corner_max_extension: 0.25,
        }
    }
}

impl FeatureConfig {
    /// Checks that every threshold is usable; [`crate::Extractor::extract`] refuses to run
    /// on a configuration that fails this.
    pub fn validate(&self) -> Result<(), SettingError> {
        let half_pi = std::f64::consts::FRAC_PI_2;
        check_positive(&stage_kit::named_fields!(self;
            max_range, range_sigma, split_threshold, merge_angle, min_line_length, corner_max_gap,
            corner_max_extension,
        ))?;
        check_non_negative(&stage_kit::named_fields!(self; bearing_sigma, merge_max_gap))?;
        let l = self.breakpoint_lambda;
        check(
            "breakpoint_lambda",
            l,
            l > 0.0 && l <= half_pi,
            "must be in (0, pi/2]",
        )?;
        let (lo, hi) = (self.corner_min_angle, self.corner_max_angle);
        let pi = std::f64::consts::PI;
        check(
            "corner_min_angle",
            lo,
            lo > 0.0 && lo < hi,
            "must be in (0, corner_max_angle)",
        )?;
        check("corner_max_angle", hi, hi < pi, "must be below pi")?;
        // Three points are the fewest whose fit has a residual to judge it by.
        check_counts(&stage_kit::named_fields!(self; min_line_points), 3..=1000)?;
        check_counts(&stage_kit::named_fields!(self; max_invalid_gap), ..=100)?;
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
            toml::from_str("split_threshold = 0.05\nmax_range = 15.0").unwrap();
        assert_eq!(config.split_threshold, 0.05);
        assert_eq!(config.max_range, 15.0);
        assert_eq!(
            config.min_line_points,
            FeatureConfig::default().min_line_points
        );
        assert!(toml::from_str::<FeatureConfig>("split_treshold = 0.05").is_err());
    }

    #[test]
    fn bad_values_are_named() {
        let config = FeatureConfig {
            corner_min_angle: 2.5,
            ..FeatureConfig::default()
        };
        assert_eq!(config.validate().unwrap_err().field, "corner_min_angle");
        let config = FeatureConfig {
            range_sigma: f64::NAN,
            ..FeatureConfig::default()
        };
        assert_eq!(config.validate().unwrap_err().field, "range_sigma");
    }
}
