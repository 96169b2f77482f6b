//! Issue 14, row 11: every count of skipped or lost data reaches the console at the end of
//! a run, per stage, in one block after the stages' own summaries; "nothing lost" when no
//! stage lost anything.

use std::process::Output;

use tests::*;

/// The block of lost data at the end of the console (stderr), head line first.
fn losses_block(output: &Output) -> Vec<String> {
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    let Some(start) = lines.iter().position(|line| {
        line.starts_with("slam-launch: nothing lost")
            || line.starts_with("slam-launch: data lost or skipped")
    }) else {
        panic!("no block of lost data on the console:\n{stderr}");
    };
    let mut block = vec![lines[start].to_owned()];
    block.extend(
        lines[start + 1..]
            .iter()
            .take_while(|line| line.starts_with("  "))
            .map(|line| (*line).to_owned()),
    );
    block
}

#[test]
fn a_run_that_lost_nothing_says_so() {
    let output = launched("losses-none", &["--world", "office", "--frames", "30"]).output;
    assert_eq!(
        losses_block(&output),
        ["slam-launch: nothing lost (every stage counted no skipped or lost data)"]
    );
}

#[test]
fn lines_a_replay_dropped_are_counted_on_the_console() {
    // The first 600 lines of aces, with a malformed scan line in the middle and the first
    // scan again at the end, far later than the reordering window: dropped as late.
    let log = std::fs::read_to_string(test_data::carmen_log("aces")).expect("aces.clf");
    let lines: Vec<&str> = log.lines().take(600).collect();
    let first_scan = lines
        .iter()
        .find(|line| line.starts_with("FLASER "))
        .expect("a FLASER line");
    let mut doctored: Vec<&str> = lines[..300].to_vec();
    doctored.push("FLASER 180 1.0 2.0");
    doctored.extend(&lines[300..]);
    doctored.push(first_scan);
    let dir = scratch("losses-replay");
    let file = dir.join("doctored.clf");
    std::fs::write(&file, doctored.join("\n") + "\n").expect("write the log");

    let out = dir.join("run");
    let output = launch_replay(&domain("losses-replay"), &out, &file, &[]);
    assert_success(&output);
    assert_eq!(
        losses_block(&output),
        [
            "slam-launch: data lost or skipped, per stage (why: logs/<stage>.log)",
            "  lidar-replay: malformed_lines=1 late_scans=1",
        ]
    );
}

#[test]
fn world_corners_beyond_a_message_are_counted_on_the_console() {
    // A room around a short path, and 1100 square pillars far out of view: 4404 corners,
    // 308 more than a WorldCorners message holds.
    let mut walls = vec!["[[-5,-5],[5,-5],[5,5],[-5,5],[-5,-5]]".to_owned()];
    for i in 0..1100 {
        let (x, y) = (100.0 + f64::from(i % 40), 100.0 + f64::from(i / 40));
        walls.push(format!(
            "[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]",
            x + 0.2,
            x + 0.2,
            y + 0.2,
            y + 0.2
        ));
    }
    let world = format!(
        "{{\"walls\": [{}], \"waypoints\": [[-2,0],[2,0]], \"speed\": 1.0}}",
        walls.join(",")
    );
    let dir = scratch("losses-world");
    let file = dir.join("pillars.json");
    std::fs::write(&file, world).expect("write the world");

    let out = dir.join("run");
    let output = launch(
        &domain("losses-world"),
        &out,
        &[
            "--world",
            file.to_str().expect("utf-8 path"),
            "--frames",
            "5",
        ],
    );
    assert_success(&output);
    let block = losses_block(&output);
    assert_eq!(
        block[0],
        "slam-launch: data lost or skipped, per stage (why: logs/<stage>.log)"
    );
    assert!(
        block.contains(&"  lidar-sim: world_corners_not_published=308".to_owned()),
        "{block:?}"
    );
}
