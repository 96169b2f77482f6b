//! A SCIP 2.0 client over any byte stream: a TCP socket for a real sensor, an in-memory
//! stream in tests.
//!
//! The stream's reads should time out now and then (a socket read timeout of ~100 ms) so the
//! client notices a stop request and a sensor that went silent; a stream that blocks for
//! ever blocks the client for ever.

use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

use crate::scip::{
    Command, Information, Ranging, Reply, ScanData, ScipError, SensorParams, Status, TimeMode,
};
use crate::text_lines::{LineError, LineReader};
use crate::time_sync::{ClockSample, SensorClock, TimeSyncError};

/// Lines a reply may have: a full scan of 8192 beams with intensities is 768 data lines.
const MAX_REPLY_LINES: usize = 1024;
/// `TM0` when already in adjustment mode, `BM` when the laser is already on.
const ALREADY: Status = Status(*b"02");
/// `TM2` when adjustment mode is already off.
const ALREADY_OFF: Status = Status(*b"03");
/// Bytes of a stray reply quoted in [`SensorError::NotScip`].
const LAST_OTHER_BYTES: usize = 40;

/// Why the sensor could not be talked to.
#[derive(Debug, thiserror::Error)]
pub enum SensorError {
    #[error("cannot send to the sensor: {0}")]
    Write(io::Error),
    #[error(transparent)]
    Line(#[from] LineError),
    #[error("damaged reply: {0}")]
    Protocol(#[from] ScipError),
    #[error("the sensor answered {command} with status {status}")]
    Refused { command: String, status: Status },
    #[error("no reply to {command} within {timeout:?}")]
    NoReply { command: String, timeout: Duration },
    /// Bytes came, but no reply to the command: whatever the peer is, it is no SCIP sensor.
    #[error(
        "not a SCIP sensor: no reply to {command} within {timeout:?}, only {others} replies \
         to something else (the last began {last:?})"
    )]
    NotScip {
        command: String,
        timeout: Duration,
        /// Replies (or empty lines) that were not the awaited one.
        others: usize,
        /// The start of the last of them.
        last: String,
    },
    #[error("no ranging command is running")]
    NotRanging,
    #[error("cannot relate the sensor's clock to ours: {0}")]
    TimeSync(#[from] TimeSyncError),
}

impl SensorError {
    /// True when a stop was requested while waiting.
    pub fn is_stop(&self) -> bool {
        matches!(self, Self::Line(LineError::Stopped))
    }

    /// True when the peer does not speak SCIP: it sent what no sensor sends (no reply to a
    /// command, only other lines, or lines longer than any SCIP line).
    pub fn is_not_scip(&self) -> bool {
        matches!(self, Self::NotScip { .. } | Self::Line(LineError::TooLong))
    }

    /// True for a reply that arrived whole but damaged (bad checksum, bad character, wrong
    /// length): the stream is still in step, and the next reply can be read.
    pub fn is_damaged_reply(&self) -> bool {
        matches!(self, Self::Protocol(_))
    }
}

/// What the sensor says about itself when connected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// `VV`: vendor, product, firmware, protocol, serial number.
    pub version: Information,
    /// `PP`: geometry and timing.
    pub params: SensorParams,
    /// `II`: state of the laser, motor and measurement.
    pub status: Information,
}

/// A connected sensor.
pub struct Sensor<S> {
    reader: LineReader<S>,
    reply_timeout: Duration,
    stop: Box<dyn Fn() -> bool>,
    ranging: Option<Ranging>,
}

impl<S> std::fmt::Debug for Sensor<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sensor")
            .field("reply_timeout", &self.reply_timeout)
            .field("ranging", &self.ranging)
            .finish_non_exhaustive()
    }
}

impl<S: Read + Write> Sensor<S> {
    /// A client on `stream`; each reply (and each scan while ranging) must come within
    /// `reply_timeout`.
    pub fn new(stream: S, reply_timeout: Duration) -> Self {
        Self {
            reader: LineReader::replies(stream),
            reply_timeout,
            stop: Box::new(|| false),
            ranging: None,
        }
    }

    /// Makes every wait end with a stop error once `stop` returns true.
    pub fn with_stop(mut self, stop: impl Fn() -> bool + 'static) -> Self {
        self.stop = Box::new(stop);
        self
    }

