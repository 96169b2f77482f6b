//! Angle wrapping, done once where an angle is made (docs/CONVENTIONS.md).

use std::f64::consts::{PI, TAU};

/// Wraps an angle to `[-pi, pi)`; a non-finite angle stays non-finite.
// Inlined across crates: the filters call it in their innermost loops, and the common
// case is two comparisons.
#[inline]
pub fn wrap_angle(angle: f64) -> f64 {
    // Most angles are sums of two wrapped ones: one step of 2 pi brings them back without
    // the division that the general case needs.
    if (-PI..PI).contains(&angle) {
        return angle;
    }
    let once = if angle < 0.0 {
        angle + TAU
    } else {
        angle - TAU
    };
    if (-PI..PI).contains(&once) {
        return once;
    }
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
        assert!((wrap_angle(-0.25) + 0.25).abs() < 1e-15);
        assert!(wrap_angle(-1e-18) < PI);
        assert!(wrap_angle(f64::NAN).is_nan());
        assert!(wrap_angle(f64::INFINITY).is_nan());
        for k in -20..=20 {
            let a = 0.37 * f64::from(k);
            let w = wrap_angle(a);
            assert!((-PI..PI).contains(&w));
            assert!(((a - w) / TAU - ((a - w) / TAU).round()).abs() < 1e-12);
        }
    }
}
