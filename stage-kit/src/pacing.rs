//! When a source publishes: at once in lockstep, or at a real-time rate.
//!
//! Every scan source takes a `--rate`: 0 for lockstep (each message waits for the
//! subscribers, not for the clock), or a rate within [`RATE_RANGE`]. What the rate counts
//! is the source's own ([`RateUnit`]: scans per second, a log's speed factor); the range,
//! the check, the clock and the sliced sleep are one.

use std::ops::RangeInclusive;
use std::time::{Duration, Instant};

/// Real-time rates a source may be given; 0 (lockstep) is allowed besides. A thousandth
/// stretches the period of a scan, or a day-long log, far inside a `Duration`; a thousand
/// is beyond what the stages keep up with, and lockstep is the way to go as fast as they can.
pub const RATE_RANGE: RangeInclusive<f64> = 0.001..=1000.0;

/// What a source's rate means, for its error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RateUnit {
    /// Said before the range, e.g. `"a speed factor "` (or nothing).
    pub before: &'static str,
    /// Said after it, e.g. `" scans per second"`.
    pub after: &'static str,
}

impl RateUnit {
    /// Checks a rate: 0 (lockstep) or within [`RATE_RANGE`]; the error says what may be
    /// given.
    pub fn check(self, rate: f64) -> Result<f64, String> {
        if rate == 0.0 || RATE_RANGE.contains(&rate) {
            Ok(rate)
        } else {
            Err(format!(
                "must be 0 (lockstep) or {}from {} to {}{}, not {rate:?}",
                self.before,
                RATE_RANGE.start(),
                RATE_RANGE.end(),
                self.after,
            ))
        }
    }

    /// A `--rate` argument: a number that passes [`RateUnit::check`].
    pub fn parse(self, text: &str) -> Result<f64, String> {
        let rate: f64 = text
            .trim()
            .parse()
            .map_err(|_| format!("'{text}' is not a number"))?;
        self.check(rate)
    }
}

/// Longest nap of [`sleep_until`]: how late a stop may be noticed while waiting.
pub const SLEEP_SLICE: Duration = Duration::from_millis(50);

/// Sleeps until `due` in naps of at most [`SLEEP_SLICE`], so a stop is noticed promptly
/// however long the wait (a slow rate, a gap in a log). Returns false when `stopped` said
/// so first.
pub fn sleep_until(due: Instant, stopped: impl Fn() -> bool) -> bool {
    loop {
        if stopped() {
            return false;
        }
        let left = due.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return true;
        }
        std::thread::sleep(left.min(SLEEP_SLICE));
    }
}

/// Maps a source's clock to wall-clock deadlines. The first stamp asked about is due at
/// once and anchors the rest: a record `dt` of source time later is due `dt / rate` later.
/// A log's stamps are its source time; a source that paces by count (scans per second)
/// gives its n-th record `n` seconds ([`Pacer::nth`]).
#[derive(Debug, Clone)]
pub struct Pacer {
    /// `None` in lockstep: nothing waits for the clock, only for the subscribers.
    rate: Option<f64>,
    origin: Option<(u64, Instant)>,
}

impl Pacer {
    /// `rate` 0 = lockstep; see [`RateUnit::check`]. A rate outside [`RATE_RANGE`] is not refused
    /// here, but a record it would put beyond any clock is due at the latest time the clock
    /// has rather than a panic.
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

    /// The source time of the `n`-th record of a source paced by count: `n` seconds, so
    /// that a rate counts records per second.
    pub fn nth(n: u64) -> u64 {
        n.saturating_mul(1_000_000_000)
    }

    /// When the record stamped `stamp_ns` is due, `now` being the time of asking; `None` in
    /// lockstep. A record stamped before the anchor (a log not in time order) is due at the
    /// anchor, i.e. at once.
    pub fn due(&mut self, stamp_ns: u64, now: Instant) -> Option<Instant> {
        let rate = self.rate?;
        let (origin_stamp, origin_time) = *self.origin.get_or_insert((stamp_ns, now));
        let elapsed = stamp_ns.saturating_sub(origin_stamp) as f64 * 1e-9;
        // Far enough to be never in practice, near enough for any Instant to hold.
        const NEVER: Duration = Duration::from_secs(100 * 365 * 86_400);
        let wait = Duration::try_from_secs_f64(elapsed / rate).map_or(NEVER, |w| w.min(NEVER));
        Some(origin_time + wait)
    }

    /// Waits until the record stamped `stamp_ns` is due (not at all in lockstep). Returns
    /// false when `stopped` said so first.
    pub fn wait(&mut self, stamp_ns: u64, stopped: impl Fn() -> bool) -> bool {
        match self.due(stamp_ns, Instant::now()) {
            Some(due) => sleep_until(due, stopped),
            None => !stopped(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HERTZ: RateUnit = RateUnit {
        before: "",
        after: " scans per second",
    };

    #[test]
    fn lockstep_and_the_range_pass_and_the_rest_is_named() {
        for good in ["0", "0.001", "1", "1000"] {
            assert!(HERTZ.parse(good).is_ok(), "{good}");
        }
        for bad in ["1e-20", "-1", "1000.5", "inf", "NaN"] {
            assert_eq!(
                HERTZ.parse(bad).unwrap_err(),
                format!(
                    "must be 0 (lockstep) or from 0.001 to 1000 scans per second, not {:?}",
                    bad.parse::<f64>().unwrap()
                )
            );
        }
        assert_eq!(HERTZ.parse("fast").unwrap_err(), "'fast' is not a number");
    }

    #[test]
    fn lockstep_never_waits() {
        let mut pacer = Pacer::new(0.0);
        assert!(pacer.is_lockstep());
        assert_eq!(pacer.due(5, Instant::now()), None);
        assert!(pacer.wait(5, || false));
        assert!(!pacer.wait(5, || true), "a stop is seen in lockstep too");
    }

    #[test]
    fn the_source_time_is_scaled_by_the_rate() {
        let start = Instant::now();
        let mut pacer = Pacer::new(2.0);
        let base = 1_134_864_629_895_182_000;
        assert_eq!(pacer.due(base, start), Some(start));
        let later = start + Duration::from_secs(100);
        assert_eq!(
            pacer.due(base + 1_000_000_000, later),
            Some(start + Duration::from_millis(500)),
            "one second of source time at twice the speed, from the first record's time"
        );
        assert_eq!(pacer.due(base - 1, later), Some(start));
    }

    #[test]
    fn a_count_paced_source_publishes_rate_records_a_second() {
        let start = Instant::now();
        let mut pacer = Pacer::new(40.0);
        assert_eq!(pacer.due(Pacer::nth(0), start), Some(start));
        assert_eq!(
            pacer.due(Pacer::nth(80), start),
            Some(start + Duration::from_secs(2))
        );
    }

    #[test]
    fn no_rate_panics() {
        // A rate that passed no check still gives a time, not a panic.
        let start = Instant::now();
        let mut pacer = Pacer::new(1e-20);
        pacer.due(0, start);
        assert!(pacer.due(u64::MAX, start).unwrap() > start);
    }

    #[test]
    fn a_long_wait_ends_at_the_stop() {
        let mut pacer = Pacer::new(0.001);
        assert!(pacer.wait(0, || false), "the first record is due at once");
        let asked = Instant::now();
        let looks = std::cell::Cell::new(0);
        let stopped = || {
            looks.set(looks.get() + 1);
            looks.get() > 2
        };
        assert!(!pacer.wait(1_000_000_000, stopped), "due in 1000 s");
        assert!(
            asked.elapsed() < Duration::from_secs(1),
            "stopped within slices"
        );
    }
}
