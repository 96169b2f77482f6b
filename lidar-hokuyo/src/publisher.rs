//! The driver loop: connect, identify, sync the clock, range, publish; on any loss log it,
//! wait (doubling back-off) and start over, keeping the sequence numbers running.
//!
//! What ends a connection:
//! * a damaged scan (bad checksum, bad character, wrong length) is dropped and counted, and
//!   the next scan is read: the reply was read to its end, so the stream is still in step.
//!   After `max_damaged_in_row` damaged scans in a row the connection is renewed.
//! * a closed or silent connection, a refused command or a sensor error status: reconnect.
//! * a peer that is no SCIP sensor (it talks, but never replies to the command; its lines
//!   are too long): named so in the log, and reconnect. Every exchange has its deadline
//!   whatever arrives meanwhile.
//! * a stop request: `QT`, wait for its confirmation (at most [`STOP_QUIT_WAIT`]), done.
//! * `frames` scans published: `QT`, done.
//!
//! Only what cannot get better by reconnecting ends the loop with an error: a window the
//! sensor cannot measure, or a transport that cannot publish.

use std::time::{Duration, Instant};

use ipc_types::{LaserScan, Outlet, PublishError};
use stage_kit::pacing::sleep_until;
use stage_kit::say_err;

use crate::backoff::Backoff;
use crate::connector::Connect;
use crate::decoded_scan::DecodedScan;
use crate::geometry::{GeometryError, RangingPlan, ScanRequest};
use crate::notices::ConnectionNotices;
use crate::ranges::ranges_m;
use crate::sensor::{Sensor, SensorError};

/// Longest wait for the confirmation of the `QT` sent on a stop: a UTM-30LX sends a scan
/// every 25 ms and confirms after the one under way, so this is several scans' time, and
/// short enough that a stop is done within a fraction of a second.
pub const STOP_QUIT_WAIT: Duration = Duration::from_millis(100);

/// How the driver runs.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverConfig {
    pub request: ScanRequest,
    /// Scans to publish before stopping; `None` = until stopped.
    pub frames: Option<u64>,
    /// `frame_id` of the scans.
    pub frame_id: String,
    /// Longest wait for a reply, and for the next scan while ranging.
    pub reply_timeout: Duration,
    /// First and longest wait between connection attempts.
    pub backoff_initial: Duration,
    pub backoff_max: Duration,
    /// `TM1` exchanges per clock synchronisation.
    pub time_samples: usize,
    /// Damaged scans in a row after which the connection is renewed.
    pub max_damaged_in_row: u32,
}

impl Default for DriverConfig {
    fn default() -> Self {
        Self {
            request: ScanRequest::default(),
            frames: None,
            frame_id: "laser".into(),
            reply_timeout: Duration::from_secs(2),
            backoff_initial: Duration::from_millis(100),
            backoff_max: Duration::from_secs(5),
            time_samples: 10,
            max_damaged_in_row: 3,
        }
    }
}

/// Where scans go.
pub trait ScanSink {
    fn publish(&mut self, decoded: &DecodedScan<'_>) -> Result<(), PublishError>;
}

impl ScanSink for Outlet<LaserScan> {
    fn publish(&mut self, decoded: &DecodedScan<'_>) -> Result<(), PublishError> {
        let mut filled = Ok(());
        Outlet::publish(self, |scan| filled = decoded.fill(scan))?;
        // The geometry never asks for more beams than a LaserScan holds; should it, the
        // message went out short and that is reported.
        filled.map_err(|source| PublishError::Failed {
            service: ipc_types::topic::SCAN.name().to_owned(),
            source: source.into(),
        })
    }
}

/// What the driver did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DriverStats {
    /// Scans published; also the next sequence number.
    pub published: u64,
    /// Damaged scans dropped.
    pub damaged: u64,
    /// Connections opened.
    pub connections: u64,
    /// Stamp of the last published scan.
    pub last_stamp_ns: u64,
}

