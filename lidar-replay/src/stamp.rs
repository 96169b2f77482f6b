//! Decimal seconds (`1058295543.123456`) to integer nanoseconds, exactly.
//!
//! An `f64` has about 16 significant digits, too few for today's epoch in nanoseconds, so a
//! stamp read through it would come out a few hundred nanoseconds off. The digits are parsed
//! as integers instead.

/// Nanoseconds in a second.
const NANOS_PER_SECOND: u64 = 1_000_000_000;
/// Decimals a nanosecond stamp can hold.
const MAX_DECIMALS: usize = 9;

/// Parses `seconds[.fraction]` into nanoseconds without rounding.
///
/// Refused: signs, exponents, empty parts (`.5`, `5.`), more than nine decimals (they would
/// need rounding, which would break the promise of exact stamps) and values beyond `u64`.
pub fn parse_stamp_ns(text: &str) -> Result<u64, String> {
    let bad = |why: &str| format!("{text:?} is not a timestamp in seconds ({why})");
    let (seconds, fraction) = match text.split_once('.') {
        Some((seconds, fraction)) => (seconds, Some(fraction)),
        None => (text, None),
    };
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !all_digits(seconds) {
        return Err(bad("expected digits before the decimal point"));
    }
    let nanos = match fraction {
        None => 0,
        Some(fraction) if !all_digits(fraction) => {
            return Err(bad("expected digits after the decimal point"));
        }
        Some(fraction) if fraction.len() > MAX_DECIMALS => {
            return Err(bad("more than 9 decimals cannot be kept exactly"));
        }
        // Right-padding to nine digits scales e.g. micro- to nanoseconds: "123456" -> "123456000".
        Some(fraction) => format!("{fraction:0<MAX_DECIMALS$}")
            .parse::<u64>()
            .map_err(|_| bad("expected digits after the decimal point"))?,
    };
    seconds
        .parse::<u64>()
        .ok()
        .and_then(|s| s.checked_mul(NANOS_PER_SECOND))
        .and_then(|ns| ns.checked_add(nanos))
        .ok_or_else(|| bad("too large"))
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
        assert_eq!(
            parse_stamp_ns("1134864629.895182"),
            Ok(1_134_864_629_895_182_000)
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
    fn anything_but_plain_decimal_seconds_is_refused() {
        for text in [
            "",
            "-1.5",
            "+1.5",
            "1e9",
            ".5",
            "5.",
            "1.2.3",
            "1.0000000001",
            "nan",
            "99999999999999999999",
            "18446744074.0",
            " 1.5",
        ] {
            assert!(parse_stamp_ns(text).is_err(), "{text:?} was accepted");
        }
    }
}
