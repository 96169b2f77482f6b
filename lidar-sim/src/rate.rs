//! The publishing rate `--rate` (and `[sim] rate` in slam-launch's config) may have.

pub use ipc_types::rate::RATE_RANGE;
use ipc_types::rate::RateUnit;

/// lidar-sim's rate is in scans per second.
const SCANS_PER_SECOND: RateUnit = RateUnit {
    before: "",
    after: " scans per second",
};

/// Checks a rate in scans per second: 0 (lockstep) or within [`RATE_RANGE`].
pub fn check_rate(rate: f64) -> Result<f64, String> {
    ipc_types::rate::check_rate(rate, SCANS_PER_SECOND)
}

/// `--rate`'s parser: a number that passes [`check_rate`].
pub fn parse_rate(text: &str) -> Result<f64, String> {
    ipc_types::rate::parse_rate(text, SCANS_PER_SECOND)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lockstep_and_the_range_pass_and_the_rest_is_named() {
        for good in ["0", "0.001", "0.01", "40", "1000"] {
            assert!(parse_rate(good).is_ok(), "{good}");
        }
        for bad in ["1e-20", "-1", "-0.5", "1000.5", "inf", "NaN"] {
            let error = parse_rate(bad).unwrap_err();
            assert!(
                error.contains("must be 0 (lockstep) or from 0.001 to 1000 scans per second"),
                "{bad}: {error}"
            );
        }
        assert_eq!(parse_rate("fast").unwrap_err(), "'fast' is not a number");
    }
}
