//! A replay's `--rate`: a factor of the log's own speed, paced by the log's stamps with
//! [`stage_kit::pacing::Pacer`].

pub use stage_kit::pacing::RATE_RANGE;
use stage_kit::pacing::RateUnit;

/// A replay's rate is a factor of the log's own speed.
pub const SPEED_FACTOR: RateUnit = RateUnit {
    before: "a speed factor ",
    after: " (1 = as recorded)",
};

/// Checks a speed factor: 0 (lockstep) or within [`RATE_RANGE`].
pub fn check_rate(rate: f64) -> Result<f64, String> {
    SPEED_FACTOR.check(rate)
}

/// `--rate`'s parser: a number that passes [`check_rate`].
pub fn parse_rate(text: &str) -> Result<f64, String> {
    SPEED_FACTOR.parse(text)
}
