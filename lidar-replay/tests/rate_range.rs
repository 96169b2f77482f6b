//! `--rate` as the process takes it: a speed factor out of range is refused by name with
//! the range, before the log is opened, not a panic in `Duration` once it is replayed.

use std::process::Command;

#[test]
fn a_rate_out_of_range_is_refused_with_the_range() {
    let dir = std::env::temp_dir().join(format!("lidar-replay-rate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("two.clf");
    let ranges = vec!["2.50"; 180].join(" ");
    let line = |stamp: &str| format!("FLASER 180 {ranges} 0 0 0 0 0 0 {stamp} robot 0.1\n");
    std::fs::write(&log, line("100.0") + &line("101.0")).unwrap();
    let domain = format!("replay-rate-{}", std::process::id());
    let replay = || {
        let mut command = Command::new(env!("CARGO_BIN_EXE_lidar-replay"));
        command
            .args(["--format", "carmen", "--file", log.to_str().unwrap()])
            .args(["--subscribers", "0", "--no-odometry", "--domain", &domain]);
        command
    };
    test_child::assert_rates_refused(
        replay,
        &["1e-20", "-1", "1001", "NaN"],
        "must be 0 (lockstep) or a speed factor from 0.001 to 1000",
    );
}
