//! When to publish a record: at once in lockstep, or at the log's own pace scaled by a rate.

use std::time::{Duration, Instant};

pub use ipc_types::rate::RATE_RANGE;
use ipc_types::rate::RateUnit;

/// A replay's rate is a factor of the log's own speed.
const SPEED_FACTOR: RateUnit = RateUnit {
    before: "a speed factor ",
    after: " (1 = as recorded)",
};

/// Checks a speed factor: 0 (lockstep) or within [`RATE_RANGE`].
pub fn check_rate(rate: f64) -> Result<f64, String> {
    ipc_types::rate::check_rate(rate, SPEED_FACTOR)
}

/// `--rate`'s parser: a number that passes [`check_rate`].
pub fn parse_rate(text: &str) -> Result<f64, String> {
    ipc_types::rate::parse_rate(text, SPEED_FACTOR)
}

/// Maps log stamps to wall-clock deadlines. The first stamp asked about is published at
/// once and anchors the rest: a record `dt` of log time later is due `dt / rate` later.
#[derive(Debug, Clone)]
pub struct Pacer {
    /// `None` in lockstep: nothing waits for the clock, only for the subscribers.
    rate: Option<f64>,
    origin: Option<(u64, Instant)>,
}

impl Pacer {
    /// `rate` 0 = lockstep, 1 = as recorded, 2 = twice as fast; see [`check_rate`]. A rate
    /// outside it is not refused here, but a record it would put beyond any clock is due at
    /// the latest time the clock has rather than a panic.
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
        // Far enough to be never in practice, near enough for any Instant to hold.
        const NEVER: Duration = Duration::from_secs(100 * 365 * 86_400);
        let wait = Duration::try_from_secs_f64(log_elapsed / rate).map_or(NEVER, |w| w.min(NEVER));
        Some(origin_time + wait)
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
    fn rates_are_lockstep_or_in_range_and_no_rate_panics() {
        for good in ["0", "0.001", "1", "1000"] {
            assert!(parse_rate(good).is_ok(), "{good}");
        }
        for bad in ["1e-20", "-1", "1001", "inf", "NaN"] {
            let error = parse_rate(bad).unwrap_err();
            assert!(
                error.contains("must be 0 (lockstep) or a speed factor from 0.001 to 1000"),
                "{bad}: {error}"
            );
        }
        // A rate that passed no check still gives a time, not a panic.
        let start = Instant::now();
        let mut pacer = Pacer::new(1e-20);
        pacer.due(0, start);
        assert!(pacer.due(u64::MAX, start).unwrap() > start);
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
