//! `--rate` as the process takes it: a rate out of range is refused by name with the range
//! (not a panic in `Duration`), and a slow rate's long waits do not hold up SIGTERM.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ipc_types::prelude::*;

mod common;
use common::Sim;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(60);

#[test]
fn a_rate_out_of_range_is_refused_with_the_range() {
    let domain = format!("sim-rate-refused-{}", std::process::id());
    let sim = || {
        let mut command = Command::new(env!("CARGO_BIN_EXE_lidar-sim"));
        command.args(["--frames", "1", "--domain", &domain]);
        command
    };
    test_child::assert_rates_refused(
        sim,
        &["1e-20", "-1", "2000", "NaN", "inf"],
        "must be 0 (lockstep) or from 0.001 to 1000 scans per second",
    );
}

#[test]
fn sigterm_ends_the_wait_for_a_slow_rates_next_scan() {
    // One scan every 100 s: the first goes out at once, the second is 100 s away.
    let Sim {
        child: sim,
        node,
        domain,
    } = Sim::start(
        "slow-rate",
        &["--world", "hall", "--rate", "0.01"],
        Stdio::piped(),
    );
    let scans = Inlet::open(&node, topic::SCAN).unwrap();
    let deadline = Instant::now() + LIMIT;
    let first = loop {
        assert!(Instant::now() < deadline, "no first scan");
        wait_any(&[&scans], Duration::from_millis(50)).unwrap();
        if let Some(scan) = scans.receive().unwrap() {
            break scan.header.seq;
        }
    };
    assert_eq!(first, 0);
    // The simulator is now waiting for the second scan's time.
    let stopped = test_child::stop(sim, LIMIT);
    let output = stopped.output;
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("stopped after 1 scans"), "{stderr}");
    // Waits are sliced in 50 ms naps: the stop comes within one. The bound leaves room for
    // a loaded machine and stays far below the 100 s an unsliced wait would take.
    assert!(stopped.took < Duration::from_secs(5), "{:?}", stopped.took);
    drop((scans, node));
    let _ = domain.remove_leftovers();
}
