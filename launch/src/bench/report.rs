//! What a benchmark found, per log: ours over the seeds, and the published figures beside.

use std::path::PathBuf;

use serde::Serialize;
use slam_eval::{Metrics, PoseErrors, RelativePoseErrors, ScoreSummary};

use super::published::{Published, SOURCES};

/// One run of slam-launch: a log with one seed.
#[derive(Debug, Clone, Serialize)]
pub struct SeedRun {
    pub seed: u64,
    /// The run's output directory.
    pub out: PathBuf,
    /// The whole slam-launch command, start to exit, seconds.
    pub wall_s: f64,
    /// The run's metrics.json.
    pub metrics: Metrics,
}

/// The smallest, median and largest of some values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    /// `None` for no values; the median of an even count is the mean of the middle two.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = match n {
            0 => return None,
            _ if n % 2 == 1 => sorted[n / 2],
            _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
        };
        Some(Self {
            min: sorted[0],
            median,
            max: sorted[n - 1],
        })
    }
}

/// One log over all its seeds.
#[derive(Debug, Clone, Serialize)]
pub struct LogResult {
    /// The log's name (file stem), as the published figures know it.
    pub log: String,
    /// The figures published for the log, if it is one of the benchmark's.
    pub published: Option<Published>,
    pub file: PathBuf,
    pub relations: PathBuf,
    /// `trajectory.tum`'s errors over the relations of all seeds together.
    pub estimate: Option<PoseErrors>,
    /// The spread of the seeds' mean translational errors.
    pub seed_means_m: Option<Spread>,
    /// `dead_reckoning.tum` (the front end alone), over all seeds' relations.
    pub front_end: Option<PoseErrors>,
    /// Scans processed (the most of any seed; every seed processes the whole log).
    pub scans: u64,
    /// Mean wall time of a run, seconds.
    pub wall_s: f64,
    /// How long the log took to record, seconds (its scans' stamps, first to last).
    pub duration_s: Option<f64>,
    /// `duration_s / wall_s`: how many times faster than the log was recorded.
    pub real_time: Option<f64>,
    pub runs: Vec<SeedRun>,
}

impl LogResult {
    /// Sums up the runs of one log.
    pub fn new(log: String, file: PathBuf, relations: PathBuf, runs: Vec<SeedRun>) -> Self {
        let summaries = |pick: fn(&RelativePoseErrors) -> Option<ScoreSummary>| {
            runs.iter()
                .filter_map(|run| run.metrics.relative_pose_error.as_ref().and_then(pick))
                .collect::<Vec<_>>()
        };
        let estimate = summaries(|rpe| rpe.trajectory);
        let front_end = summaries(|rpe| rpe.dead_reckoning);
        let pool = |summaries: &[ScoreSummary]| {
            let parts: Vec<(usize, PoseErrors)> = summaries
                .iter()
                .filter_map(|s| Some((s.used, s.errors?)))
                .collect();
            PoseErrors::pooled(&parts)
        };
        let seed_means: Vec<f64> = estimate
            .iter()
            .filter_map(|s| s.errors.map(|e| e.translation_m.mean))
            .collect();
        let wall_s = if runs.is_empty() {
            0.0
        } else {
            runs.iter().map(|r| r.wall_s).sum::<f64>() / runs.len() as f64
        };
        let duration_s = runs.iter().find_map(|r| r.metrics.duration_s);
        Self {
            published: super::published::published(&log),
            log,
            file,
            relations,
            estimate: pool(&estimate),
            seed_means_m: Spread::of(&seed_means),
            front_end: pool(&front_end),
            scans: runs
                .iter()
                .map(|r| r.metrics.frames_processed)
                .max()
                .unwrap_or(0),
            wall_s,
            duration_s,
            real_time: duration_s.filter(|_| wall_s > 0.0).map(|d| d / wall_s),
            runs,
        }
    }
}

/// The whole benchmark, as bench.json.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    pub particles: usize,
    pub seeds: Vec<u64>,
    /// The configuration file passed through to slam-launch, if any.
    pub config: Option<PathBuf>,
    /// Scans per log, if limited.
    pub frames: Option<u64>,
    /// Every how many scans of a log were replayed, if not all (`--every`).
    pub every: Option<u64>,
    /// Ranges beyond this were replayed as no-returns, metres (`--max-range`).
    pub max_range_m: Option<f64>,
    /// Where the published figures come from.
    pub published_sources: &'static str,
    pub logs: Vec<LogResult>,
}

impl BenchReport {
    pub fn new(
        particles: usize,
        seeds: Vec<u64>,
        config: Option<PathBuf>,
        frames: Option<u64>,
        logs: Vec<LogResult>,
    ) -> Self {
        Self {
            particles,
            seeds,
            config,
            frames,
            every: None,
            max_range_m: None,
            published_sources: SOURCES,
            logs,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_odd_and_even_counts() {
        assert_eq!(Spread::of(&[]), None);
        let odd = Spread::of(&[0.3, 0.1, 0.2]).unwrap();
        assert_eq!((odd.min, odd.median, odd.max), (0.1, 0.2, 0.3));
        let even = Spread::of(&[0.4, 0.1, 0.2, 0.3]).unwrap();
        assert!((even.median - 0.25).abs() < 1e-12);
    }
}
