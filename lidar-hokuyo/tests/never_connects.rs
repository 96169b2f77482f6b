//! The driver binary and a sensor it never reaches: an address that cannot be resolved is
//! refused at start; a closed port shows on the console (stdout, which slam-launch shows),
//! rate-limited, while every attempt goes to the log (stderr); and a run that got no scan
//! ends non-zero, saying so.

mod common;

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::*;
use test_child::{finish, lines_of, terminate, wait_for_line};

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(60);

#[test]
fn an_address_that_cannot_be_resolved_is_refused_at_start() {
    for addr in ["notanaddr", "127.0.0.1:notaport"] {
        let domain = unique_domain("unresolved");
        let started = Instant::now();
        let child = Command::new(env!("CARGO_BIN_EXE_lidar-hokuyo"))
            .args(["--addr", addr, "--domain", domain.name()])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // A driver that took the address would retry it for ever: bounded, and killed.
        let output = finish(child, LIMIT);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{addr}: {stderr}");
        assert!(
            stderr.contains(&format!(
                "lidar-hokuyo: --addr: '{addr}' cannot be resolved to an address (HOST:PORT"
            )),
            "{stderr}"
        );
        assert!(output.stdout.is_empty(), "refused before announcing ready");
        // Refused, not retried: no back-off of any length came first.
        assert!(started.elapsed() < LIMIT / 2, "{:?}", started.elapsed());
        clean_up(&domain);
    }
}

#[test]
fn a_closed_port_shows_on_the_console_and_a_run_without_scans_fails() {
    let closed = test_child::closed_port();
    let addr = closed.addr();
    let domain = unique_domain("closed");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lidar-hokuyo"))
        .args([
            "--addr",
            addr,
            "--domain",
            domain.name(),
            "--subscribers",
            "0",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = lines_of(child.stdout.take().unwrap());
    let stderr = lines_of(child.stderr.take().unwrap());
    // The log has every attempt: wait for the third (back-off 100, 200, then 400 ms).
    let mut log = Vec::new();
    if let Err(e) = wait_for_line(&stderr, &mut log, "reconnecting in 400ms", LIMIT) {
        panic!("no third attempt: {e}");
    }
    terminate(&child);
    let output = finish(child, LIMIT);
    log.extend(stderr.iter());
    let console: Vec<String> = stdout.iter().collect();
    let log = log.join("\n");

    assert_eq!(output.status.code(), Some(1), "{log}");
    let attempts = log.matches("reconnecting in").count();
    assert!(attempts >= 3, "{log}");
    // The console: ready, then the first failure at once; the next would come 10 s later.
    let refused = format!("cannot connect to {addr}: Connection refused");
    assert_eq!(
        console.first().map(String::as_str),
        Some("ready"),
        "{console:?}"
    );
    assert_eq!(
        console.iter().filter(|l| l.starts_with(&refused)).count(),
        1,
        "{console:?}"
    );
    assert!(
        console[1].starts_with(&refused) && console[1].ends_with("; retrying"),
        "{console:?}"
    );
    assert!(
        log.contains(&format!(
            "lidar-hokuyo: no scan arrived from {addr} ({attempts} failed attempts; the last: \
             {refused}"
        )),
        "{log}"
    );
    clean_up(&domain);
}
