//! A Hokuyo that is not there: a TCP server speaking SCIP 2.0 that serves recorded scans at
//! the sensor's own rate, for tests and for trying the pipeline without hardware.
//!
//! It answers `VV`, `PP`, `II`, `TM0/1/2`, `BM`, `QT`, `RS`, `MD`, `MS` and `ME`, has its
//! own 24-bit millisecond clock (its start value is configurable, to see it wrap), serves
//! one client at a time like the real sensor, and can break on purpose: a scan with a wrong
//! checksum, or a connection dropped in the middle of a scan.
//!
//! Scans are served in the recording's order across connections: the `n`-th scan
//! completely sent is recording line `n` (modulo its length when looping). A scan cut off by
//! a dropped connection is sent again to the next client; a corrupted one is not (a real
//! sensor would not resend it either). Without looping, the sensor goes quiet after the last
//! scan, and the emulator ends when that client leaves.

mod clock;
mod measure;
mod scan_file;
mod session;

use std::collections::BTreeSet;
use std::net::{SocketAddr, TcpListener, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

pub use clock::EmulatedClock;
pub use measure::{intensity_of, measure};
pub use scan_file::{ScanFileError, load_scans, parse_scans};

use crate::scip::SensorParams;

/// Faults to inject, by the position of a scan in the served stream (0 = the first scan
/// sent). Each fires once.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Faults {
    /// Scans sent with a wrong checksum on their first data line.
    pub corrupt: BTreeSet<u64>,
    /// Scans cut off halfway, the connection then closed.
    pub drop: BTreeSet<u64>,
}

/// What the emulator serves.
#[derive(Debug, Clone)]
pub struct EmulatorConfig {
    /// What `PP` reports; the scans must have one value per step `AMIN..=AMAX`.
    pub params: SensorParams,
    /// Recorded scans in millimetres, error codes included.
    pub scans: Arc<Vec<Vec<u32>>>,
    /// Start over at the end of the recording instead of going quiet.
    pub looping: bool,
    pub faults: Faults,
    /// The sensor's counter at start, ms (modulo 2^24).
    pub clock_start_ms: u32,
}

impl EmulatorConfig {
    /// A UTM-30LX serving `scans` once, without faults, its clock starting at 0.
    pub fn utm_30lx(scans: Vec<Vec<u32>>) -> Self {
        Self {
            params: SensorParams::utm_30lx(),
            scans: Arc::new(scans),
            looping: false,
            faults: Faults::default(),
            clock_start_ms: 0,
        }
    }
}

/// A scan the emulator sent whole.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SentScan {
    /// Its position in the served stream.
    pub position: u64,
    /// Its line in the recording (0-based).
    pub row: usize,
    /// Its time stamp on the sensor's counter.
    pub counter_ms: u32,
    /// The host time (CLOCK_REALTIME, ns) of that counter value: the ideal stamp.
    pub stamp_ns: u64,
    /// Sent with a wrong checksum.
    pub corrupted: bool,
}

/// What the emulator did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EmulatorStats {
    /// Clients accepted.
    pub connections: u64,
    /// Every command line received, in order.
    pub commands: Vec<String>,
    /// Every scan sent whole, in order.
    pub sent: Vec<SentScan>,
    /// Connections dropped on purpose.
    pub dropped_connections: u64,
    /// `QT` commands received.
    pub quits: u64,
}

/// Why the emulator cannot start.
#[derive(Debug, thiserror::Error)]
pub enum EmulatorError {
    #[error("cannot listen on {addr}: {source}")]
    Listen {
        addr: String,
        source: std::io::Error,
    },
    #[error("no scans to serve")]
    NoScans,
    #[error("scan {row} has {len} values, but steps {amin}..={amax} need {expected}")]
    ScanWidth {
        row: usize,
        len: usize,
        amin: u32,
        amax: u32,
        expected: usize,
    },
}

