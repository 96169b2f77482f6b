//! The driver binary against TCP peers that are not SCIP sensors: one that keeps sending
//! replies to a command nobody sent, one that floods bare newlines. Neither may hold the
//! driver in its first exchange: the deadline holds, the peer is named as no SCIP sensor,
//! the connection is retried with back-off, and SIGTERM ends it all promptly.

mod common;

use std::io::Write;
use std::net::TcpListener;
use std::process::Child;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver};
use std::thread::JoinHandle;
use std::time::Duration;

use common::*;
use test_child::{lines_of, stop, wait_for_line};

/// Generous for a loaded 2-core machine; the driver's reply timeout is 2 s.
const LIMIT: Duration = Duration::from_secs(60);

/// A TCP peer on 127.0.0.1 that, on every connection, writes `chunk` every `every` until
/// the connection breaks or the peer is dropped. Each accepted connection is reported.
struct Peer {
    addr: String,
    accepted: Receiver<()>,
    done: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Peer {
    fn start(chunk: &'static [u8], every: Duration) -> Self {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        listener.set_nonblocking(true).unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let done = Arc::new(AtomicBool::new(false));
        let (sender, accepted) = mpsc::channel();
        let stop = Arc::clone(&done);
        let thread = std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                let Ok((mut stream, _)) = listener.accept() else {
                    std::thread::sleep(Duration::from_millis(10));
                    continue;
                };
                let _ = sender.send(());
                let stop = Arc::clone(&stop);
                std::thread::spawn(move || {
                    stream.set_nonblocking(false).unwrap();
                    while !stop.load(Ordering::Relaxed) && stream.write_all(chunk).is_ok() {
                        std::thread::sleep(every);
                    }
                });
            }
        });
        Self {
            addr,
            accepted,
            done,
            thread: Some(thread),
        }
    }

    /// Waits for the next connection, at most `limit`.
    fn wait_for_connection(&self, limit: Duration) {
        self.accepted
            .recv_timeout(limit)
            .unwrap_or_else(|e| panic!("no connection within {limit:?}: {e}"));
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// A driver that is killed if the test fails before it is stopped, so none outlives it.
struct Running(Option<Child>);

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(mut child) = self.0.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// Runs the driver against `peer` until it has named the peer and come back for a second
/// try, then stops it with SIGTERM during that try. Returns its stderr.
fn named_retried_and_stopped(peer: &Peer, tag: &str, last_began: &str) -> String {
    let domain = unique_domain(tag);
    let mut child = Running(Some(spawn_driver(
        &peer.addr,
        &domain,
        &["--subscribers", "0"],
    )));
    let lines = lines_of(child.0.as_mut().unwrap().stderr.take().unwrap());
    let mut seen = Vec::new();
    peer.wait_for_connection(LIMIT);
    let named = format!(
        "lidar-hokuyo: {}: not a SCIP sensor: no reply to QT within 2s, only ",
        peer.addr
    );
    wait_for_line(&lines, &mut seen, &named, LIMIT).unwrap();
    let line = seen.iter().find(|l| l.contains(&named)).unwrap();
    assert!(
        line.contains(&format!(
            "(the last began {last_began:?}); reconnecting in 100ms"
        )),
        "{line}"
    );
    // Back-off, then the second try: the driver is in its first exchange again.
    peer.wait_for_connection(LIMIT);
    let child = child.0.take().unwrap();
    let stopped = stop(child, LIMIT);
    let output = stopped.output;
    seen.extend(lines.iter());
    let log = seen.join("\n");
    // No scan came: the run failed, and says so.
    assert_eq!(output.status.code(), Some(1), "{log}");
    assert!(
        log.contains(&format!("no scan arrived from {}", peer.addr)),
        "{log}"
    );
    // Reads wake every 100 ms to look at the stop flag, and the QT on the way out waits at
    // most 100 ms: well within a second. The bound leaves room for a loaded machine and
    // stays below the 2 s the exchange would otherwise still have had.
    assert!(
        stopped.took < Duration::from_millis(1900),
        "{:?}: {log}",
        stopped.took
    );
    clean_up(&domain);
    log
}

#[test]
fn a_peer_answering_other_commands_is_named_and_retried_and_sigterm_ends_it() {
    // A well-formed reply to VV, which nobody asked for, every 25 ms.
    let peer = Peer::start(b"VV\n00P\n\n", Duration::from_millis(25));
    let log = named_retried_and_stopped(&peer, "other-replies", "VV");
    assert!(log.contains("stopped: published 0 scans"), "{log}");
}

#[test]
fn a_flood_of_bare_newlines_is_named_and_retried_and_sigterm_ends_it() {
    let peer = Peer::start(&[b'\n'; 4096], Duration::from_millis(1));
    let log = named_retried_and_stopped(&peer, "newlines", "");
    assert!(log.contains("stopped: published 0 scans"), "{log}");
}
