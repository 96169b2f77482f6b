//! Angle wrapping, done once where an angle is made (docs/CONVENTIONS.md).

use std::f64::consts::{PI, TAU};

/// Wraps an angle to `[-pi, pi)`; a non-finite angle stays non-finite.
pub fn wrap_angle(angle: f64) -> f64 {
    let wrapped = (angle + PI).rem_euclid(TAU) - PI;
    // `rem_euclid` can round up to exactly TAU for inputs just below a multiple of it.
    if wrapped >= PI {
        wrapped - TAU
    } else {
        wrapped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_into_the_half_open_interval() {
        assert_eq!(wrap_angle(PI), -PI);
        assert_eq!(wrap_angle(-PI), -PI);
        assert!((wrap_angle(3.0 * PI + 0.5) - (-PI + 0.5)).abs() < 1e-12);
        assert!((wrap_angle(-2.255213) + 2.255213).abs() < 1e-15);
        assert!(wrap_angle(f64::NAN).is_nan());
    }
}