/// Why the driver ended normally.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finish {
    /// `frames` scans were published.
    Frames,
    /// A stop was requested.
    Stopped,
}

/// Why the driver gave up.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    #[error(transparent)]
    Publish(#[from] PublishError),
}

/// How a connection ended, when it did not end the driver.
enum Lost {
    Sensor(SensorError),
    TooManyDamaged(u32),
}

impl Lost {
    /// The kind of loss, without its particulars: notices are repeated when it changes.
    fn reason(&self) -> String {
        match self {
            Self::Sensor(e) => {
                // The variant and the first word inside it: `Line Closed`, `NotScip command`.
                let debug = format!("{e:?}");
                let words: Vec<&str> = debug
                    .split(|c: char| !c.is_alphanumeric())
                    .filter(|word| !word.is_empty())
                    .take(2)
                    .collect();
                words.join(" ")
            }
            Self::TooManyDamaged(_) => "damaged".to_owned(),
        }
    }
}

impl std::fmt::Display for Lost {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Sensor(e @ SensorError::NotScip { .. }) => write!(f, "{e}"),
            Self::Sensor(e) if e.is_not_scip() => write!(f, "not a SCIP sensor: {e}"),
            Self::Sensor(e) => write!(f, "{e}"),
            Self::TooManyDamaged(n) => write!(f, "{n} damaged scans in a row"),
        }
    }
}

enum SessionEnd {
    Finished(Finish),
    Lost(Lost),
    Fatal(DriverError),
}

impl From<SensorError> for SessionEnd {
    fn from(e: SensorError) -> Self {
        if e.is_stop() {
            Self::Finished(Finish::Stopped)
        } else {
            Self::Lost(Lost::Sensor(e))
        }
    }
}

/// The driver: what it publishes to, how it connects, when it stops, what time it is.
pub struct Driver<'a, C, K, F> {
    pub config: &'a DriverConfig,
    pub connector: &'a mut C,
    pub sink: &'a mut K,
    /// True once the driver should stop (Ctrl-C).
    pub stop: F,
    /// The host clock the stamps are in, ns (CLOCK_REALTIME: [`ipc_types::now_ns`]).
    pub clock: &'a dyn Fn() -> u64,
    pub stats: DriverStats,
    /// Failed attempts, and what the console has been told about them.
    pub notices: ConnectionNotices,
}

