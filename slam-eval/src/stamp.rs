//! Decimal seconds to integer nanoseconds, exactly, so a trajectory's stamps meet the
//! relations' stamps digit for digit instead of through `f64` rounding.

/// Parses `seconds[.fraction]` (at most nine decimals, no sign, no exponent) into
/// nanoseconds.
pub fn parse_stamp_ns(text: &str) -> Result<u64, String> {
    let bad = || format!("{text:?} is not a stamp in seconds with at most 9 decimals");
    let (seconds, fraction) = text.split_once('.').unwrap_or((text, "0"));
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(seconds) || !digits(fraction) || fraction.len() > 9 {
        return Err(bad());
    }
    // "5" after the point is 500 000 000 ns: pad to nine digits.
    let nanos: u64 = format!("{fraction:0<9}").parse().map_err(|_| bad())?;
    seconds
        .parse::<u64>()
        .ok()
        .and_then(|s| s.checked_mul(1_000_000_000))
        .and_then(|ns| ns.checked_add(nanos))
        .ok_or_else(bad)
}

/// Nanoseconds as decimal seconds with nine digits, for messages.
pub fn format_stamp(stamp_ns: u64) -> String {
    format!(
        "{}.{:09}",
        stamp_ns / 1_000_000_000,
        stamp_ns % 1_000_000_000
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_are_exact() {
        assert_eq!(
            parse_stamp_ns("1134864629.895182"),
            Ok(1_134_864_629_895_182_000)
        );
        assert_eq!(parse_stamp_ns("0.000001"), Ok(1_000));
        assert_eq!(parse_stamp_ns("3"), Ok(3_000_000_000));
        assert_eq!(
            format_stamp(1_134_864_629_895_182_000),
            "1134864629.895182000"
        );
        for bad in ["", "-1", "1e3", ".5", "5.", "1.0000000001", "x"] {
            assert!(parse_stamp_ns(bad).is_err(), "{bad:?}");
        }
    }
}
