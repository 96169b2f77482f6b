//! The `--rate` every scan source takes: 0 for lockstep, or a real-time rate within
//! [`RATE_RANGE`]. Each source says what its rate means (scans per second, a log's speed
//! factor); the range and the check are one.

use std::ops::RangeInclusive;

/// Real-time rates a source may be given; 0 (lockstep) is allowed besides. A thousandth
/// stretches the period of a scan, or a day-long log, far inside a `Duration`; a thousand
/// is beyond what the stages keep up with, and lockstep is the way to go as fast as they can.
pub const RATE_RANGE: RangeInclusive<f64> = 0.001..=1000.0;

/// What a source's rate means, for its error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RateUnit {
    /// Said before the range, e.g. `"a speed factor "` (or nothing).
    pub before: &'static str,
    /// Said after it, e.g. `" scans per second"`.
    pub after: &'static str,
}

/// Checks a rate: 0 (lockstep) or within [`RATE_RANGE`]; the error says what may be given.
pub fn check_rate(rate: f64, unit: RateUnit) -> Result<f64, String> {
    if rate == 0.0 || RATE_RANGE.contains(&rate) {
        Ok(rate)
    } else {
        Err(format!(
            "must be 0 (lockstep) or {}from {} to {}{}, not {rate:?}",
            unit.before,
            RATE_RANGE.start(),
            RATE_RANGE.end(),
            unit.after,
        ))
    }
}

/// A `--rate` argument: a number that passes [`check_rate`].
pub fn parse_rate(text: &str, unit: RateUnit) -> Result<f64, String> {
    let rate: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    check_rate(rate, unit)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HERTZ: RateUnit = RateUnit {
        before: "",
        after: " scans per second",
    };

    #[test]
    fn lockstep_and_the_range_pass_and_the_rest_is_named() {
        for good in ["0", "0.001", "1", "1000"] {
            assert!(parse_rate(good, HERTZ).is_ok(), "{good}");
        }
        for bad in ["1e-20", "-1", "1000.5", "inf", "NaN"] {
            assert_eq!(
                parse_rate(bad, HERTZ).unwrap_err(),
                format!(
                    "must be 0 (lockstep) or from 0.001 to 1000 scans per second, not {:?}",
                    bad.parse::<f64>().unwrap()
                )
            );
        }
        assert_eq!(
            parse_rate("fast", HERTZ).unwrap_err(),
            "'fast' is not a number"
        );
    }
}
