//! One client of the emulated sensor: answer its commands, stream scans while ranging.
//!
//! A reader thread turns the client's bytes into command lines; this thread answers them and
//! sends each scan when it is due, so a `QT` is answered between two scans as a sensor
//! would, never in the middle of one.

use std::io::{self, Write};
use std::net::{Shutdown, TcpStream};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use super::{SentScan, Shared, measure};
use crate::scip::{Command, Information, Ranging, Reply, Status, TimeMode, data_line, encode};
use crate::scip::{information_line, scan_body};
use crate::text_lines::LineReader;

/// Longest sleep between two looks at the stop flag.
const POLL: Duration = Duration::from_millis(20);

/// A running ranging command.
#[derive(Debug, Clone)]
struct Streaming {
    ranging: Ranging,
    /// `;tag` of the command, repeated in every echo.
    tag: Vec<u8>,
    /// Scans still to send; `None` = until `QT`.
    remaining: Option<u8>,
    /// When the next scan has been measured and goes out.
    due: Instant,
}

enum Sent {
    Scan,
    ConnectionDropped,
}

struct Session<'a> {
    stream: TcpStream,
    shared: &'a Shared,
    streaming: Option<Streaming>,
    adjusting: bool,
    laser: bool,
}

/// Serves one client until it leaves, the emulator stops or a fault drops the connection.
pub(super) fn serve(stream: TcpStream, shared: &Shared) -> io::Result<()> {
    let (sender, commands) = mpsc::channel();
    let incoming = stream.try_clone()?;
    let reader = std::thread::spawn(move || {
        let mut lines = LineReader::commands(incoming);
        while let Ok(line) = lines.read_line(Duration::MAX, &|| false) {
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    let mut session = Session {
        stream,
        shared,
        streaming: None,
        adjusting: false,
        laser: false,
    };
    let result = session.run(&commands);
    // Also ends the reader's blocking read.
    let _ = session.stream.shutdown(Shutdown::Both);
    let _ = reader.join();
    result
}

impl Session<'_> {
    fn run(&mut self, commands: &Receiver<Vec<u8>>) -> io::Result<()> {
        loop {
            if self.shared.stopping() {
                return Ok(());
            }
            let wait = self
                .streaming
                .as_ref()
                .map_or(POLL, |s| s.due.saturating_duration_since(Instant::now()))
                .min(POLL);
            match commands.recv_timeout(wait) {
                Ok(line) => self.answer(&line)?,
                Err(RecvTimeoutError::Timeout) => {}
                // The client closed its side.
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
            if self
                .streaming
                .as_ref()
                .is_some_and(|s| Instant::now() >= s.due)
                && let Sent::ConnectionDropped = self.send_scan()?
            {
                return Ok(());
            }
        }
    }

    fn answer(&mut self, line: &[u8]) -> io::Result<()> {
        self.shared.update(|state| {
            state
                .stats
                .commands
                .push(String::from_utf8_lossy(line).into())
        });
        let params = &self.shared.config.params;
        let ok = *b"00";
        let (status, body) = match Command::parse(line) {
            // What a sensor answers to a command it does not understand.
            Err(_) => (*b"0E", Vec::new()),
            Ok(Command::Version) => (ok, information(&self.version())),
            Ok(Command::Parameters) => (ok, information(&params.to_information())),
            Ok(Command::Status) => (ok, information(&self.status())),
            Ok(Command::Time(TimeMode::AdjustOn)) if self.adjusting => (*b"02", Vec::new()),
            Ok(Command::Time(TimeMode::AdjustOn)) => {
                self.adjusting = true;
                self.streaming = None;
                self.laser = false;
                (ok, Vec::new())
            }
            Ok(Command::Time(TimeMode::Request)) if !self.adjusting => (*b"04", Vec::new()),
            Ok(Command::Time(TimeMode::Request)) => {
                let counter = self.shared.clock.counter(Instant::now());
                let stamp = encode(counter, 4).map_err(invalid)?;
                (ok, vec![data_line(&stamp)])
            }
            Ok(Command::Time(TimeMode::AdjustOff)) if !self.adjusting => (*b"03", Vec::new()),
            Ok(Command::Time(TimeMode::AdjustOff)) => {
                self.adjusting = false;
                (ok, Vec::new())
            }
            Ok(Command::LaserOn) if self.laser => (*b"02", Vec::new()),
            Ok(Command::LaserOn) => {
                self.laser = true;
                (ok, Vec::new())
            }
            Ok(Command::Quit | Command::Reset) => {
                if line.starts_with(b"QT") {
                    self.shared.update(|state| state.stats.quits += 1);
                }
                self.streaming = None;
                self.laser = false;
                (ok, Vec::new())
            }
            // End step beyond the last step.
            Ok(Command::Ranging(ranging)) if u32::from(ranging.end) > params.amax => {
                (*b"04", Vec::new())
            }
            Ok(Command::Ranging(ranging)) => {
                let tag = line
                    .iter()
                    .position(|&b| b == b';')
                    .map(|at| line[at..].to_vec())
                    .unwrap_or_default();
                self.laser = true;
                self.streaming = Some(Streaming {
                    ranging,
                    tag,
                    remaining: (ranging.scans > 0).then_some(ranging.scans),
                    due: Instant::now() + self.period(&ranging),
                });
                (ok, Vec::new())
            }
        };
        let reply = Reply {
            echo: line.to_vec(),
            status: Status(status),
            body,
        };
        self.stream.write_all(&reply.to_bytes())?;
        self.stream.flush()
    }

    /// Time between two sent scans: one revolution, plus those skipped.
    fn period(&self, ranging: &Ranging) -> Duration {
        let revolution = Duration::from_secs_f64(self.shared.config.params.scan_time());
        revolution * (u32::from(ranging.interval) + 1)
    }

    fn send_scan(&mut self) -> io::Result<Sent> {
        let Some(streaming) = self.streaming.clone() else {
            return Ok(Sent::Scan);
        };
        let config = &self.shared.config;
        let revolution = Duration::from_secs_f64(config.params.scan_time());
        // The scan was measured during the revolution that ends now; the sensor stamps it
        // when it passes step 0, at the start.
        let measured = streaming
            .due
            .checked_sub(revolution)
            .unwrap_or(streaming.due);
        let (position, drop, corrupt) = {
            let mut state = self.shared.lock();
            let position = state.position;
            if !config.looping && position >= config.scans.len() as u64 {
                // The recording is over: the sensor goes quiet.
                state.exhausted = true;
                self.streaming = None;
                return Ok(Sent::Scan);
            }
            let drop = state.faults.drop.remove(&position);
            let corrupt = !drop && state.faults.corrupt.remove(&position);
            (position, drop, corrupt)
        };
        let row = (position % config.scans.len() as u64) as usize;
        let (ranges, intensities) = measure(&config.scans[row], &config.params, &streaming.ranging);
        let counter = self.shared.clock.counter(measured);
        let mut body =
            scan_body(streaming.ranging.kind, counter, &ranges, &intensities).map_err(invalid)?;
        if corrupt && let Some(sum) = body.get_mut(1).and_then(|line| line.last_mut()) {
            // Another valid character, so only the checksum comparison can tell.
            *sum = if *sum == b'o' { b'0' } else { *sum + 1 };
        }
        let remaining = streaming.remaining.map(|n| n.saturating_sub(1));
        let mut echo = streaming.ranging.echo(remaining.unwrap_or(0));
        echo.extend_from_slice(&streaming.tag);
        let bytes = Reply {
            echo,
            status: Status::SCAN,
            body,
        }
        .to_bytes();
        if drop {
            // Half a scan, then the cable is pulled.
            self.stream.write_all(&bytes[..bytes.len() / 2])?;
            self.stream.flush()?;
            self.shared
                .update(|state| state.stats.dropped_connections += 1);
            return Ok(Sent::ConnectionDropped);
        }
        self.stream.write_all(&bytes)?;
        self.stream.flush()?;
        let stamp_ns = self.shared.clock.host_ns_of_counter(measured);
        self.shared.update(|state| {
            state.position += 1;
            state.stats.sent.push(SentScan {
                position,
                row,
                counter_ms: counter,
                stamp_ns,
                corrupted: corrupt,
            });
        });
        let next = streaming.due + self.period(&streaming.ranging);
        // After a stall, start afresh rather than send a burst of late scans.
        let now = Instant::now();
        let due = if next + revolution < now {
            now + revolution
        } else {
            next
        };
        self.streaming = match remaining {
            Some(0) => None,
            _ => Some(Streaming {
                remaining,
                due,
                ..streaming
            }),
        };
        Ok(Sent::Scan)
    }

    fn version(&self) -> Information {
        let model = &self.shared.config.params.model;
        Information(vec![
            ("VEND".into(), "Hokuyo Automatic Co.,Ltd.".into()),
            ("PROD".into(), format!("SOKUIKI Sensor {model} (emulated)")),
            (
                "FIRM".into(),
                format!("hokuyo-emulator {}", env!("CARGO_PKG_VERSION")),
            ),
            ("PROT".into(), "SCIP 2.0".into()),
            ("SERI".into(), "EMU00001".into()),
        ])
    }

    fn status(&self) -> Information {
        let params = &self.shared.config.params;
        let counter = self.shared.clock.counter(Instant::now());
        let on_off = |on: bool| if on { "ON" } else { "OFF" };
        let measuring = if self.streaming.is_some() {
            "Measuring by Sensitive Mode"
        } else {
            "Idle"
        };
        Information(vec![
            ("MODL".into(), params.model.clone()),
            ("LASR".into(), on_off(self.laser).into()),
            ("SCSP".into(), format!("Initial({}[rpm])", params.scan_rpm)),
            ("MESM".into(), measuring.into()),
            ("SBPS".into(), "Ethernet 100 [Mbps]".into()),
            ("TIME".into(), format!("{counter:06X}")),
            ("STAT".into(), "Stable 000 no error.".into()),
        ])
    }
}

fn information(info: &Information) -> Vec<Vec<u8>> {
    info.0
        .iter()
        .map(|(name, value)| information_line(name, value))
        .collect()
}

fn invalid(e: crate::scip::ScipError) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, e)
}
