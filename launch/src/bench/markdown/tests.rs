use slam_eval::{ErrorStats, Metrics, PoseErrors};

use super::*;
use crate::bench::report::WorldResult;

/// A table of the rendered file, by its heading: the header cells and the rows' cells.
fn table_under(text: &str, heading: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let cells = |line: &str| -> Vec<String> {
        line.trim()
            .trim_matches('|')
            .split(" | ")
            .map(|c| c.trim().to_owned())
            .collect()
    };
    let after = &text[text.find(heading).unwrap()..];
    let mut lines = after.lines().skip_while(|l| !l.starts_with('|'));
    let header = cells(lines.next().unwrap());
    let rule = lines.next().unwrap();
    assert_eq!(rule, format!("|{}", "---|".repeat(header.len())));
    let rows: Vec<Vec<String>> = lines
        .take_while(|l| l.starts_with('|'))
        .map(cells)
        .collect();
    assert!(rows.iter().all(|r| r.len() == header.len()), "{rows:?}");
    (header, rows)
}

/// `0.035 +- 0.043` as its two numbers.
fn mean_std_of(cell: &str) -> (f64, f64) {
    let (mean, std) = cell.split_once(" +- ").unwrap();
    (mean.parse().unwrap(), std.parse().unwrap())
}

fn metrics(duration_s: f64, ate: Option<f64>) -> Metrics {
    let mut metrics: Metrics = serde_json::from_str(
        r#"{"frames_published": 7374, "frames_processed": 7374, "frames_dropped": 0,
            "path_length_m": 250.0, "map_corners": 300, "wall_s": 12.0,
            "scans_per_s": 600.0, "latency_ms_p50": null, "latency_ms_p99": null}"#,
    )
    .unwrap();
    metrics.duration_s = Some(duration_s);
    metrics.ate_rmse_m = ate;
    metrics.dead_reckoning_ate_rmse_m = ate.map(|a| 4.0 * a);
    metrics.map_corner_rmse_m = ate.map(|a| 2.0 * a);
    metrics
}

fn run(seed: u64, wall_s: f64, duration_s: f64, ate: Option<f64>, slam_kib: u64) -> SeedRun {
    SeedRun {
        seed,
        out: format!("runs/bench/x/seed-{seed}").into(),
        wall_s,
        metrics: metrics(duration_s, ate),
        peak_memory_kib: [
            ("lidar-replay".to_owned(), 7 * 1024),
            ("slam-proc".to_owned(), slam_kib),
            ("graph-proc".to_owned(), 64 * 1024),
            ("map-sink".to_owned(), 128 * 1024),
        ]
        .into(),
    }
}

fn log(name: &str, translation: (f64, f64)) -> LogResult {
    let stats = |(mean, std)| ErrorStats {
        mean,
        std,
        ..ErrorStats::default()
    };
    LogResult {
        log: name.to_owned(),
        // As an older report had it: the figures are looked up by name.
        published: None,
        file: format!("{name}.clf").into(),
        relations: format!("{name}.relations").into(),
        estimate: Some(PoseErrors {
            translation_m: stats(translation),
            rotation_deg: stats((0.412, 0.733)),
        }),
        seed_means_m: Spread::of(&[translation.0 - 0.001, translation.0, translation.0 + 0.002]),
        front_end: None,
        scans: 7374,
        wall_s: 12.0,
        duration_s: Some(1366.0),
        real_time: Some(113.8),
        runs: vec![
            run(1, 11.0, 1366.0, None, 90 * 1024),
            run(2, 13.0, 1366.0, None, 100 * 1024),
        ],
    }
}

fn report() -> BenchReport {
    let logs = vec![
        log("aces", (0.0351, 0.0432)),
        log("fr079", (0.0468, 0.051)),
        log("intel", (0.0291, 0.0301)),
        log("mit-csail", (0.0402, 0.0555)),
    ];
    let mut report = BenchReport::new(100, vec![1, 2, 3], None, None, logs);
    report.worlds = vec![WorldResult {
        world: "office".to_owned(),
        runs: vec![
            run(1, 6.5, 98.9, Some(0.006), 95 * 1024),
            run(2, 6.7, 98.9, Some(0.008), 95 * 1024),
        ],
    }];
    report.commit = Some("e2d0d73".to_owned());
    report.started_utc = Some("2025-11-29 02:44".to_owned());
    report.processors = Some(2);
    report
}