impl<C, K, F> Driver<'_, C, K, F>
where
    C: Connect,
    K: ScanSink,
    F: Fn() -> bool + Clone + 'static,
{
    /// Runs until `frames` scans are published or a stop is requested; reconnects after
    /// every loss.
    pub fn run(&mut self) -> Result<Finish, DriverError> {
        let mut backoff = Backoff::new(self.config.backoff_initial, self.config.backoff_max);
        loop {
            if (self.stop)() {
                return Ok(Finish::Stopped);
            }
            let (lost, reason) = match self.connector.connect() {
                Ok(stream) => {
                    self.stats.connections += 1;
                    match self.session(stream, &mut backoff) {
                        SessionEnd::Finished(finish) => return Ok(finish),
                        SessionEnd::Fatal(e) => return Err(e),
                        // Named, so a wrong address (another service on the port) shows.
                        SessionEnd::Lost(lost) => (
                            format!("{}: {lost}", self.connector.describe()),
                            lost.reason(),
                        ),
                    }
                }
                Err(e) => (
                    format!("cannot connect to {}: {e}", self.connector.describe()),
                    format!("connect: {:?}", e.kind()),
                ),
            };
            let delay = backoff.next_delay();
            log(&format!("{lost}; reconnecting in {delay:?}"));
            if let Some(notice) = self.notices.failure(Instant::now(), &lost, &reason) {
                console(&notice);
            }
            // In slices, so that a stop does not wait out the back-off.
            if !sleep_until(Instant::now() + delay, &self.stop) {
                return Ok(Finish::Stopped);
            }
        }
    }

    fn session(&mut self, stream: C::Stream, backoff: &mut Backoff) -> SessionEnd {
        let mut sensor =
            Sensor::new(stream, self.config.reply_timeout).with_stop(self.stop.clone());
        let end = self.stream_scans(&mut sensor, backoff);
        match &end {
            SessionEnd::Finished(finish) => {
                // A stop must be quick: a sensor confirms QT within a scan or two, and one
                // that does not (or a peer that is no sensor) is not waited for longer.
                let wait = match finish {
                    Finish::Stopped => STOP_QUIT_WAIT.min(self.config.reply_timeout),
                    Finish::Frames => self.config.reply_timeout,
                };
                if let Err(e) = sensor.quit(wait) {
                    log(&format!("the sensor did not confirm QT: {e}"));
                }
            }
            SessionEnd::Fatal(_) => {
                if let Err(e) = sensor.quit(self.config.reply_timeout) {
                    log(&format!("the sensor did not confirm QT: {e}"));
                }
            }
            // The connection is probably gone; a QT is a courtesy to a sensor that is not.
            SessionEnd::Lost(_) => {
                let _ = sensor.send_quit();
            }
        }
        end
    }

    fn stream_scans(
        &mut self,
        sensor: &mut Sensor<C::Stream>,
        backoff: &mut Backoff,
    ) -> SessionEnd {
        let identity = match sensor.connect() {
            Ok(identity) => identity,
            Err(e) => return e.into(),
        };
        let p = &identity.params;
        let version = &identity.version;
        log(&format!(
            "connected to {} ({}, serial {}, firmware {}): steps {}..{} of {} (front {}), \
             {}..{} mm, {} rpm",
            self.connector.describe(),
            version.get("PROD").unwrap_or(&p.model),
            version.get("SERI").unwrap_or("?"),
            version.get("FIRM").unwrap_or("?"),
            p.amin,
            p.amax,
            p.ares,
            p.afrt,
            p.dmin_mm,
            p.dmax_mm,
            p.scan_rpm,
        ));
        let plan = match RangingPlan::new(p, &self.config.request) {
            Ok(plan) => plan,
            Err(e) => return SessionEnd::Fatal(e.into()),
        };
        let mut clock = match sensor.sync_clock(self.config.time_samples, self.clock) {
            Ok(clock) => clock,
            Err(e) => return e.into(),
        };
        log(&format!(
            "sensor clock synced (round trip {:.2} ms); ranging {} beams",
            clock.round_trip_ns() as f64 / 1e6,
            plan.beams
        ));
        if let Err(e) = sensor.start_ranging(plan.command) {
            return e.into();
        }
        // The sensor stamps a scan when it passes step 0; the first beam comes later.
        let first_beam_ns = (plan.first_beam_delay * 1e9).round() as u64;
        let mut damaged_in_row = 0;
        let mut ranges = Vec::with_capacity(plan.beams);
        let mut intensities = Vec::new();
        loop {
            if self
                .config
                .frames
                .is_some_and(|n| self.stats.published >= n)
            {
                return SessionEnd::Finished(Finish::Frames);
            }
            if (self.stop)() {
                return SessionEnd::Finished(Finish::Stopped);
            }
            let data = match sensor.next_scan() {
                Ok(data) => data,
                Err(e) if e.is_damaged_reply() => {
                    self.stats.damaged += 1;
                    damaged_in_row += 1;
                    log(&format!(
                        "dropped a damaged scan ({e}); {} so far",
                        self.stats.damaged
                    ));
                    if damaged_in_row >= self.config.max_damaged_in_row {
                        return SessionEnd::Lost(Lost::TooManyDamaged(damaged_in_row));
                    }
                    continue;
                }
                Err(e) => return e.into(),
            };
            damaged_in_row = 0;
            let stamp_ns = clock.host_ns(data.timestamp_ms) + first_beam_ns;
            ranges_m(&data.ranges, plan.dmin_mm, &mut ranges);
            intensities.clear();
            // Intensities are at most 18 bits: exact in f32.
            intensities.extend(data.intensities.iter().map(|&i| i as f32));
            let decoded = DecodedScan {
                seq: self.stats.published,
                stamp_ns,
                frame_id: &self.config.frame_id,
                plan: &plan,
                ranges: &ranges,
                intensities: &intensities,
            };
            match self.sink.publish(&decoded) {
                Ok(()) => {}
                Err(PublishError::Stopped(_)) => return SessionEnd::Finished(Finish::Stopped),
                Err(e) => return SessionEnd::Fatal(e.into()),
            }
            self.stats.published += 1;
            self.stats.last_stamp_ns = stamp_ns;
            if let Some(notice) = self.notices.success(&self.connector.describe()) {
                console(&notice);
            }
            // The sensor works: the next loss starts the back-off afresh.
            backoff.reset();
        }
    }
}