    /// The stream.
    pub fn get_ref(&self) -> &S {
        self.reader.get_ref()
    }

    /// The stream; unread bytes are lost.
    pub fn into_inner(self) -> S {
        self.reader.into_inner()
    }

    /// Stops whatever the sensor was doing (a ranging command left running by an earlier
    /// client, a time adjustment) and reads its version, parameters and state.
    pub fn connect(&mut self) -> Result<Identity, SensorError> {
        if let Err(e) = self.request(Command::Quit, &[Status::OK]) {
            if !matches!(e, SensorError::Refused { .. }) {
                return Err(e);
            }
            // Refused: most likely left in time adjustment mode, which accepts nothing else.
            self.request(
                Command::Time(TimeMode::AdjustOff),
                &[Status::OK, ALREADY_OFF],
            )?;
            self.request(Command::Quit, &[Status::OK])?;
        }
        self.ranging = None;
        // VV and II are only shown to the user: a line of them that does not parse is no
        // reason to refuse a sensor whose PP does.
        let version = self
            .request(Command::Version, &[Status::OK])?
            .information()
            .unwrap_or_default();
        let params = SensorParams::from_information(
            &self
                .request(Command::Parameters, &[Status::OK])?
                .information()?,
        )?;
        let status = self
            .request(Command::Status, &[Status::OK])?
            .information()
            .unwrap_or_default();
        Ok(Identity {
            version,
            params,
            status,
        })
    }

    /// Relates the sensor's clock to the host's `clock` (ns) with `samples` `TM1`
    /// exchanges in time adjustment mode (which turns the laser off while it lasts).
    pub fn sync_clock(
        &mut self,
        samples: usize,
        clock: &dyn Fn() -> u64,
    ) -> Result<SensorClock, SensorError> {
        self.ranging = None;
        self.request(Command::Time(TimeMode::AdjustOn), &[Status::OK, ALREADY])?;
        let taken = self.time_samples(samples, clock);
        // Leave adjustment mode even when a sample failed: the sensor accepts nothing else
        // while in it.
        let off = self.request(
            Command::Time(TimeMode::AdjustOff),
            &[Status::OK, ALREADY_OFF],
        );
        let clock = SensorClock::from_samples(&taken?)?;
        off?;
        Ok(clock)
    }

    fn time_samples(
        &mut self,
        samples: usize,
        clock: &dyn Fn() -> u64,
    ) -> Result<Vec<ClockSample>, SensorError> {
        (0..samples)
            .map(|_| {
                let host_sent_ns = clock();
                let reply = self.request(Command::Time(TimeMode::Request), &[Status::OK])?;
                let host_received_ns = clock();
                Ok(ClockSample {
                    host_sent_ns,
                    host_received_ns,
                    sensor_ms: reply.time()?,
                })
            })
            .collect()
    }

    /// Starts continuous ranging; read the scans with [`Sensor::next_scan`].
    pub fn start_ranging(&mut self, ranging: Ranging) -> Result<(), SensorError> {
        self.request(Command::Ranging(ranging), &[Status::OK])?;
        self.ranging = Some(ranging);
        Ok(())
    }

    /// The next scan of the running ranging command.
    ///
    /// A damaged scan ([`SensorError::is_damaged_reply`]) has been read to its end, so the
    /// next call reads the next scan.
    pub fn next_scan(&mut self) -> Result<ScanData, SensorError> {
        let ranging = self.ranging.ok_or(SensorError::NotRanging)?;
        let lines = loop {
            let lines = read_reply_lines(&mut self.reader, self.reply_timeout, &*self.stop)?;
            // A lone empty line carries nothing; skip it rather than call it a damaged scan.
            if !lines.is_empty() {
                break lines;
            }
        };
        let reply = Reply::parse(lines)?;
        let prefix = ranging.echo_prefix();
        // The echo carries the remaining scan count (2 digits) and the tag, if any.
        let own = reply.echo.starts_with(&prefix)
            && reply
                .echo
                .get(prefix.len()..prefix.len() + 2)
                .is_some_and(|count| count.iter().all(u8::is_ascii_digit));
        if !own {
            return Err(ScipError::malformed("scan echo", &reply.echo).into());
        }
        if reply.status != Status::SCAN {
            return Err(SensorError::Refused {
                command: String::from_utf8_lossy(&reply.echo).into_owned(),
                status: reply.status,
            });
        }
        Ok(reply.scan(ranging.kind, ranging.beams())?)
    }

