//! When to publish a record: at once in lockstep, or at the log's own pace scaled by a rate.

use std::time::{Duration, Instant};

/// Maps log stamps to wall-clock deadlines. The first stamp asked about is published at
/// once and anchors the rest: a record `dt` of log time later is due `dt / rate` later.
#[derive(Debug, Clone)]
pub struct Pacer {
    /// `None` in lockstep: nothing waits for the clock, only for the subscribers.
    rate: Option<f64>,
    origin: Option<(u64, Instant)>,
}

impl Pacer {
    /// `rate` 0 = lockstep, 1 = as recorded, 2 = twice as fast. Must be finite and >= 0.
    pub fn new(rate: f64) -> Self {
        Self {
            rate: (rate > 0.0).then_some(rate),
            origin: None,
        }
    }

    /// True when records go out as fast as the subscribers take them.
    pub fn is_lockstep(&self) -> bool {
        self.rate.is_none()
    }

    /// When the record stamped `stamp_ns` is due, `now` being the time of asking; `None` in
    /// lockstep. A record stamped before the anchor (the log is not in time order) is due
    /// at the anchor, i.e. at once.
    pub fn due(&mut self, stamp_ns: u64, now: Instant) -> Option<Instant> {
        let rate = self.rate?;
        let (origin_stamp, origin_time) = *self.origin.get_or_insert((stamp_ns, now));
        let log_elapsed = stamp_ns.saturating_sub(origin_stamp) as f64 * 1e-9;
        Some(origin_time + Duration::from_secs_f64(log_elapsed / rate))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lockstep_never_waits() {
        let mut pacer = Pacer::new(0.0);
        assert!(pacer.is_lockstep());
        assert_eq!(pacer.due(5, Instant::now()), None);
    }

    #[test]
    fn the_logs_timing_is_scaled_by_the_rate() {
        let start = Instant::now();
        let mut pacer = Pacer::new(2.0);
        let base = 1_134_864_629_895_182_000;
        assert_eq!(pacer.due(base, start), Some(start));
        let later = start + Duration::from_secs(100);
        assert_eq!(
            pacer.due(base + 1_000_000_000, later),
            Some(start + Duration::from_millis(500)),
            "one log second at twice the speed, from the first record's time"
        );
        assert_eq!(pacer.due(base - 1, later), Some(start));
    }

    #[test]
    fn real_time_is_rate_one() {
        let start = Instant::now();
        let mut pacer = Pacer::new(1.0);
        pacer.due(0, start);
        assert_eq!(
            pacer.due(213_386_000, start),
            Some(start + Duration::from_nanos(213_386_000))
        );
    }
}
