//! The publishing rate `--rate` (and `[sim] rate` in slam-launch's config) may have: scans
//! per second, paced by [`stage_kit::pacing::Pacer`] by count.

pub use stage_kit::pacing::RATE_RANGE;
use stage_kit::pacing::RateUnit;

/// lidar-sim's rate is in scans per second.
pub const SCANS_PER_SECOND: RateUnit = RateUnit {
    before: "",
    after: " scans per second",
};

/// Checks a rate in scans per second: 0 (lockstep) or within [`RATE_RANGE`].
pub fn check_rate(rate: f64) -> Result<f64, String> {
    SCANS_PER_SECOND.check(rate)
}

/// `--rate`'s parser: a number that passes [`check_rate`].
pub fn parse_rate(text: &str) -> Result<f64, String> {
    SCANS_PER_SECOND.parse(text)
}
