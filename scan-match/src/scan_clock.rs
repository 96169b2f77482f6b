//! The time between scans as the front end's motion model sees it. Some loggers stamp a
//! scan when they write it, not when it was taken: stamps then come in bursts (two scans a
//! millisecond apart, then a long pause) while the sensor turned at its steady rate. A
//! speed or an acceleration over such an interval is meaningless. A sensor does not take
//! two scans a tenth of its period apart, so where the recent intervals hold one that short
//! the stamps are the logger's, and each step is timed by the longer of its interval and
//! the mean of the recent ones (the sensor's rate, which bursts do not change). Stamps
//! without bursts time their steps as they are.

use std::collections::VecDeque;

use crate::prior::MAX_EXTRAPOLATION_S;

/// Intervals the mean is taken over.
const SPAN: usize = 50;

/// An interval under this share of the mean is not a sensor's: the stamps come in bursts.
const BURST: f64 = 0.1;

/// Intervals shorter than this (repeated or reordered stamps) count as this long, seconds.
pub(crate) const MIN_DT: f64 = 1e-3;

#[derive(Debug, Clone, Default)]
pub(crate) struct ScanClock {
    /// The recent intervals, seconds; pauses longer than [`MAX_EXTRAPOLATION_S`] left out.
    recent: VecDeque<f64>,
}

impl ScanClock {
    /// The interval to move the robot over for a scan `elapsed` seconds (by the stamps)
    /// after the previous one.
    pub fn interval(&mut self, elapsed: f64) -> f64 {
        let elapsed = elapsed.max(0.0);
        if elapsed <= MAX_EXTRAPOLATION_S {
            if self.recent.len() == SPAN {
                self.recent.pop_front();
            }
            self.recent.push_back(elapsed);
        }
        let mean = self.recent.iter().sum::<f64>() / self.recent.len().max(1) as f64;
        let bursts = self.recent.iter().any(|&dt| dt < BURST * mean);
        let interval = if bursts { elapsed.max(mean) } else { elapsed };
        interval.max(MIN_DT)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_rate_with_jitter_is_its_own_interval() {
        let mut clock = ScanClock::default();
        for k in 0..40 {
            let elapsed = if k % 2 == 0 { 0.02 } else { 0.03 };
            assert_eq!(clock.interval(elapsed), elapsed);
        }
    }

    #[test]
    fn bursts_are_timed_at_the_sensors_rate() {
        let mut clock = ScanClock::default();
        // Pairs a millisecond apart, 0.4 s between pairs: a scan every 0.2 s on average.
        let mut last = 0.0;
        for k in 0..40 {
            last = clock.interval(if k % 2 == 0 { 0.399 } else { 0.001 });
        }
        assert!((last - 0.2).abs() < 1e-9, "{last}");
    }

    #[test]
    fn a_pause_is_timed_as_long_as_it_was_and_does_not_slow_the_rate() {
        let mut clock = ScanClock::default();
        for _ in 0..20 {
            clock.interval(0.025);
        }
        assert_eq!(clock.interval(5.0), 5.0);
        assert!((clock.interval(0.025) - 0.025).abs() < 1e-12);
    }
}
