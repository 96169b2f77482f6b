//! docs/RESULTS.md: a benchmark's report as Markdown. Nobody edits that file by hand;
//! `slam-bench` writes it (`--markdown FILE`, or by default on the whole benchmark).

use std::collections::BTreeMap;
use std::fmt::Write;

use super::published::published;
use super::report::{BenchReport, LogResult, SeedRun, Spread};
use super::table::{mean_std, published_cells};

/// The headings of the three tables, which the parsing test finds them by.
pub const LOGS_HEADING: &str = "## Benchmark logs";
pub const SPEED_HEADING: &str = "## Speed and memory";
pub const WORLDS_HEADING: &str = "## Simulated worlds";

/// The columns of the logs' table.
pub const LOG_COLUMNS: [&str; 12] = [
    "log",
    "scans",
    "ours (m)",
    "ours (deg)",
    "seed means (m) min / median / max",
    "front end alone (m)",
    "front end alone (deg)",
    "scan matching (m)",
    "GMapping (m)",
    "graph mapping (m)",
    "Cartographer (m)",
    "Cartographer (deg)",
];

/// The processes whose memory is shown, in pipeline order; `source` is whichever of the
/// sources ran.
const PROCESSES: [&str; 6] = [
    "source",
    "feature-proc",
    "slam-proc",
    "graph-proc",
    "map-sink",
    "slam-launch",
];
const SOURCES: [&str; 3] = ["lidar-replay", "lidar-sim", "lidar-hokuyo"];

/// The columns of the speed table.
pub const SPEED_COLUMNS: [&str; 11] = [
    "run",
    "duration (s)",
    "wall (s)",
    "x real time",
    "Cartographer wall (s)",
    "source (MiB)",
    "feature-proc (MiB)",
    "slam-proc (MiB)",
    "graph-proc (MiB)",
    "map-sink (MiB)",
    "slam-launch (MiB)",
];

/// The columns of the worlds' table.
pub const WORLD_COLUMNS: [&str; 5] = [
    "world",
    "scans",
    "ATE RMSE (m)",
    "front end alone ATE RMSE (m)",
    "map corner RMSE (m)",
];

/// The whole file.
pub fn render(report: &BenchReport) -> String {
    let mut text = String::from("# Results\n\n");
    text.push_str(&provenance(report));
    let _ = write!(
        text,
        "\n{LOGS_HEADING}\n\nRelative-pose error against each log's ground-truth relations \
         (Kuemmerle et al. 2009; docs/CONVENTIONS.md): mean +- standard deviation over the \
         relations of every seed together, translation in metres and rotation in degrees. \
         \"front end alone\" is the scan-matching front end's own path (`dead_reckoning.tum`). \
         The published columns are the figures of the papers on the whole logs: {}.\n\n",
        report.published_sources
    );
    text.push_str(&markdown_table(&LOG_COLUMNS, logs_rows(report)));
    text.push_str(&failures(report));
    let _ = write!(
        text,
        "\n{SPEED_HEADING}\n\nWall time of one whole run (slam-launch from start to exit, \
         the mean over the seeds) against the duration of the data (its scans' stamps, first \
         to last); Cartographer's as published, on a desktop. Peak resident memory of each \
         process (VmHWM, the largest over the seeds; read while the process runs, so a peak \
         in its last moments can be missed).\n\n"
    );
    text.push_str(&markdown_table(&SPEED_COLUMNS, speed_rows(report)));
    let _ = write!(
        text,
        "\n{WORLDS_HEADING}\n\n`slam-launch --world NAME` with the same particles and \
         seeds: absolute trajectory error against the simulator's ground truth after \
         alignment, and the error of the map's corners against the world's true corners; \
         the mean over the seeds (min - max when they differ).\n\n"
    );
    if report.worlds.is_empty() {
        text.push_str("No simulated world was run (`--worlds none`).\n");
    } else {
        text.push_str(&markdown_table(&WORLD_COLUMNS, world_rows(report)));
    }
    text
}

/// Who wrote the file, from what, and how to write it again.
fn provenance(report: &BenchReport) -> String {
    let commit = report.commit.as_deref().unwrap_or("not recorded");
    let started = report.started_utc.as_deref().unwrap_or("not recorded");
    let processors = report
        .processors
        .map_or_else(|| "not recorded".to_owned(), |n| n.to_string());
    let seeds: Vec<String> = report.seeds.iter().map(u64::to_string).collect();
    let mut how = vec![
        format!("{} particles", report.particles),
        format!(
            "{} {}",
            if seeds.len() == 1 { "seed" } else { "seeds" },
            seeds.join(", ")
        ),
    ];
    how.extend(
        report
            .frames
            .map(|n| format!("the first {n} scans of each log")),
    );
    how.extend(report.every.map(|n| format!("every {n}th scan")));
    how.extend(
        report
            .max_range_m
            .map(|m| format!("ranges beyond {m} m dropped")),
    );
    how.extend(
        report
            .config
            .as_ref()
            .map(|c| format!("config {}", c.display())),
    );
    format!(
        "Written by `slam-bench`; do not edit by hand. To measure again: `cargo build \
         --release --workspace && target/release/slam-bench ../shared/data/carmen --seeds \
         1-5` (run on every log with published figures, whole, it rewrites this file); to \
         write it from a benchmark's report: `target/release/slam-bench --markdown-from \
         runs/bench/bench.json --markdown docs/RESULTS.md`.\n\n\
         Measured at commit `{commit}`, started {started} UTC, on a machine with \
         {processors} logical processors; lockstep replay, {}.\n",
        how.join(", ")
    )
}

