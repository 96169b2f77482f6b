//! How long the end step may take.
//!
//! At a normal end (the source's end of stream) map-sink takes as long as its results need,
//! so that they are the same on every run. A stopped run (Ctrl-C, SIGTERM) is killed by
//! slam-launch once its grace period is over, so from the stop on map-sink has a budget:
//! the refinement of the path stops in time for what it reached to be written. The stop
//! may come before the end step or during it; it is noticed where the clock is read.

use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The end step's deadline: none until the run is stopped, then `budget` after the stop.
/// Read from every core the refinement runs on.
pub struct EndClock<'a> {
    budget: Option<Duration>,
    stopped: &'a (dyn Fn() -> bool + Sync),
    /// The first moment the stop was seen; later sightings do not move it.
    stopped_at: OnceLock<Instant>,
}

impl std::fmt::Debug for EndClock<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EndClock")
            .field("budget", &self.budget)
            .field("stopped_at", &self.stopped_at.get())
            .finish_non_exhaustive()
    }
}

impl<'a> EndClock<'a> {
    /// A clock that never runs out: the end step takes what it needs.
    pub fn unlimited() -> Self {
        Self::new(None, &|| false)
    }

    /// Once `stopped` says the run was stopped, the end step has `budget` from the moment
    /// that was first seen (`None`: no limit even then).
    pub fn new(budget: Option<Duration>, stopped: &'a (dyn Fn() -> bool + Sync)) -> Self {
        Self {
            budget,
            stopped,
            stopped_at: OnceLock::new(),
        }
    }

    /// The run was stopped at `at` (the process saw the signal then, before the end step);
    /// an earlier moment already noted stands.
    pub fn stop_seen_at(&self, at: Instant) {
        // Set already: the earlier moment stands.
        let _ = self.stopped_at.set(at);
    }

    /// When the run was stopped, if it was (as far as seen by `now`).
    pub fn stopped_at(&self, now: Instant) -> Option<Instant> {
        if self.stopped_at.get().is_none() && (self.stopped)() {
            // Another core may have seen it first: its moment stands.
            let _ = self.stopped_at.set(now);
        }
        self.stopped_at.get().copied()
    }

    /// The time left at `now`; `None` while there is no limit.
    pub fn left_at(&self, now: Instant) -> Option<Duration> {
        let stopped = self.stopped_at(now)?;
        let budget = self.budget?;
        Some((stopped + budget).saturating_duration_since(now))
    }

    /// True while more than `needed` is left (always, while there is no limit).
    pub fn has(&self, needed: Duration) -> bool {
        self.left_at(Instant::now())
            .is_none_or(|left| left > needed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};

    #[test]
    fn an_unstopped_run_has_all_the_time_it_needs() {
        let clock = EndClock::new(Some(Duration::ZERO), &|| false);
        assert_eq!(clock.left_at(Instant::now()), None);
        assert!(clock.has(Duration::from_secs(1_000_000)));
        assert!(EndClock::unlimited().has(Duration::MAX));
    }

    #[test]
    fn the_budget_counts_from_the_stop_seen_before_the_end_step() {
        let stop = Instant::now();
        let clock = EndClock::new(Some(Duration::from_secs(10)), &|| true);
        clock.stop_seen_at(stop);
        // A later sighting does not move the stop.
        clock.stop_seen_at(stop + Duration::from_secs(5));
        assert_eq!(clock.stopped_at(stop + Duration::from_secs(7)), Some(stop));
        let left = clock.left_at(stop + Duration::from_secs(4));
        assert_eq!(left, Some(Duration::from_secs(6)));
        assert_eq!(
            clock.left_at(stop + Duration::from_secs(11)),
            Some(Duration::ZERO)
        );
    }

    #[test]
    fn a_stop_during_the_end_step_starts_the_budget_when_it_is_first_seen() {
        let stopped = AtomicBool::new(false);
        let is_stopped = || stopped.load(Ordering::Relaxed);
        let clock = EndClock::new(Some(Duration::from_secs(3)), &is_stopped);
        let start = Instant::now();
        assert_eq!(clock.left_at(start), None, "not stopped yet");
        stopped.store(true, Ordering::Relaxed);
        let seen = start + Duration::from_secs(20);
        assert_eq!(clock.left_at(seen), Some(Duration::from_secs(3)));
        assert_eq!(
            clock.left_at(seen + Duration::from_secs(1)),
            Some(Duration::from_secs(2))
        );
    }

    #[test]
    fn a_stopped_run_without_a_budget_has_no_limit() {
        let clock = EndClock::new(None, &|| true);
        let now = Instant::now();
        assert_eq!(clock.stopped_at(now), Some(now));
        assert_eq!(clock.left_at(now), None);
        assert!(clock.has(Duration::from_secs(3600)));
    }

    #[test]
    fn a_spent_budget_has_no_time_for_anything() {
        let clock = EndClock::new(Some(Duration::ZERO), &|| true);
        assert!(!clock.has(Duration::ZERO));
    }
}
