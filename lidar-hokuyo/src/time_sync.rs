//! The sensor's clock in host time.
//!
//! A Hokuyo stamps each scan with its own 24-bit millisecond counter, which starts at power-on
//! and wraps every 16 777.216 s (about 4 h 40 min). In time adjustment mode (`TM0`) the host
//! asks for the counter (`TM1`) a few times, noting its own clock before sending and after
//! receiving; the exchange with the shortest round trip bounds the offset best, and the
//! counter is taken to have been read halfway through it (NTP's assumption of a symmetric
//! link). A scan's stamp is then the host time of its counter value, the counter unwrapped
//! against the previous one so wrap-around is invisible.
//!
//! The offset is measured once per connection; a sensor clock that drifts from the host's
//! (tens of ppm) is corrected at the next reconnection only.

/// Bits of the sensor's counter.
pub const COUNTER_BITS: u32 = 24;
/// Values of the counter: it wraps after this many milliseconds.
pub const COUNTER_WRAP: i64 = 1 << COUNTER_BITS;
const NS_PER_MS: i128 = 1_000_000;

/// One `TM1` exchange.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClockSample {
    /// Host clock (ns) just before the request was sent.
    pub host_sent_ns: u64,
    /// Host clock (ns) just after the reply arrived.
    pub host_received_ns: u64,
    /// The sensor's counter in the reply (ms, 24 bits).
    pub sensor_ms: u32,
}

impl ClockSample {
    fn round_trip_ns(&self) -> u64 {
        self.host_received_ns.saturating_sub(self.host_sent_ns)
    }
}

/// Why no clock model could be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TimeSyncError {
    #[error("no time samples")]
    NoSamples,
    #[error("a time sample was received before it was sent ({0:?})")]
    Backwards(ClockSample),
    #[error("sensor time {0} does not fit in 24 bits")]
    CounterTooLarge(u32),
}

/// Maps the sensor's counter to host time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SensorClock {
    /// Host time (ns) at which the counter read `reference_ms`.
    reference_host_ns: i128,
    reference_ms: i64,
    /// The last counter value seen, unwrapped: the origin of the next unwrapping.
    last_ms: i64,
    round_trip_ns: u64,
}

impl SensorClock {
    /// The model of the sample with the shortest round trip.
    pub fn from_samples(samples: &[ClockSample]) -> Result<Self, TimeSyncError> {
        if let Some(bad) = samples.iter().find(|s| s.host_received_ns < s.host_sent_ns) {
            return Err(TimeSyncError::Backwards(*bad));
        }
        if let Some(bad) = samples
            .iter()
            .find(|s| i64::from(s.sensor_ms) >= COUNTER_WRAP)
        {
            return Err(TimeSyncError::CounterTooLarge(bad.sensor_ms));
        }
        let best = samples
            .iter()
            .min_by_key(|s| s.round_trip_ns())
            .ok_or(TimeSyncError::NoSamples)?;
        let midpoint = i128::from(best.host_sent_ns) + i128::from(best.round_trip_ns() / 2);
        Ok(Self {
            reference_host_ns: midpoint,
            reference_ms: i64::from(best.sensor_ms),
            last_ms: i64::from(best.sensor_ms),
            round_trip_ns: best.round_trip_ns(),
        })
    }

    /// Round trip of the exchange the model rests on: the offset is known to within half
    /// of it (plus the counter's millisecond).
    pub fn round_trip_ns(&self) -> u64 {
        self.round_trip_ns
    }

    /// Host time (ns) of the counter value `sensor_ms`, which must be within about 2.3 h
    /// (half the counter's period) of the previous value given; values may go backwards.
    pub fn host_ns(&mut self, sensor_ms: u32) -> u64 {
        let unwrapped = self.unwrap(sensor_ms);
        let ns = self.reference_host_ns + i128::from(unwrapped - self.reference_ms) * NS_PER_MS;
        u64::try_from(ns.max(0)).unwrap_or(u64::MAX)
    }

