//! The publishing rate `--rate` (and `[sim] rate` in slam-launch's config) may have.

use std::ops::RangeInclusive;

/// Scans per second a real-time run may ask for; 0 (lockstep) is allowed besides. Slower
/// than one scan in 1000 s is no live sensor, and a period that long is still far inside a
/// `Duration`; faster than 1000 Hz is more than the ray caster keeps up with, and lockstep
/// is the way to go as fast as it can.
pub const RATE_RANGE: RangeInclusive<f64> = 0.001..=1000.0;

/// Checks a rate: 0 (lockstep) or within [`RATE_RANGE`]; the error says what may be given.
pub fn check_rate(rate: f64) -> Result<f64, String> {
    if rate == 0.0 || RATE_RANGE.contains(&rate) {
        Ok(rate)
    } else {
        Err(format!(
            "must be 0 (lockstep) or from {} to {} scans per second, not {rate:?}",
            RATE_RANGE.start(),
            RATE_RANGE.end()
        ))
    }
}

/// `--rate`'s parser: a number that passes [`check_rate`].
pub fn parse_rate(text: &str) -> Result<f64, String> {
    let rate: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    check_rate(rate)
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
