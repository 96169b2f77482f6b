//! `slam-score` as a program: files in, the score out, bad lines named.

use std::path::PathBuf;
use std::process::Command;

fn fixture(name: &str, text: &str) -> PathBuf {
    test_child::fixture("slam-score-test", name, text)
}

/// What a run of `slam-score` said.
struct Run {
    success: bool,
    stdout: String,
    stderr: String,
}

fn slam_score(trajectory: &PathBuf, relations: &PathBuf, extra: &[&str]) -> Run {
    let output = Command::new(env!("CARGO_BIN_EXE_slam-score"))
        .arg("--trajectory")
        .arg(trajectory)
        .arg("--relations")
        .arg(relations)
        .args(extra)
        .output()
        .unwrap();
    Run {
        success: output.status.success(),
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

/// `slam-score` on a [`stretched_trajectory`] against the relations `text`, both files
/// named after `tag` (`TAG.relations`).
fn score_stretched(tag: &str, text: &str, extra: &[&str]) -> Run {
    let relations = fixture(&format!("{tag}.relations"), text);
    slam_score(&stretched_trajectory(tag), &relations, extra)
}

/// A TUM line of a planar pose.
fn tum(stamp: &str, x: f64, y: f64, yaw: f64) -> String {
    let (s, c) = (yaw / 2.0).sin_cos();
    format!("{stamp} {x} {y} 0 0 0 {s} {c}\n")
}

/// Poses 1.1 m apart along x at full-precision log stamps: 10 % too long a step. Each test
/// has its own copy (`tag`), as tests run in parallel.
fn stretched_trajectory(tag: &str) -> PathBuf {
    let mut text = String::from("# stamp x y z qx qy qz qw\n");
    for k in 0..5u32 {
        let us = 1_134_864_629_895_182_u64 + 100_000 * u64::from(k);
        let stamp = format!("{}.{:06}", us / 1_000_000, us % 1_000_000);
        text.push_str(&tum(&stamp, 1.1 * f64::from(k), 0.0, 0.0));
    }
    fixture(&format!("stretched-{tag}.tum"), &text)
}

#[test]
fn the_score_is_printed_as_json() {
    let run = score_stretched(
        "truth",
        "1134864629.895182 1134864629.995182 1 0 0 0 0 0\n\
         1134864629.995182 1134864630.195182 2 0 0 0 0 0\n\
         1134864629.995182 1134864640.0 2 0 0 0 0 0\n",
        &["--json"],
    );
    let stderr = &run.stderr;
    assert!(run.success, "{stderr}");
    let score: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(score["relations"], 3);
    assert_eq!(score["used"], 2);
    // Errors 0.1 m and 0.2 m: mean 0.15, std 0.05, squared mean 0.025.
    let t = &score["translation_m"];
    assert!((t["mean"].as_f64().unwrap() - 0.15).abs() < 1e-9, "{score}");
    assert!((t["std"].as_f64().unwrap() - 0.05).abs() < 1e-9, "{score}");
    assert!(
        (t["squared_mean"].as_f64().unwrap() - 0.025).abs() < 1e-9,
        "{score}"
    );
    assert_eq!(score["rotation_deg"]["mean"], 0.0);
    assert_eq!(score["unmatched"][0]["line"], 3);
    assert!(
        stderr.contains("line 3: no pose within 1 ms of t2"),
        "{stderr}"
    );
}

#[test]
fn the_text_report_names_both_errors() {
    let run = score_stretched(
        "one",
        "1134864629.895182 1134864629.995182 1 0 0 0 0 0\n",
        &[],
    );
    assert!(run.success);
    let stdout = &run.stdout;
    assert!(stdout.contains("relations: 1 used of 1"), "{stdout}");
    assert!(stdout.contains("translation  mean 0.1000"), "{stdout}");
    assert!(stdout.contains("rotation     mean 0.0000"), "{stdout}");
}

#[test]
fn only_the_relations_spanning_long_enough_are_scored() {
    // Spans of 0.1, 0.2 and 0.4 s; errors 0.1, 0.2 and 0.4 m.
    let relations = "1134864629.895182 1134864629.995182 1 0 0 0 0 0\n\
                     1134864629.995182 1134864630.195182 2 0 0 0 0 0\n\
                     1134864629.895182 1134864630.295182 4 0 0 0 0 0\n";
    let run = score_stretched("span", relations, &["--min-span-s", "0.15", "--json"]);
    assert!(run.success, "{}", run.stderr);
    let score: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(score["used"], 2);
    let mean = score["translation_m"]["mean"].as_f64().unwrap();
    assert!((mean - 0.3).abs() < 1e-9, "{score}");
    assert!(
        run.stderr
            .contains("2 of the 3 relations span 0.15 s or more"),
        "{}",
        run.stderr
    );

    let none = score_stretched("span-none", relations, &["--min-span-s", "1"]);
    assert!(!none.success);
    assert!(
        none.stderr.contains("none of the 3 relations in")
            && none.stderr.contains("spans 1 s or more"),
        "{}",
        none.stderr
    );
    let negative = score_stretched("span-negative", relations, &["--min-span-s=-1"]);
    assert!(!negative.success);
    assert!(
        negative
            .stderr
            .contains("--min-span-s must be a non-negative number, not -1"),
        "{}",
        negative.stderr
    );
}

#[test]
fn malformed_lines_are_named() {
    let relations = fixture(
        "bad.relations",
        "# t1 t2 x y z roll pitch yaw\n\n1.0 2.0 1 0 0 0 0 0\n1.0 2.0 1 0 0 0 0\n",
    );
    let run = slam_score(&stretched_trajectory("malformed"), &relations, &[]);
    assert!(!run.success);
    let stderr = &run.stderr;
    assert!(
        stderr.contains("bad.relations, line 4: 7 fields, expected 8 (t1 t2 x y z roll pitch yaw)"),
        "{stderr}"
    );

    let trajectory = fixture(
        "bad.tum",
        &(tum("1.0", 0.0, 0.0, 0.0) + "2.0 1 0 0 0 0 x 1\n"),
    );
    let stderr = slam_score(&trajectory, &relations, &[]).stderr;
    assert!(
        stderr.contains("bad.tum, line 2: qz: \"x\" is not a finite number"),
        "{stderr}"
    );

    let repeated = fixture("repeated.tum", &(tum("1.0", 0.0, 0.0, 0.0).repeat(2)));
    let stderr = slam_score(&repeated, &relations, &[]).stderr;
    assert!(
        stderr.contains("repeated.tum, line 2: stamp repeats line 1"),
        "{stderr}"
    );
}

#[test]
fn nothing_to_score_is_an_error() {
    let run = score_stretched("far", "7.0 8.0 1 0 0 0 0 0\n", &[]);
    assert!(!run.success);
    let stderr = &run.stderr;
    assert!(
        stderr.contains("none of the 1 relations has both poses"),
        "{stderr}"
    );
}

#[test]
fn absurd_relations_are_refused_with_their_line() {
    let head = "1134864629.895182 1134864629.995182 1 0 0 0 0 0\n";
    for (tag, line, reason) in [
        (
            "huge",
            "1134864629.995182 1134864630.095182 1e300 0 0 0 0 0\n",
            "a motion of 1.000e300 m in 0.100 s",
        ),
        (
            "fast",
            "1134864629.995182 1134864630.095182 50 0 0 0 0 0\n",
            "a motion of 50.000 m in 0.100 s",
        ),
        (
            "turns",
            "1134864629.995182 1134864630.095182 1 0 0 0 0 100\n",
            "yaw 100 rad",
        ),
        (
            "inf",
            "1134864629.995182 1134864630.095182 inf 0 0 0 0 0\n",
            "x: \"inf\"",
        ),
        (
            "clash",
            "1134864629.895182 1134864629.995182 2 0 0 0 0 0\n",
            "the stamps of line 1",
        ),
    ] {
        let run = score_stretched(tag, &format!("{head}{line}"), &[]);
        assert!(!run.success, "{tag}: {}", run.stdout);
        let want = format!("{tag}.relations, line 2: {reason}");
        assert!(run.stderr.contains(&want), "{tag}: {}", run.stderr);
    }
}

#[test]
fn a_repeated_line_counts_once_and_a_backward_one_is_scored_as_such() {
    let forward = "1134864629.895182 1134864629.995182 1 0 0 0 0 0\n";
    let backward = "1134864629.995182 1134864629.895182 -1 0 0 0 0 0\n";
    let text = format!("{forward}{forward}{backward}");
    let run = score_stretched("repeat", &text, &["--json"]);
    assert!(run.success, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("repeat.relations, line 2: repeats line 1; counted once"),
        "{}",
        run.stderr
    );
    assert!(
        run.stderr.contains("1 relation(s) with t2 before t1"),
        "{}",
        run.stderr
    );
    let score: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(score["relations"], 2, "{}", run.stdout);
}