/// The runs that failed, one line each; nothing when none did.
fn failures(report: &BenchReport) -> String {
    if report.failures.is_empty() {
        return String::new();
    }
    let mut text = String::from("\nRuns that failed, and are in none of the figures:\n\n");
    for failure in &report.failures {
        let _ = writeln!(
            text,
            "- {} seed {}: {}",
            failure.run, failure.seed, failure.error
        );
    }
    text
}

fn markdown_table(columns: &[&str], rows: Vec<Vec<String>>) -> String {
    let mut text = format!(
        "| {} |\n|{}\n",
        columns.join(" | "),
        "---|".repeat(columns.len())
    );
    for row in rows {
        let _ = writeln!(text, "| {} |", row.join(" | "));
    }
    text
}

fn logs_rows(report: &BenchReport) -> Vec<Vec<String>> {
    report
        .logs
        .iter()
        .map(|log| {
            let spread = match log.seed_means_m {
                Some(s) if report.seeds.len() > 1 => {
                    format!("{:.3} / {:.3} / {:.3}", s.min, s.median, s.max)
                }
                _ => "-".to_owned(),
            };
            let mut cells = vec![
                log.log.clone(),
                log.scans.to_string(),
                mean_std(log.estimate.map(|e| e.translation_m), 3),
                mean_std(log.estimate.map(|e| e.rotation_deg), 2),
                spread,
                mean_std(log.front_end.map(|e| e.translation_m), 3),
                mean_std(log.front_end.map(|e| e.rotation_deg), 2),
            ];
            // By name, so that a report written before a log's figures were added gets them.
            cells.extend(published_cells(published(&log.log)));
            cells
        })
        .collect()
}

fn speed_rows(report: &BenchReport) -> Vec<Vec<String>> {
    let logs = report.logs.iter().map(|log: &LogResult| {
        let cartographer = published(&log.log).and_then(|p| p.cartographer_wall_s);
        speed_row(&log.log, &log.runs, cartographer)
    });
    let worlds = report
        .worlds
        .iter()
        .map(|world| speed_row(&format!("world {}", world.world), &world.runs, None));
    logs.chain(worlds).collect()
}

fn speed_row(name: &str, runs: &[SeedRun], cartographer_wall_s: Option<f64>) -> Vec<String> {
    let optional = |value: Option<f64>, decimals: usize| {
        value.map_or_else(|| "n/a".to_owned(), |v| format!("{v:.decimals$}"))
    };
    let duration = runs.iter().find_map(|r| r.metrics.duration_s);
    let wall =
        (!runs.is_empty()).then(|| runs.iter().map(|r| r.wall_s).sum::<f64>() / runs.len() as f64);
    let real_time = duration
        .zip(wall)
        .filter(|&(_, w)| w > 0.0)
        .map(|(d, w)| d / w);
    let mut cells = vec![
        name.to_owned(),
        optional(duration, 1),
        optional(wall, 1),
        optional(real_time, 0),
        optional(cartographer_wall_s, 0),
    ];
    let peaks = peak_memory(runs);
    cells.extend(
        PROCESSES
            .iter()
            .map(|process| optional(peaks.get(*process).map(|&kib| kib as f64 / 1024.0), 1)),
    );
    cells
}

/// The largest peak of each process over the runs, KiB; the source under `source`.
fn peak_memory(runs: &[SeedRun]) -> BTreeMap<&'static str, u64> {
    let mut peaks = BTreeMap::new();
    for (process, &kib) in runs.iter().flat_map(|r| &r.peak_memory_kib) {
        let column = if SOURCES.contains(&process.as_str()) {
            "source"
        } else if let Some(name) = PROCESSES.iter().find(|p| **p == process.as_str()) {
            name
        } else {
            continue;
        };
        let peak = peaks.entry(column).or_insert(0);
        *peak = kib.max(*peak);
    }
    peaks
}

fn world_rows(report: &BenchReport) -> Vec<Vec<String>> {
    report
        .worlds
        .iter()
        .map(|world| {
            let over_seeds = |pick: fn(&SeedRun) -> Option<f64>| {
                let values: Vec<f64> = world.runs.iter().filter_map(pick).collect();
                mean_and_spread(&values)
            };
            let scans = world
                .runs
                .iter()
                .map(|r| r.metrics.frames_processed)
                .max()
                .unwrap_or(0);
            vec![
                world.world.clone(),
                scans.to_string(),
                over_seeds(|r| r.metrics.ate_rmse_m),
                over_seeds(|r| r.metrics.dead_reckoning_ate_rmse_m),
                over_seeds(|r| r.metrics.map_corner_rmse_m),
            ]
        })
        .collect()
}

/// `0.006` for one value (or equal ones), `0.007 (0.006 - 0.008)` for a spread; `n/a` for
/// none.
fn mean_and_spread(values: &[f64]) -> String {
    let Some(spread) = Spread::of(values) else {
        return "n/a".to_owned();
    };
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    if spread.max - spread.min < 5e-4 {
        format!("{mean:.3}")
    } else {
        format!("{mean:.3} ({:.3} - {:.3})", spread.min, spread.max)
    }
}

#[cfg(test)]
mod tests;