fn log(message: &str) {
    say_err(&format!("lidar-hokuyo: {message}"));
}

/// A line for the console: stdout, which slam-launch shows (its stderr goes to a log file).
fn console(message: &str) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    // A console that is gone is no reason to stop publishing scans.
    let _ = writeln!(stdout, "{message}").and_then(|()| stdout.flush());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scip::{Command, DataKind, Ranging};
    use crate::test_stream::{ScriptedStream, reply, scan_reply, utm_handshake};
    use std::collections::VecDeque;
    use std::io;

    /// Hands out scripted connections, then refuses.
    struct Scripted(VecDeque<Vec<u8>>);

    impl Connect for Scripted {
        type Stream = ScriptedStream;
        fn connect(&mut self) -> io::Result<ScriptedStream> {
            self.0
                .pop_front()
                .map(ScriptedStream::new)
                .ok_or_else(|| io::ErrorKind::ConnectionRefused.into())
        }
        fn describe(&self) -> String {
            "script".into()
        }
    }

    #[derive(Default)]
    struct Collect(Vec<(u64, u64, Vec<f32>)>);

    impl ScanSink for Collect {
        fn publish(&mut self, decoded: &DecodedScan<'_>) -> Result<(), PublishError> {
            self.0
                .push((decoded.seq, decoded.stamp_ns, decoded.ranges.to_vec()));
            Ok(())
        }
    }

    fn config(frames: u64) -> DriverConfig {
        DriverConfig {
            frames: Some(frames),
            backoff_initial: Duration::from_millis(1),
            backoff_max: Duration::from_millis(4),
            time_samples: 1,
            reply_timeout: Duration::from_millis(200),
            ..DriverConfig::default()
        }
    }

    /// A connection: handshake with the counter at `counter`, then scans of `mm`
    /// millimetres stamped 25 ms apart, then the end of the script.
    fn connection(counter: u32, scans: &[u32], tail: &[u8]) -> Vec<u8> {
        let ranging = Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap();
        let mut script = utm_handshake(&[counter]);
        script.extend(reply(&Command::Ranging(ranging).line(), b"00", &[]));
        for (i, &mm) in scans.iter().enumerate() {
            let stamp = counter + 25 * (i as u32 + 1);
            script.extend(scan_reply(&ranging, stamp, &vec![mm; 1081], &[]));
        }
        script.extend_from_slice(tail);
        script
    }

    fn run(
        config: &DriverConfig,
        connections: Vec<Vec<u8>>,
    ) -> (Result<Finish, DriverError>, DriverStats, Collect) {
        let mut connector = Scripted(connections.into());
        let mut sink = Collect::default();
        let clock = || 1_000_000_000_000u64;
        let mut driver = Driver {
            config,
            connector: &mut connector,
            sink: &mut sink,
            stop: || false,
            clock: &clock,
            stats: DriverStats::default(),
            notices: ConnectionNotices::default(),
        };
        let result = driver.run();
        let stats = driver.stats;
        (result, stats, sink)
    }

    #[test]
    fn sequence_numbers_run_on_across_reconnections() {
        let (result, stats, sink) = run(
            &config(5),
            vec![
                connection(100, &[1000, 2000, 3000], b""),
                connection(9000, &[4000, 5000, 6000], b""),
            ],
        );
        assert_eq!(result.unwrap(), Finish::Frames);
        assert_eq!(stats.connections, 2);
        assert_eq!(stats.published, 5);
        let seqs: Vec<u64> = sink.0.iter().map(|s| s.0).collect();
        assert_eq!(seqs, [0, 1, 2, 3, 4]);
        let firsts: Vec<f32> = sink.0.iter().map(|s| s.2[0]).collect();
        assert_eq!(firsts, [1.0, 2.0, 3.0, 4.0, 5.0]);
        // Stamps: the host clock reads 1000 s at every sample, so counter c maps to
        // 1000 s + (c - reference) ms.
        let stamps: Vec<u64> = sink.0.iter().map(|s| s.1).collect();
        assert_eq!(
            stamps,
            [
                1_000_025_000_000,
                1_000_050_000_000,
                1_000_075_000_000,
                1_000_025_000_000,
                1_000_050_000_000
            ]
        );
    }

    #[test]
    fn damaged_scans_are_dropped_and_counted() {
        let ranging = Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap();
        let mut bad = scan_reply(&ranging, 5, &[7000; 1081], &[]);
        let at = bad.len() - 4;
        bad[at] ^= 0x01;
        let mut tail = bad;
        tail.extend(scan_reply(&ranging, 200, &[8000; 1081], &[]));
        let (result, stats, sink) = run(&config(3), vec![connection(100, &[1000, 2000], &tail)]);
        assert_eq!(result.unwrap(), Finish::Frames);
        assert_eq!(stats.damaged, 1);
        assert_eq!(stats.connections, 1);
        let firsts: Vec<f32> = sink.0.iter().map(|s| s.2[0]).collect();
        assert_eq!(firsts, [1.0, 2.0, 8.0]);
    }

    #[test]
    fn a_run_of_damaged_scans_renews_the_connection() {
        let ranging = Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap();
        let mut tail = Vec::new();
        for _ in 0..3 {
            let mut bad = scan_reply(&ranging, 5, &[7000; 1081], &[]);
            let at = bad.len() / 2;
            bad[at] = b'~';
            tail.extend(bad);
        }
        let (result, stats, sink) = run(
            &config(2),
            vec![
                connection(100, &[1000], &tail),
                connection(100, &[2000], b""),
            ],
        );
        assert_eq!(result.unwrap(), Finish::Frames);
        assert_eq!((stats.damaged, stats.connections), (3, 2));
        assert_eq!(sink.0.len(), 2);
    }

    #[test]
    fn a_window_the_sensor_cannot_measure_is_fatal() {
        let mut config = config(1);
        config.request.min_angle = Some(-3.0);
        let (result, _, _) = run(&config, vec![connection(100, &[], b"")]);
        assert!(matches!(result, Err(DriverError::Geometry(_))));
    }

    #[test]
    fn a_stop_ends_the_wait_for_a_sensor() {
        let mut connector = Scripted(VecDeque::new());
        let mut sink = Collect::default();
        let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stopper = std::sync::Arc::clone(&flag);
        let timer = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(50));
            stopper.store(true, std::sync::atomic::Ordering::Relaxed);
        });
        let config = DriverConfig {
            backoff_initial: Duration::from_secs(10),
            backoff_max: Duration::from_secs(10),
            ..DriverConfig::default()
        };
        let started = Instant::now();
        let mut driver = Driver {
            config: &config,
            connector: &mut connector,
            sink: &mut sink,
            stop: move || flag.load(std::sync::atomic::Ordering::Relaxed),
            clock: &|| 0,
            stats: DriverStats::default(),
            notices: ConnectionNotices::default(),
        };
        assert_eq!(driver.run().unwrap(), Finish::Stopped);
        assert!(started.elapsed() < Duration::from_secs(5));
        timer.join().unwrap();
    }
}