    /// The counter value as milliseconds since the reference's wrap, continuing across
    /// wraps: the step from the last value is taken modulo 2^24 into [-2^23, 2^23).
    fn unwrap(&mut self, sensor_ms: u32) -> i64 {
        let raw = i64::from(sensor_ms).rem_euclid(COUNTER_WRAP);
        let mut step = (raw - self.last_ms).rem_euclid(COUNTER_WRAP);
        if step >= COUNTER_WRAP / 2 {
            step -= COUNTER_WRAP;
        }
        self.last_ms += step;
        self.last_ms
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn sample(sent_ms: u64, received_ms: u64, sensor_ms: u32) -> ClockSample {
        ClockSample {
            host_sent_ns: 1_700_000_000_000 * MS + sent_ms * MS,
            host_received_ns: 1_700_000_000_000 * MS + received_ms * MS,
            sensor_ms,
        }
    }

    #[test]
    fn the_shortest_round_trip_wins_and_its_midpoint_is_the_reference() {
        // The sensor's counter reads 1000 when the host reads 100 ms (after its base).
        let mut clock = SensorClock::from_samples(&[
            sample(0, 40, 910),    // slow exchange
            sample(98, 102, 1000), // fast one: midpoint 100 ms
            sample(150, 170, 1060),
        ])
        .unwrap();
        assert_eq!(clock.round_trip_ns(), 4 * MS);
        let base = 1_700_000_000_000 * MS;
        assert_eq!(clock.host_ns(1000), base + 100 * MS);
        assert_eq!(clock.host_ns(1025), base + 125 * MS);
        // Earlier scans map to earlier times.
        assert_eq!(clock.host_ns(990), base + 90 * MS);
    }

    #[test]
    fn the_counter_wraps_forward_invisibly() {
        let top = (COUNTER_WRAP - 10) as u32;
        let mut clock = SensorClock::from_samples(&[sample(0, 0, top)]).unwrap();
        let base = 1_700_000_000_000 * MS;
        assert_eq!(clock.host_ns(top), base);
        assert_eq!(clock.host_ns(top + 9), base + 9 * MS);
        // 16 777 215 -> 0 -> 15: one millisecond, then 15 more.
        assert_eq!(clock.host_ns(0), base + 10 * MS);
        assert_eq!(clock.host_ns(15), base + 25 * MS);
        // And backwards across the wrap again.
        assert_eq!(clock.host_ns(top + 5), base + 5 * MS);
    }

    #[test]
    fn many_wraps_accumulate() {
        let mut clock = SensorClock::from_samples(&[sample(0, 0, 0)]).unwrap();
        let base = 1_700_000_000_000 * MS;
        let mut ms: u64 = 0;
        // Ten turns of the counter in steps of an hour.
        while ms < 10 * COUNTER_WRAP as u64 {
            ms += 3_600_000;
            let counter = (ms % COUNTER_WRAP as u64) as u32;
            assert_eq!(clock.host_ns(counter), base + ms * MS);
        }
    }

    #[test]
    fn bad_samples_are_refused() {
        assert_eq!(
            SensorClock::from_samples(&[]),
            Err(TimeSyncError::NoSamples)
        );
        assert!(matches!(
            SensorClock::from_samples(&[sample(10, 5, 0)]),
            Err(TimeSyncError::Backwards(_))
        ));
        assert!(matches!(
            SensorClock::from_samples(&[sample(0, 1, 1 << 24)]),
            Err(TimeSyncError::CounterTooLarge(_))
        ));
    }

    #[test]
    fn times_before_the_epoch_saturate() {
        let mut clock = SensorClock::from_samples(&[ClockSample {
            host_sent_ns: 0,
            host_received_ns: 0,
            sensor_ms: 5000,
        }])
        .unwrap();
        assert_eq!(clock.host_ns(4000), 0);
    }
}
