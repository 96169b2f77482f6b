//! `slam-bench` over a directory with one benchmark log: a run per seed, the table, and
//! bench.json.

use std::process::Command;

use tests::*;

#[test]
fn slam_bench_runs_every_seed_and_writes_its_report() {
    let carmen = test_data::carmen_dir();
    let dir = scratch("bench");
    let logs = dir.join("logs");
    std::fs::create_dir_all(&logs).unwrap();
    // One log with its relations, and one without (which is not a benchmark log).
    for name in ["mit-csail.clf", "mit-csail.relations", "aces.clf"] {
        std::os::unix::fs::symlink(carmen.join(name), logs.join(name)).unwrap();
    }
    let out = dir.join("out");
    let output = Command::new(bin("slam-bench"))
        .arg(&logs)
        .args(["--seeds", "1,2", "--particles", "30", "--frames", "200"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run slam-bench");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");

    let rows: Vec<&str> = stdout.lines().filter(|l| l.starts_with("| ")).collect();
    assert_eq!(rows.len(), 3, "header, rule, mit-csail: {stdout}");
    assert!(rows[2].starts_with("| mit-csail | 200 | "), "{stdout}");
    assert!(
        rows[2].ends_with("| 0.0319 +- 0.0363 / 0.369 +- 0.365 |"),
        "{stdout}"
    );

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    assert_eq!(report["seeds"], serde_json::json!([1, 2]));
    let log = &report["logs"][0];
    assert_eq!(report["logs"].as_array().map(Vec::len), Some(1));
    assert_eq!(log["log"], "mit-csail");
    assert_eq!(log["runs"].as_array().map(Vec::len), Some(2));
    for (run, seed) in log["runs"].as_array().unwrap().iter().zip([1, 2]) {
        assert_eq!(run["seed"], seed);
        assert!(
            out.join(format!("mit-csail/seed-{seed}/metrics.json"))
                .is_file()
        );
    }
    // bench.json is read as any tool would read it: by key.
    let number = |value: &serde_json::Value| value.as_f64().expect("a number");
    let spread = &log["seed_means_m"];
    let (min, max) = (number(&spread["min"]), number(&spread["max"]));
    let pooled = number(&log["estimate"]["translation_m"]["mean"]);
    // Both seeds score the same relations, so the pooled mean is the seeds' mean.
    assert!(min <= pooled && pooled <= max, "{log}");
    assert!(number(&log["real_time"]) > 1.0, "{log}");
    assert_eq!(log["published"]["graph_mapping_m"]["mean"], 0.004);
}
