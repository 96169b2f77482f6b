//! The benchmark's table on the console, as Markdown; docs/RESULTS.md is [`super::markdown`]'s.

use slam_eval::ErrorStats;

use super::published::{Figure, Published};
use super::report::{BenchReport, LogResult};

const HEADER: [&str; 13] = [
    "log",
    "scans",
    "ours: translation (m)",
    "seed means (m) min / median / max",
    "ours: rotation (deg)",
    "front end: translation (m)",
    "front end: rotation (deg)",
    "wall (s)",
    "x real time",
    "scan matching (m)",
    "RBPF (m)",
    "graph mapping (m)",
    "Cartographer (m / deg)",
];

/// One row per log; errors are mean +- std over the relations (of all seeds together).
pub fn render(report: &BenchReport) -> String {
    let mut rows = vec![
        HEADER.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>(),
        HEADER.iter().map(|_| "---".to_owned()).collect(),
    ];
    rows.extend(report.logs.iter().map(|log| row(log, report.seeds.len())));
    rows.iter()
        .map(|cells| format!("| {} |\n", cells.join(" | ")))
        .collect()
}

/// Mean +- standard deviation with `decimals` decimals; `n/a` without a score.
pub(super) fn mean_std(stats: Option<ErrorStats>, decimals: usize) -> String {
    stats.map_or_else(
        || "n/a".to_owned(),
        |s| format!("{:.decimals$} +- {:.decimals$}", s.mean, s.std),
    )
}

/// A published figure. As many decimals as the papers give: three in Kuemmerle et al., four
/// (metres) and three (degrees) in Hess et al.
pub(super) fn figure(f: Figure, decimals: usize) -> String {
    format!("{:.decimals$} +- {:.decimals$}", f.mean, f.std)
}

/// The published columns of a log (scan matching, GMapping, graph mapping, Cartographer in
/// metres and in degrees); `-` for a log nobody published figures for.
pub(super) fn published_cells(figures: Option<Published>) -> Vec<String> {
    figures.map_or_else(
        || vec!["-".to_owned(); 5],
        |p| {
            vec![
                figure(p.scan_matching_m, 3),
                figure(p.rbpf_m, 3),
                figure(p.graph_mapping_m, 3),
                figure(p.cartographer_m, 4),
                figure(p.cartographer_deg, 3),
            ]
        },
    )
}

fn row(log: &LogResult, seeds: usize) -> Vec<String> {
    let ours = mean_std;
    let spread = match log.seed_means_m {
        Some(s) if seeds > 1 => format!("{:.3} / {:.3} / {:.3}", s.min, s.median, s.max),
        _ => "-".to_owned(),
    };
    // The table on the console has Cartographer's two figures in one column.
    let mut published = published_cells(log.published);
    if log.published.is_some() {
        let degrees = published.pop().unwrap_or_default();
        let metres = published.pop().unwrap_or_default();
        published.push(format!("{metres} / {degrees}"));
    } else {
        published.pop();
    }
    let mut cells = vec![
        log.log.clone(),
        log.scans.to_string(),
        ours(log.estimate.map(|e| e.translation_m), 3),
        spread,
        ours(log.estimate.map(|e| e.rotation_deg), 2),
        ours(log.front_end.map(|e| e.translation_m), 3),
        ours(log.front_end.map(|e| e.rotation_deg), 2),
        format!("{:.1}", log.wall_s),
        log.real_time
            .map_or_else(|| "n/a".to_owned(), |x| format!("{x:.0}")),
    ];
    cells.extend(published);
    cells
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::report::Spread;
    use slam_eval::PoseErrors;

    fn log(name: &str) -> LogResult {
        let stats = |mean, std| ErrorStats {
            mean,
            std,
            ..ErrorStats::default()
        };
        LogResult {
            log: name.to_owned(),
            published: crate::bench::published::published(name),
            file: format!("{name}.clf").into(),
            relations: format!("{name}.relations").into(),
            estimate: Some(PoseErrors {
                translation_m: stats(0.5797, 1.7818),
                rotation_deg: stats(2.604, 6.0411),
            }),
            seed_means_m: Spread::of(&[0.5, 0.58, 0.7]),
            front_end: None,
            scans: 1988,
            wall_s: 3.4,
            duration_s: Some(424.0),
            real_time: Some(124.7),
            runs: Vec::new(),
        }
    }

    #[test]
    fn ours_and_the_published_figures_side_by_side() {
        let report = BenchReport::new(
            100,
            vec![1, 2, 3],
            None,
            None,
            vec![log("mit-csail"), log("seed-hall")],
        );
        let table = render(&report);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 4);
        assert!(lines[0].starts_with("| log | scans | ours: translation (m) |"));
        assert_eq!(
            lines[2],
            "| mit-csail | 1988 | 0.580 +- 1.782 | 0.500 / 0.580 / 0.700 | 2.60 +- 6.04 \
             | n/a | n/a | 3.4 | 125 | 0.106 +- 0.325 | 0.049 +- 0.049 \
             | 0.004 +- 0.009 | 0.0319 +- 0.0363 / 0.369 +- 0.365 |"
        );
        // A log nobody published figures for still gets our columns.
        assert!(lines[3].starts_with("| seed-hall | 1988 | 0.580 +- 1.782 |"));
        assert!(lines[3].ends_with("| - | - | - | - |"));
        // One seed has no spread over seeds.
        let one = BenchReport::new(100, vec![1], None, None, vec![log("aces")]);
        let table = render(&one);
        assert!(table.contains("| 0.580 +- 1.782 | - |"), "{table}");
        assert!(table.contains("| 0.060 +- 0.049 |"), "{table}");
    }
}