/// A running emulator; stops when dropped.
#[derive(Debug)]
pub struct Emulator {
    addr: SocketAddr,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

#[derive(Debug)]
struct Shared {
    config: EmulatorConfig,
    clock: EmulatedClock,
    stop: AtomicBool,
    state: Mutex<State>,
}

#[derive(Debug, Default)]
struct State {
    /// Scans sent whole so far: the position of the next one.
    position: u64,
    faults: Faults,
    stats: EmulatorStats,
    /// The recording is over (without looping).
    exhausted: bool,
    /// The last client has left after the recording was over.
    finished: bool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere cannot leave the counters inconsistent enough to matter.
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn update(&self, change: impl FnOnce(&mut State)) {
        change(&mut self.lock());
    }

    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

impl Emulator {
    /// Starts serving on `addr` (e.g. `127.0.0.1:0` for any free port).
    pub fn start(config: EmulatorConfig, addr: impl ToSocketAddrs) -> Result<Self, EmulatorError> {
        let expected = (config.params.amax - config.params.amin) as usize + 1;
        if config.scans.is_empty() {
            return Err(EmulatorError::NoScans);
        }
        if let Some((row, scan)) = config
            .scans
            .iter()
            .enumerate()
            .find(|(_, scan)| scan.len() != expected)
        {
            return Err(EmulatorError::ScanWidth {
                row,
                len: scan.len(),
                amin: config.params.amin,
                amax: config.params.amax,
                expected,
            });
        }
        let listen_error = |source| EmulatorError::Listen {
            addr: addr_text(&addr),
            source,
        };
        let listener = TcpListener::bind(&addr).map_err(listen_error)?;
        let local = listener.local_addr().map_err(listen_error)?;
        // Accept polls, so the stop flag is seen between clients.
        listener.set_nonblocking(true).map_err(listen_error)?;
        let shared = Arc::new(Shared {
            clock: EmulatedClock::new(config.clock_start_ms),
            state: Mutex::new(State {
                faults: config.faults.clone(),
                ..State::default()
            }),
            config,
            stop: AtomicBool::new(false),
        });
        let serving = Arc::clone(&shared);
        let thread = std::thread::spawn(move || accept_clients(&listener, &serving));
        Ok(Self {
            addr: local,
            shared,
            thread: Some(thread),
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// What it has done so far.
    pub fn stats(&self) -> EmulatorStats {
        self.shared.lock().stats.clone()
    }

    /// True once the recording is over and its last client has left (never when looping).
    pub fn is_finished(&self) -> bool {
        self.shared.lock().finished
    }

    /// Stops serving and waits for the server thread.
    pub fn stop(mut self) -> EmulatorStats {
        self.shut_down();
        self.stats()
    }

    fn shut_down(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        self.shut_down();
    }
}

fn accept_clients(listener: &TcpListener, shared: &Shared) {
    while !shared.stopping() {
        match listener.accept() {
            Ok((stream, peer)) => {
                shared.update(|state| state.stats.connections += 1);
                let served = stream
                    .set_nonblocking(false)
                    .and_then(|()| session::serve(stream, shared));
                if let Err(e) = served {
                    eprintln!("hokuyo-emulator: connection from {peer} ended: {e}");
                }
                let mut state = shared.lock();
                if state.exhausted {
                    state.finished = true;
                    return;
                }
            }
            Err(_) => std::thread::sleep(Duration::from_millis(5)),
        }
    }
}

fn addr_text(addr: &impl ToSocketAddrs) -> String {
    addr.to_socket_addrs()
        .ok()
        .and_then(|mut addrs| addrs.next())
        .map_or_else(|| "the given address".into(), |a| a.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scans_must_fit_the_sensor() {
        let narrow = EmulatorConfig::utm_30lx(vec![vec![1000; 1080]]);
        assert!(matches!(
            Emulator::start(narrow, "127.0.0.1:0"),
            Err(EmulatorError::ScanWidth {
                row: 0,
                len: 1080,
                ..
            })
        ));
        assert!(matches!(
            Emulator::start(EmulatorConfig::utm_30lx(vec![]), "127.0.0.1:0"),
            Err(EmulatorError::NoScans)
        ));
    }

    #[test]
    fn starts_and_stops() {
        let emulator = Emulator::start(
            EmulatorConfig::utm_30lx(vec![vec![1000; 1081]]),
            "127.0.0.1:0",
        )
        .unwrap();
        assert_ne!(emulator.addr().port(), 0);
        assert!(!emulator.is_finished());
        assert_eq!(emulator.stop(), EmulatorStats::default());
    }
}