    /// Stops ranging (`QT`) and waits at most `wait` for the sensor to confirm, reading away
    /// the scans still on their way. Ignores stop requests: this is what a stop does; the
    /// caller bounds it with `wait` instead.
    pub fn quit(&mut self, wait: Duration) -> Result<(), SensorError> {
        self.ranging = None;
        let reply_timeout = std::mem::replace(&mut self.reply_timeout, wait);
        let result = self.exchange(Command::Quit, &[Status::OK], &|| false);
        self.reply_timeout = reply_timeout;
        result.map(drop)
    }

    /// Sends `QT` without waiting for the reply: for a connection about to be dropped.
    pub fn send_quit(&mut self) -> Result<(), SensorError> {
        self.ranging = None;
        self.send(&Command::Quit)
    }

    fn send(&mut self, command: &Command) -> Result<(), SensorError> {
        let stream = self.reader.get_mut();
        stream
            .write_all(&command.to_bytes())
            .and_then(|()| stream.flush())
            .map_err(SensorError::Write)
    }

    fn request(&mut self, command: Command, accept: &[Status]) -> Result<Reply, SensorError> {
        // The box is moved out for the call so `self` can be borrowed mutably.
        let stop = std::mem::replace(&mut self.stop, Box::new(|| false));
        let result = self.exchange(command, accept, &*stop);
        self.stop = stop;
        result
    }

    /// Sends `command` and returns its reply, skipping replies to anything else (scans of
    /// a ranging command still running, late replies of an earlier client).
    fn exchange(
        &mut self,
        command: Command,
        accept: &[Status],
        stop: &dyn Fn() -> bool,
    ) -> Result<Reply, SensorError> {
        self.send(&command)?;
        let echo = command.line();
        let name = String::from_utf8_lossy(&echo).into_owned();
        let timeout = self.reply_timeout;
        let deadline = Instant::now() + timeout;
        let received_before = self.reader.bytes_received();
        // Replies to something else, and the first line of the last one, to tell a peer that
        // does not speak SCIP from a silent one.
        let mut others = 0usize;
        let mut last_other = Vec::new();
        // Bytes came and our reply did not: the peer talks, but not SCIP.
        let no_reply = |reader: &LineReader<S>, others: usize, last_other: &[u8]| {
            if reader.bytes_received() == received_before {
                SensorError::NoReply {
                    command: name.clone(),
                    timeout,
                }
            } else {
                SensorError::NotScip {
                    command: name.clone(),
                    timeout,
                    others,
                    last: String::from_utf8_lossy(last_other).into_owned(),
                }
            }
        };
        loop {
            // The deadline holds whatever arrives: replies to other commands (or empty ones)
            // that come faster than it would otherwise be looked at included.
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(no_reply(&self.reader, others, &last_other));
            }
            let lines = match read_reply_lines(&mut self.reader, left, stop) {
                Ok(lines) => lines,
                Err(SensorError::Line(LineError::TimedOut(_))) => {
                    return Err(no_reply(&self.reader, others, &last_other));
                }
                Err(e) => return Err(e),
            };
            if lines.first() != Some(&echo) {
                others += 1;
                last_other = lines.first().cloned().unwrap_or_default();
                last_other.truncate(LAST_OTHER_BYTES);
                continue;
            }
            let reply = Reply::parse(lines)?;
            if !accept.contains(&reply.status) {
                return Err(SensorError::Refused {
                    command: name,
                    status: reply.status,
                });
            }
            return Ok(reply);
        }
    }
}

