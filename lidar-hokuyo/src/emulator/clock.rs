//! The emulated sensor's 24-bit millisecond counter, and which host time each value means.

use std::time::Instant;

use crate::time_sync::COUNTER_WRAP;

/// A counter that started at `start_ms` when the emulator started.
#[derive(Debug, Clone)]
pub struct EmulatedClock {
    epoch: Instant,
    epoch_host_ns: u64,
    start_ms: u32,
}

impl EmulatedClock {
    /// A counter reading `start_ms` (taken modulo 2^24) now.
    pub fn new(start_ms: u32) -> Self {
        Self {
            epoch: Instant::now(),
            epoch_host_ns: ipc_types::now_ns(),
            start_ms: (i64::from(start_ms) % COUNTER_WRAP) as u32,
        }
    }

    /// Milliseconds elapsed at `at`, counted from the counter's start.
    fn elapsed_ms(&self, at: Instant) -> u64 {
        u64::try_from(at.saturating_duration_since(self.epoch).as_millis()).unwrap_or(u64::MAX)
    }

    /// The counter at `at`.
    pub fn counter(&self, at: Instant) -> u32 {
        let ms = u64::from(self.start_ms) + self.elapsed_ms(at);
        // The modulo keeps it below 2^24.
        (ms % COUNTER_WRAP as u64) as u32
    }

    /// The host time (CLOCK_REALTIME, ns) at which the counter took the value it has at
    /// `at`: what a perfect driver would stamp.
    pub fn host_ns_of_counter(&self, at: Instant) -> u64 {
        self.epoch_host_ns + self.elapsed_ms(at) * 1_000_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn counts_milliseconds_and_wraps() {
        let clock = EmulatedClock::new((COUNTER_WRAP - 5) as u32);
        let epoch = clock.epoch;
        assert_eq!(clock.counter(epoch), (COUNTER_WRAP - 5) as u32);
        assert_eq!(
            clock.counter(epoch + Duration::from_micros(4900)),
            (COUNTER_WRAP - 1) as u32
        );
        assert_eq!(clock.counter(epoch + Duration::from_millis(5)), 0);
        assert_eq!(clock.counter(epoch + Duration::from_millis(1005)), 1000);
        assert_eq!(
            clock.host_ns_of_counter(epoch + Duration::from_micros(1500)),
            clock.epoch_host_ns + 1_000_000
        );
    }
}