#[test]
fn the_logs_table_parses_back_with_ours_and_the_published_figures() {
    let text = render(&report());
    assert!(text.contains("Measured at commit `e2d0d73`, started 2025-11-29 02:44 UTC"));
    let (header, rows) = table_under(&text, LOGS_HEADING);
    assert_eq!(header, LOG_COLUMNS);
    let names: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(names, ["aces", "fr079", "intel", "mit-csail"]);
    let column = |name: &str| LOG_COLUMNS.iter().position(|c| *c == name).unwrap();
    let aces = &rows[0];
    assert_eq!(aces[column("scans")], "7374");
    assert_eq!(mean_std_of(&aces[column("ours (m)")]), (0.035, 0.043));
    assert_eq!(mean_std_of(&aces[column("ours (deg)")]), (0.41, 0.73));
    assert_eq!(
        aces[column("seed means (m) min / median / max")],
        "0.034 / 0.035 / 0.037"
    );
    assert_eq!(aces[column("front end alone (m)")], "n/a");
    // Every log has every published column, from the bench's table of figures.
    for row in &rows {
        let figures = published(&row[0]).unwrap();
        let cell = |name: &str| mean_std_of(&row[column(name)]);
        let pair = |f: crate::bench::published::Figure| (f.mean, f.std);
        assert_eq!(cell("scan matching (m)"), pair(figures.scan_matching_m));
        assert_eq!(cell("GMapping (m)"), pair(figures.rbpf_m));
        assert_eq!(cell("graph mapping (m)"), pair(figures.graph_mapping_m));
        assert_eq!(cell("Cartographer (m)"), pair(figures.cartographer_m));
        assert_eq!(cell("Cartographer (deg)"), pair(figures.cartographer_deg));
    }
}

#[test]
fn speed_memory_and_worlds_parse_back() {
    let text = render(&report());
    let (header, rows) = table_under(&text, SPEED_HEADING);
    assert_eq!(header, SPEED_COLUMNS);
    assert_eq!(rows.len(), 5);
    // Mean wall 12 s over the two seeds, 1366 s of data: 114 times real time.
    assert_eq!(
        rows[0][..5],
        ["aces", "1366.0", "12.0", "114", "41"].map(String::from)
    );
    // Memory: the largest of the seeds, in MiB; a process that reported none is n/a.
    assert_eq!(
        rows[0][5..],
        ["7.0", "n/a", "100.0", "64.0", "128.0", "n/a"].map(String::from)
    );
    assert_eq!(rows[4][0], "world office");
    assert_eq!(rows[4][4], "n/a");
    let (header, rows) = table_under(&text, WORLDS_HEADING);
    assert_eq!(header, WORLD_COLUMNS);
    assert_eq!(
        rows,
        [[
            "office",
            "7374",
            "0.007 (0.006 - 0.008)",
            "0.028 (0.024 - 0.032)",
            "0.014 (0.012 - 0.016)"
        ]
        .map(String::from)]
    );
}

#[test]
fn a_report_reads_back_from_its_json() {
    let report = report();
    let json = serde_json::to_string(&report).unwrap();
    let read: BenchReport = serde_json::from_str(&json).unwrap();
    assert_eq!(render(&read), render(&report));
    // A report of an older slam-bench, without worlds, memory, commit or date.
    let mut old: serde_json::Value = serde_json::from_str(&json).unwrap();
    for key in ["worlds", "commit", "started_utc", "processors"] {
        old.as_object_mut().unwrap().remove(key);
    }
    let read: BenchReport = serde_json::from_value(old).unwrap();
    let text = render(&read);
    assert!(text.contains("Measured at commit `not recorded`"), "{text}");
    assert!(text.contains("No simulated world was run"));
    assert!(!text.contains("failed"));
}

#[test]
fn failed_runs_are_listed_under_the_logs() {
    let mut report = report();
    report.failures = vec![crate::bench::report::FailedRun::new(
        "intel",
        3,
        "slam-launch failed\nslam-launch: map-sink stalled",
    )];
    let text = render(&report);
    assert!(
        text.contains("Runs that failed, and are in none of the figures:\n\n- intel seed 3: slam-launch: map-sink stalled\n"),
        "{text}"
    );
    // The tables still parse.
    assert_eq!(table_under(&text, LOGS_HEADING).1.len(), 4);
}