/// The lines of one reply, up to the empty line that ends it.
fn read_reply_lines<S: Read>(
    reader: &mut LineReader<S>,
    timeout: Duration,
    stop: &dyn Fn() -> bool,
) -> Result<Vec<Vec<u8>>, SensorError> {
    let deadline = Instant::now() + timeout;
    let mut lines = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let line = reader.read_line(left, stop)?;
        if line.is_empty() {
            return Ok(lines);
        }
        if lines.len() >= MAX_REPLY_LINES {
            return Err(ScipError::Malformed {
                what: "reply (too many lines)",
                text: String::new(),
            }
            .into());
        }
        lines.push(line);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scip::{DataKind, data_line, information_line, scan_body};
    use crate::test_stream::{ScriptedStream, reply, scan_reply, utm_handshake};

    const SECOND: Duration = Duration::from_secs(1);

    fn utm_ranging() -> Ranging {
        Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap()
    }

    #[test]
    fn connects_syncs_and_reads_scans() {
        let ranging = utm_ranging();
        let mut script = utm_handshake(&[5000, 5001, 5002]);
        script.extend(reply(&Command::Ranging(ranging).line(), b"00", &[]));
        let ranges: Vec<u32> = (0..1081).map(|i| 1000 + i).collect();
        script.extend(scan_reply(&ranging, 5010, &ranges, &[]));
        let mut sensor = Sensor::new(ScriptedStream::new(script), SECOND);
        let identity = sensor.connect().unwrap();
        assert_eq!(identity.params, SensorParams::utm_30lx());
        assert_eq!(identity.version.get("PROT"), Some("SCIP 2.0"));
        assert_eq!(identity.status.get("LASR"), Some("OFF"));
        // A host clock that advances 2 ms per reading: the samples' midpoints are 1 ms
        // after their sending.
        let now = std::cell::Cell::new(1_000_000_000u64);
        let clock = || {
            now.set(now.get() + 2_000_000);
            now.get()
        };
        let mut sensor_clock = sensor.sync_clock(3, &clock).unwrap();
        assert_eq!(sensor_clock.round_trip_ns(), 2_000_000);
        // The first sample: sent at 1002 ms, received at 1004 ms, counter 5000.
        assert_eq!(sensor_clock.host_ns(5000), 1_003_000_000);
        sensor.start_ranging(ranging).unwrap();
        let scan = sensor.next_scan().unwrap();
        assert_eq!(scan.timestamp_ms, 5010);
        assert_eq!(scan.ranges, ranges);
        assert_eq!(
            sensor.get_ref().written(),
            b"QT\nVV\nPP\nII\nTM0\nTM1\nTM1\nTM1\nTM2\nMD0000108001000\n"
        );
    }

    #[test]
    fn a_damaged_scan_is_skipped_whole() {
        let ranging = utm_ranging();
        let mut script = reply(&Command::Ranging(ranging).line(), b"00", &[]);
        let good: Vec<u32> = vec![2000; 1081];
        let mut bad = scan_reply(&ranging, 1, &good, &[]);
        // Corrupt a data character in the middle of the scan: its line's checksum fails.
        let at = bad.len() / 2;
        bad[at] = if bad[at] == b'0' { b'1' } else { b'0' };
        script.extend(bad);
        script.extend(scan_reply(&ranging, 2, &good, &[]));
        let mut sensor = Sensor::new(ScriptedStream::new(script), SECOND);
        sensor.start_ranging(ranging).unwrap();
        let error = sensor.next_scan().unwrap_err();
        assert!(error.is_damaged_reply(), "{error}");
        assert_eq!(sensor.next_scan().unwrap().timestamp_ms, 2);
        assert!(matches!(
            sensor.next_scan(),
            Err(SensorError::Line(LineError::Closed))
        ));
    }

    #[test]
    fn stale_replies_before_the_answer_are_skipped() {
        // A ranging command of an earlier client still sends scans when QT goes out.
        let ranging = utm_ranging();
        let mut script = scan_reply(&ranging, 1, &[3000; 1081], &[]);
        script.extend(b"MD00001080".to_vec()); // the tail of a scan cut off mid-line
        script.extend(b"\n\n".to_vec());
        script.extend(reply(b"QT", b"00", &[]));
        script.extend(reply(
            b"VV",
            b"00",
            &[information_line("PROD", "SOKUIKI Sensor UTM-30LX")],
        ));
        let mut sensor = Sensor::new(ScriptedStream::new(script), SECOND);
        sensor.quit(SECOND).unwrap();
        let version = sensor
            .request(Command::Version, &[Status::OK])
            .unwrap()
            .information()
            .unwrap();
        assert_eq!(version.get("PROD"), Some("SOKUIKI Sensor UTM-30LX"));
    }

    #[test]
    fn a_sensor_left_in_adjustment_mode_is_brought_back() {
        let mut script = reply(b"QT", b"0L", &[]);
        script.extend(reply(b"TM2", b"00", &[]));
        script.extend(reply(b"QT", b"00", &[]));
        script.extend(utm_handshake(&[]).split_off(reply(b"QT", b"00", &[]).len()));
        let mut sensor = Sensor::new(ScriptedStream::new(script), SECOND);
        sensor.connect().unwrap();
        assert!(sensor.get_ref().written().starts_with(b"QT\nTM2\nQT\nVV\n"));
    }

    #[test]
    fn refusals_and_silence_are_errors() {
        let mut sensor = Sensor::new(ScriptedStream::new(reply(b"PP", b"0E", &[])), SECOND);
        assert!(matches!(
            sensor.request(Command::Parameters, &[Status::OK]),
            Err(SensorError::Refused { .. })
        ));
        // Nothing more to read: the in-memory stream reports a closed connection.
        assert!(matches!(
            sensor.request(Command::Version, &[Status::OK]),
            Err(SensorError::Line(LineError::Closed))
        ));
        let mut silent = Sensor::new(ScriptedStream::silent(), Duration::from_millis(20));
        assert!(matches!(
            silent.request(Command::Version, &[Status::OK]),
            Err(SensorError::NoReply { .. })
        ));
        let mut stopped = Sensor::new(ScriptedStream::silent(), SECOND).with_stop(|| true);
        assert!(
            stopped
                .request(Command::Version, &[Status::OK])
                .unwrap_err()
                .is_stop()
        );
        assert!(matches!(
            Sensor::new(ScriptedStream::silent(), SECOND).next_scan(),
            Err(SensorError::NotRanging)
        ));
    }

    #[test]
    fn scans_of_another_command_or_status_are_refused() {
        let ranging = utm_ranging();
        let other = Ranging::new(DataKind::Ranges3, 0, 100, 1, 0, 0).unwrap();
        let mut script = reply(&Command::Ranging(ranging).line(), b"00", &[]);
        script.extend(scan_reply(&other, 1, &[1000; 101], &[]));
        let body = scan_body(DataKind::Ranges3, 1, &[1000; 1081], &[]).unwrap();
        script.extend(reply(&ranging.echo(0), b"50", &body));
        let mut sensor = Sensor::new(ScriptedStream::new(script), SECOND);
        sensor.start_ranging(ranging).unwrap();
        assert!(sensor.next_scan().unwrap_err().is_damaged_reply());
        assert!(matches!(
            sensor.next_scan(),
            Err(SensorError::Refused { .. })
        ));
    }

    #[test]
    fn a_time_sample_that_fails_still_leaves_adjustment_mode() {
        let mut script = reply(b"TM0", b"00", &[]);
        script.extend(reply(b"TM1", b"00", &[data_line(b"m2@")]));
        script.extend(reply(b"TM2", b"00", &[]));
        let mut sensor = Sensor::new(ScriptedStream::new(script), SECOND);
        assert!(sensor.sync_clock(1, &|| 0).unwrap_err().is_damaged_reply());
        assert_eq!(sensor.get_ref().written(), b"TM0\nTM1\nTM2\n");
    }

    /// The client reading a whole handshake off a wire of noise.
    mod on_noise {
        use proptest::collection::vec;
        use proptest::prelude::*;

        use super::*;

        proptest! {
                #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn the_client_on_a_wire_of_arbitrary_bytes_fails_with_a_typed_error(
            input in vec(any::<u8>(), 0..4096),
        ) {
            let mut sensor = Sensor::new(ScriptedStream::new(input), Duration::from_millis(20));
            let result = sensor.connect();
            // No sensor's handshake hides in noise of this length: it must be refused, for a
            // reason the driver can act on.
            match result {
                Ok(identity) => prop_assert!(false, "took noise for a sensor: {:?}", identity),
                Err(e) => {
                    let actionable = matches!(
                        e,
                        SensorError::Line(_)
                            | SensorError::Protocol(_)
                            | SensorError::Refused { .. }
                            | SensorError::NoReply { .. }
                            | SensorError::NotScip { .. }
                    );
                    prop_assert!(actionable, "{}", e);
                }
            }
            // It said little: QT, and at most a TM2 and a QT more to leave time adjustment.
            prop_assert!(sensor.get_ref().written().len() <= b"QT\nTM2\nQT\n".len());
        }
            }
    }
}
