//! What the driver tells the console about a sensor it cannot reach: the first failure at
//! once, then at most one line every [`NOTICE_PERIOD`] (or when the reason changes), so a
//! sensor that is away shows without the console filling up; and a line when it comes back.
//!
//! The console is stdout: slam-launch shows a stage's stdout lines on its console, while
//! its stderr (every attempt, with its back-off) goes to the stage's log file.

use std::time::{Duration, Instant};

/// Least time between two notices of the same failure.
pub const NOTICE_PERIOD: Duration = Duration::from_secs(10);

/// Failed attempts and the notices given about them.
#[derive(Debug, Clone, Default)]
pub struct ConnectionNotices {
    /// Attempts that failed since the last success.
    failed: u64,
    /// Failed attempts over the whole run.
    failed_total: u64,
    /// What went wrong last, for the end of a run that got no scan.
    last_problem: Option<String>,
    /// When and about what the last notice was given.
    last_notice: Option<(Instant, String)>,
}

impl ConnectionNotices {
    /// Counts a failed attempt (`problem` says what failed, `reason` is the short kind
    /// compared for changes). Returns the notice to show, if one is due.
    pub fn failure(&mut self, now: Instant, problem: &str, reason: &str) -> Option<String> {
        self.failed += 1;
        self.failed_total += 1;
        self.last_problem = Some(problem.to_owned());
        let due = match &self.last_notice {
            None => true,
            Some((at, last_reason)) => {
                last_reason != reason || now.duration_since(*at) >= NOTICE_PERIOD
            }
        };
        if !due {
            return None;
        }
        self.last_notice = Some((now, reason.to_owned()));
        Some(if self.failed == 1 {
            format!("{problem}; retrying")
        } else {
            format!("{problem} ({} attempts so far); retrying", self.failed)
        })
    }

    /// Counts a success (a scan published). Returns a notice when failures were shown
    /// before, so the console knows the sensor is back.
    pub fn success(&mut self, peer: &str) -> Option<String> {
        let failed = std::mem::take(&mut self.failed);
        let shown = self.last_notice.take().is_some();
        (shown && failed > 0).then(|| format!("scans from {peer} after {failed} failed attempts"))
    }

    /// Failed attempts over the whole run.
    pub fn failed_total(&self) -> u64 {
        self.failed_total
    }

    /// What went wrong last, if anything did.
    pub fn last_problem(&self) -> Option<&str> {
        self.last_problem.as_deref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_failure_shows_then_one_per_period_or_per_new_reason() {
        let start = Instant::now();
        let mut notices = ConnectionNotices::default();
        let at = |ms: u64| start + Duration::from_millis(ms);
        assert_eq!(
            notices.failure(at(0), "cannot connect to a: refused", "refused"),
            Some("cannot connect to a: refused; retrying".to_owned())
        );
        assert_eq!(
            notices.failure(at(100), "cannot connect to a: refused", "refused"),
            None
        );
        assert_eq!(
            notices.failure(at(9_000), "cannot connect to a: refused", "refused"),
            None
        );
        assert_eq!(
            notices.failure(at(10_100), "cannot connect to a: refused", "refused"),
            Some("cannot connect to a: refused (4 attempts so far); retrying".to_owned())
        );
        assert_eq!(
            notices.failure(at(10_200), "a: not a SCIP sensor", "not scip"),
            Some("a: not a SCIP sensor (5 attempts so far); retrying".to_owned())
        );
        assert_eq!(notices.last_problem(), Some("a: not a SCIP sensor"));
        assert_eq!(
            notices.success("a"),
            Some("scans from a after 5 failed attempts".to_owned())
        );
        assert_eq!(notices.success("a"), None);
        // After a success the next failure shows at once again.
        assert!(notices.failure(at(10_300), "lost", "lost").is_some());
        assert_eq!(notices.failed_total(), 6);
    }
}
