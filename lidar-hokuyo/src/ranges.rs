//! Sensor values in millimetres to `LaserScan` ranges in metres, error codes to REP 117.
//!
//! A value below `DMIN` is not a distance but an error code. The SCIP 2.0 specification
//! (table 4, UTM-30LX; the UST and UXM Ethernet models use the same codes) and REP 117
//! give:
//!
//! | code | sensor's meaning                          | range  | REP 117 meaning   |
//! |------|-------------------------------------------|--------|-------------------|
//! | 1    | no object in the range                    | `+inf` | no return         |
//! | 2    | object too near (internal error)          | `-inf` | too close         |
//! | 4    | object out of range at the near end       | `-inf` | too close         |
//! | 3    | measurement error (e.g. interference)     | `NaN`  | measurement error |
//! | 5    | other errors                              | `NaN`  | measurement error |
//! | any other value below `DMIN` (0, 6, ..., e.g. 19 on the last steps) | | `NaN` | measurement error |
//!
//! A value of `DMIN` or more is a distance and becomes `mm / 1000` as `f32` (correctly
//! rounded, so it equals the millimetres of a log divided by 1000 in `f32`). A distance
//! beyond `DMAX` is passed on as it is: consumers treat anything outside
//! `[range_min, range_max]` as invalid.

/// Error code: nothing reflected within the range.
pub const NO_RETURN: u32 = 1;
/// Error codes meaning the object is closer than the sensor can measure.
pub const TOO_CLOSE: [u32; 2] = [2, 4];

/// The range in metres of one sensor value, or its REP 117 code.
pub fn range_m(value_mm: u32, dmin_mm: u32) -> f32 {
    if value_mm >= dmin_mm {
        // Below 2^24, so exact in f32; one division rounds once.
        value_mm as f32 / 1000.0
    } else if value_mm == NO_RETURN {
        f32::INFINITY
    } else if TOO_CLOSE.contains(&value_mm) {
        f32::NEG_INFINITY
    } else {
        f32::NAN
    }
}

/// Converts a scan's values.
pub fn ranges_m(values_mm: &[u32], dmin_mm: u32, out: &mut Vec<f32>) {
    out.clear();
    out.extend(values_mm.iter().map(|&v| range_m(v, dmin_mm)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_become_metres_exactly() {
        assert_eq!(range_m(23, 23), 0.023);
        assert_eq!(range_m(5432, 23), 5.432);
        assert_eq!(range_m(36_881, 23), 36.881);
        for mm in (23..200_000).step_by(7) {
            assert_eq!(range_m(mm, 23), (f64::from(mm) / 1000.0) as f32);
        }
        // Beyond DMAX it stays a number; consumers check range_max.
        assert_eq!(range_m(65_000, 23), 65.0);
    }

    #[test]
    fn error_codes_follow_rep_117() {
        assert_eq!(range_m(1, 23), f32::INFINITY);
        assert_eq!(range_m(2, 23), f32::NEG_INFINITY);
        assert_eq!(range_m(4, 23), f32::NEG_INFINITY);
        for code in [0, 3, 5, 6, 19, 22] {
            assert!(range_m(code, 23).is_nan(), "{code}");
        }
    }

    #[test]
    fn a_scan_converts_in_place() {
        let mut out = vec![7.0; 10];
        ranges_m(&[1, 19, 1000, 2], 23, &mut out);
        assert_eq!(out.len(), 4);
        assert_eq!(out[0], f32::INFINITY);
        assert!(out[1].is_nan());
        assert_eq!(out[2], 1.0);
        assert_eq!(out[3], f32::NEG_INFINITY);
    }
}
