//! Stamps as decimal seconds (`1058295543.123456`) and integer nanoseconds, converted exactly.
//!
//! An `f64` has about 16 significant digits, too few for today's epoch in nanoseconds, so a
//! stamp read through it would come out a few hundred nanoseconds off, and a trajectory's
//! stamps would no longer meet a relations file's digit for digit. The digits are parsed as
//! integers instead, with one set of rules for every reader of the pipeline.

use thiserror::Error;

/// Nanoseconds in a second.
const NANOS_PER_SECOND: u64 = 1_000_000_000;
/// Decimals a nanosecond stamp can hold.
const MAX_DECIMALS: usize = 9;

/// Why a text is not a stamp.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{text:?} is not a timestamp in seconds ({reason})")]
pub struct StampError {
    pub text: String,
    pub reason: StampProblem,
}

/// What is wrong with a stamp's text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum StampProblem {
    #[error("expected digits before the decimal point")]
    Seconds,
    #[error("expected digits after the decimal point")]
    Fraction,
    #[error("more than 9 decimals cannot be kept exactly")]
    TooPrecise,
    #[error("too large")]
    TooLarge,
}

/// Parses `seconds[.fraction]` into nanoseconds without rounding.
///
/// Refused: signs, exponents, blanks, empty parts (`.5`, `5.`), more than nine decimals (they
/// would need rounding, which would break the promise of exact stamps) and values beyond
/// `u64`.
pub fn parse_stamp_ns(text: &str) -> Result<u64, StampError> {
    let bad = |reason| StampError {
        text: text.to_owned(),
        reason,
    };
    let (seconds, fraction) = match text.split_once('.') {
        Some((seconds, fraction)) => (seconds, Some(fraction)),
        None => (text, None),
    };
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !all_digits(seconds) {
        return Err(bad(StampProblem::Seconds));
    }
    let nanos = match fraction {
        None => 0,
        Some(fraction) if !all_digits(fraction) => return Err(bad(StampProblem::Fraction)),
        Some(fraction) if fraction.len() > MAX_DECIMALS => {
            return Err(bad(StampProblem::TooPrecise));
        }
        // Right-padding to nine digits scales e.g. micro- to nanoseconds: "123456" -> "123456000".
        Some(fraction) => format!("{fraction:0<MAX_DECIMALS$}")
            .parse::<u64>()
            .map_err(|_| bad(StampProblem::Fraction))?,
    };
    seconds
        .parse::<u64>()
        .ok()
        .and_then(|s| s.checked_mul(NANOS_PER_SECOND))
        .and_then(|ns| ns.checked_add(nanos))
        .ok_or_else(|| bad(StampProblem::TooLarge))
}

/// Nanoseconds as decimal seconds with nine decimals: [`parse_stamp_ns`] reads it back
/// exactly.
pub fn format_stamp(stamp_ns: u64) -> String {
    format!(
        "{}.{:09}",
        stamp_ns / NANOS_PER_SECOND,
        stamp_ns % NANOS_PER_SECOND
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn microsecond_stamps_are_kept_exactly() {
        assert_eq!(
            parse_stamp_ns("1058295543.123456"),
            Ok(1_058_295_543_123_456_000)
        );
        assert_eq!(parse_stamp_ns("0.000001"), Ok(1_000));
        assert_eq!(parse_stamp_ns("0.000000001"), Ok(1));
        assert_eq!(parse_stamp_ns("12"), Ok(12_000_000_000));
        assert_eq!(parse_stamp_ns("0.5"), Ok(500_000_000));
    }

    #[test]
    fn an_f64_would_not_have_kept_them() {
        // The reason for integer parsing: through an f64 the MIT CSAIL log's first stamp
        // comes out 48 ns early.
        let through_f64 = ("1134864629.895182".parse::<f64>().unwrap() * 1e9) as u64;
        assert_eq!(through_f64, 1_134_864_629_895_181_952);
        assert_eq!(
            parse_stamp_ns("1134864629.895182"),
            Ok(1_134_864_629_895_182_000)
        );
    }

    #[test]
    fn anything_but_plain_decimal_seconds_is_refused_with_the_reason() {
        let refused: [(StampProblem, &[&str]); 4] = [
            (
                StampProblem::Seconds,
                &["", "-1.5", "+1.5", "1e9", ".5", " 1.5", "nan"],
            ),
            (StampProblem::Fraction, &["5.", "1.2.3"]),
            (StampProblem::TooPrecise, &["1.0000000001"]),
            (
                StampProblem::TooLarge,
                &["99999999999999999999", "18446744074.0"],
            ),
        ];
        for (reason, texts) in refused {
            for text in texts {
                assert_eq!(
                    parse_stamp_ns(text).map_err(|e| e.reason),
                    Err(reason),
                    "{text:?}"
                );
            }
        }
        assert_eq!(
            parse_stamp_ns("5.").unwrap_err().to_string(),
            "\"5.\" is not a timestamp in seconds (expected digits after the decimal point)"
        );
    }

    #[test]
    fn formatted_stamps_read_back_exactly() {
        for stamp in [0, 1, 5_000_000_000, 1_134_864_629_895_182_000, u64::MAX] {
            assert_eq!(parse_stamp_ns(&format_stamp(stamp)), Ok(stamp));
        }
        assert_eq!(format_stamp(u64::MAX), "18446744073.709551615");
    }
}
