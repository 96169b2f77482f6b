//! A Hokuyo run that never reaches its sensor: an address that names nothing is refused
//! before anything starts; a closed port shows on slam-launch's console, and the run, once
//! stopped, fails with a message that no scan arrived instead of passing with "scans 0".

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine: every stage has to start.
const LIMIT: Duration = Duration::from_secs(120);

#[test]
fn an_address_that_cannot_be_resolved_is_refused_before_starting() {
    let out = scratch("hokuyo-unresolved").join("run");
    let mut child = spawn_launch(
        &domain("hokuyo-unresolved"),
        &out,
        &["--source", "hokuyo", "--addr", "notanaddr"],
        Stdio::piped(),
    );
    // A launcher that took the address would run until stopped: bounded, and stopped.
    if wait_within(&mut child, LIMIT).is_none() {
        // SIGTERM, not SIGKILL: slam-launch stops its stages on the way out.
        send(pid_of(&child), Signal::SIGTERM);
        let output = child.wait_with_output().unwrap();
        panic!(
            "still running after {LIMIT:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(
        stderr.contains(
            "refusing to start: the Hokuyo's address: 'notanaddr' cannot be resolved to an \
             address"
        ),
        "{stderr}"
    );
    assert!(!out.exists(), "refused before the run's directory was made");
}

#[test]
fn a_run_that_never_gets_a_scan_shows_why_and_fails() {
    let closed = test_child::closed_port();
    let addr = closed.addr();
    let out = scratch("hokuyo-closed").join("run");
    let mut child = Command::new(bin("slam-launch"))
        .args(["--domain", &domain("hokuyo-closed"), "--out"])
        .arg(&out)
        .args(["--source", "hokuyo", "--addr", addr])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("slam-launch");
    let stderr = child.stderr.take().unwrap();
    let (sender, lines) = mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    // The console shows the failure (a stage's stdout line, prefixed with its name).
    let shown = format!("[lidar-hokuyo] cannot connect to {addr}: Connection refused");
    let deadline = Instant::now() + LIMIT;
    let mut seen: Vec<String> = Vec::new();
    while !seen.iter().any(|line| line.starts_with(&shown)) {
        let left = deadline.saturating_duration_since(Instant::now());
        match lines.recv_timeout(left) {
            Ok(line) => seen.push(line),
            Err(e) => {
                stop(&mut child);
                panic!("not on the console ({e}): {seen:?}");
            }
        }
    }
    send(pid_of(&child), Signal::SIGTERM);
    let status = child.wait().unwrap();
    reader.join().unwrap();
    seen.extend(lines.try_iter());
    let console = seen.join("\n");
    assert_eq!(status.code(), Some(1), "{console}");
    assert!(
        console.contains(&format!(
            "slam-launch: no scan arrived from the Hokuyo at {addr}: lidar-hokuyo: no scan \
             arrived from {addr} ("
        )),
        "{console}"
    );
}
