//! A harder version of a log, made on the fly: fewer scans (a slower sensor, or a robot
//! twice as fast between scans) and a shorter range (a smaller sensor). The same log then
//! tests how the pipeline copes with what other robots' logs will throw at it, and two
//! builds can be compared on it with one command rather than on files cut by hand.

use std::fmt;
use std::num::NonZeroU64;

use crate::record::ScanRecord;

/// What a replay leaves out of its log. The default leaves out nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Degradation {
    /// Publish the first scan and every `every`-th after it; the odometry is published whole
    /// (a slower sensor on the same robot).
    pub every: NonZeroU64,
    /// Ranges beyond this many metres become no-returns (+inf), and the scans say so in
    /// their `range_max`: a sensor that sees no further.
    pub max_range_m: Option<f32>,
}

/// Why a [`Degradation`] cannot be made.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DegradationError {
    #[error("--every must be at least 1 (every scan)")]
    NoScans,
    #[error("--max-range must be a positive number of metres, not {0}")]
    BadRange(f64),
}

impl Default for Degradation {
    fn default() -> Self {
        Self::NONE
    }
}

impl Degradation {
    /// Every scan, every range.
    pub const NONE: Self = Self {
        every: NonZeroU64::MIN,
        max_range_m: None,
    };

    /// From the options: `every` scans one is published, ranges up to `max_range_m`.
    pub fn new(every: u64, max_range_m: Option<f64>) -> Result<Self, DegradationError> {
        let every = NonZeroU64::new(every).ok_or(DegradationError::NoScans)?;
        let max_range_m = max_range_m
            .map(|m| {
                if m.is_finite() && m > 0.0 {
                    Ok(m as f32)
                } else {
                    Err(DegradationError::BadRange(m))
                }
            })
            .transpose()?;
        Ok(Self { every, max_range_m })
    }

    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }

    /// Whether the log's scan number `index` (from 0, counted after any `--skip`) is
    /// published.
    pub fn keeps(&self, index: u64) -> bool {
        index.is_multiple_of(self.every.get())
    }

    /// Cuts `scan`'s ranges to the shorter sensor's; returns how many beams it made
    /// no-returns. Errors (NaN) and no-returns stay as they are.
    pub fn shorten(&self, scan: &mut ScanRecord) -> u64 {
        let Some(max) = self.max_range_m else {
            return 0;
        };
        scan.geometry.range_max = scan.geometry.range_max.min(f64::from(max));
        let mut cut = 0;
        for range in scan
            .ranges
            .iter_mut()
            .filter(|r| r.is_finite() && **r > max)
        {
            *range = f32::INFINITY;
            cut += 1;
        }
        cut
    }
}

/// `every 3rd scan, ranges to 5 m`, for the summary and the console.
impl fmt::Display for Degradation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        match self.every.get() {
            1 => {}
            n => parts.push(format!("every {}{} scan", n, ordinal_suffix(n))),
        }
        if let Some(m) = self.max_range_m {
            parts.push(format!("ranges to {m} m"));
        }
        if parts.is_empty() {
            parts.push("whole".to_owned());
        }
        f.write_str(&parts.join(", "))
    }
}

fn ordinal_suffix(n: u64) -> &'static str {
    match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::seed_csv::GEOMETRY;

    #[test]
    fn every_nth_scan_is_kept_from_the_first() {
        let third = Degradation::new(3, None).unwrap();
        let kept: Vec<u64> = (0..10).filter(|&i| third.keeps(i)).collect();
        assert_eq!(kept, [0, 3, 6, 9]);
        assert!((0..10).all(|i| Degradation::NONE.keeps(i)));
        assert_eq!(third.to_string(), "every 3rd scan");
        assert_eq!(
            Degradation::new(12, None).unwrap().to_string(),
            "every 12th scan"
        );
        assert_eq!(
            Degradation::new(22, None).unwrap().to_string(),
            "every 22nd scan"
        );
    }

    #[test]
    fn ranges_beyond_the_shorter_sensor_become_no_returns() {
        let mut scan = ScanRecord {
            line: 1,
            stamp_ns: 0,
            log_stamp_ns: 0,
            geometry: GEOMETRY,
            ranges: vec![0.5, 5.0, 5.01, 40.0, f32::NAN, f32::INFINITY],
            intensities: Vec::new(),
            robot_from_sensor: slam_geom::Pose2::IDENTITY,
        };
        let five = Degradation::new(1, Some(5.0)).unwrap();
        assert_eq!(five.shorten(&mut scan), 2);
        assert_eq!(scan.ranges[..4], [0.5, 5.0, f32::INFINITY, f32::INFINITY]);
        assert!(scan.ranges[4].is_nan());
        assert_eq!(scan.ranges[5], f32::INFINITY);
        assert_eq!(scan.geometry.range_max, 5.0);
        assert_eq!(five.to_string(), "ranges to 5 m");
        assert_eq!(Degradation::NONE.shorten(&mut scan), 0);
    }

    #[test]
    fn bad_options_are_refused() {
        assert_eq!(Degradation::new(0, None), Err(DegradationError::NoScans));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Degradation::new(1, Some(bad)).is_err(), "{bad}");
        }
        assert!(Degradation::new(1, None).unwrap().is_none());
    }
}
