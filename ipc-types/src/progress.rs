//! What a process took in and sent out, per topic, told to slam-launch on stdout.
//!
//! The launcher sees its stages only from outside. To say which stage has stalled it needs
//! more than "the pipeline stopped moving": in lockstep every stage stops at once when one
//! does. So every [`crate::Inlet`] counts the messages it receives and every
//! [`crate::Outlet`] the messages it sends, and, when the process was started with
//! [`ENV`] set (slam-launch does), a thread of its own prints them every [`PERIOD`] when
//! they have changed:
//!
//! ```text
//! progress in:lidar/scan=120 out:perception/features=119
//! ```
//!
//! A thread, not the process's loop: a loop blocked on a full subscriber or a long
//! computation would otherwise stop reporting, and its last counts would be stale. A
//! frozen process (SIGSTOP) stops reporting altogether, and its counts stay where they
//! were, which is what the launcher needs to find it.

use std::collections::BTreeMap;
use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

/// Set (to anything) in a process's environment to have it report its counts on stdout.
pub const ENV: &str = "SLAM_PROGRESS";
/// How often the counts are looked at, and printed when they changed.
pub const PERIOD: Duration = Duration::from_millis(200);
/// The first word of a progress line.
pub const PREFIX: &str = "progress";

/// Which way messages go through a port.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Direction {
    /// Received by an inlet.
    In,
    /// Sent by an outlet.
    Out,
}

impl Direction {
    fn word(self) -> &'static str {
        match self {
            Direction::In => "in",
            Direction::Out => "out",
        }
    }
}

type Registry = Mutex<BTreeMap<(Direction, &'static str), Arc<AtomicU64>>>;

fn registry() -> &'static Registry {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    REGISTRY.get_or_init(Registry::default)
}

/// The counter of `topic` in `direction` for this process (one per topic and direction);
/// starts the reporting thread on first use when [`ENV`] is set.
pub(crate) fn counter(direction: Direction, topic: &'static str) -> Arc<AtomicU64> {
    let (counter, new) = match registry().lock() {
        Ok(mut counters) => {
            let new = !counters.contains_key(&(direction, topic));
            (
                Arc::clone(counters.entry((direction, topic)).or_default()),
                new,
            )
        }
        // A panic while the map was held: count anyway, just unreported.
        Err(_) => (Arc::default(), false),
    };
    if reporting() && new {
        // A port is made known at once, not at the next period: a process frozen within
        // its first period would otherwise never tell what it reads, and the launcher would
        // not see the message waiting for it there.
        let _ = writeln!(std::io::stdout(), "{}", line());
    }
    counter
}

/// Whether this process reports its counts; starts the thread that does on first call.
fn reporting() -> bool {
    static STARTED: OnceLock<()> = OnceLock::new();
    if std::env::var_os(ENV).is_none() {
        return false;
    }
    STARTED.get_or_init(|| {
        // Without the thread the process still runs; the launcher only loses the counts.
        let _ = std::thread::Builder::new()
            .name("progress".into())
            .spawn(report);
    });
    true
}

/// Prints the counts whenever they change, until stdout is gone (the launcher died).
fn report() {
    let mut last = String::new();
    loop {
        let now = line();
        if now != last {
            // Not println!: it panics on a closed pipe.
            if writeln!(std::io::stdout(), "{now}").is_err() {
                return;
            }
            last = now;
        }
        std::thread::sleep(PERIOD);
    }
}

/// The current counts as one progress line.
pub fn line() -> String {
    let mut text = String::from(PREFIX);
    if let Ok(counters) = registry().lock() {
        for ((direction, topic), count) in counters.iter() {
            let count = count.load(Ordering::Relaxed);
            text.push_str(&format!(" {}:{topic}={count}", direction.word()));
        }
    }
    text
}

/// The counts of a progress line (without its first word): `(direction, topic, count)`;
/// words that are not counts are skipped.
pub fn parse(rest: &str) -> Vec<(Direction, String, u64)> {
    rest.split_whitespace()
        .filter_map(|word| {
            let (port, count) = word.split_once('=')?;
            let (direction, topic) = port.split_once(':')?;
            let direction = match direction {
                "in" => Direction::In,
                "out" => Direction::Out,
                _ => return None,
            };
            Some((direction, topic.to_owned(), count.parse().ok()?))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_printed_as_they_are_parsed() {
        counter(Direction::In, "lidar/scan").fetch_add(3, Ordering::Relaxed);
        counter(Direction::Out, "perception/features").fetch_add(2, Ordering::Relaxed);
        // The same topic and direction share one counter.
        counter(Direction::In, "lidar/scan").fetch_add(1, Ordering::Relaxed);
        let line = line();
        let rest = line.strip_prefix(PREFIX).unwrap();
        let counts = parse(rest);
        assert!(
            counts.contains(&(Direction::In, "lidar/scan".into(), 4)),
            "{line}"
        );
        assert!(
            counts.contains(&(Direction::Out, "perception/features".into(), 2)),
            "{line}"
        );
        assert!(parse(" junk in:x=notanumber sideways:x=1 out:y=5").len() == 1);
    }
}
