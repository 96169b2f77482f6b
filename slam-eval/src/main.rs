//! `slam-score`: the relative-pose error of a trajectory against ground-truth relations.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;
use slam_eval::{DEFAULT_TOLERANCE_NS, ErrorStats, Score, Trajectory, read_relations_noted, score};
use slam_geom::format_stamp;

/// Scores a trajectory with the relative-pose metric of Kuemmerle et al. 2009: for every
/// ground-truth relation (t1, t2, motion) the trajectory's own motion from t1 to t2 is
/// compared with it; the translational (m) and rotational (deg) errors are summarised as
/// mean and standard deviation, plain and squared.
#[derive(Debug, Parser)]
#[command(name = "slam-score", version)]
struct Args {
    /// Estimated trajectory, TUM format: stamp x y z qx qy qz qw.
    #[arg(long, value_name = "FILE")]
    trajectory: PathBuf,
    /// Ground-truth relations: t1 t2 x y z roll pitch yaw (pose at t2 in the frame at t1).
    #[arg(long, value_name = "FILE")]
    relations: PathBuf,
    /// How far a pose's stamp may be from a relation's, milliseconds.
    #[arg(long, default_value_t = DEFAULT_TOLERANCE_NS as f64 / 1e6)]
    tolerance_ms: f64,
    /// Score only the relations whose two stamps are at least this many seconds apart,
    /// most of which close loops. On the benchmark logs the relations a few seconds apart
    /// are as far off for the raw odometry as for any SLAM result (the ground truth's own
    /// noise), and the rest show what a change did to the map.
    #[arg(long, value_name = "SECONDS")]
    min_span_s: Option<f64>,
    /// Print the score as JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Relations without poses listed one by one; the rest are only counted.
const LISTED_UNMATCHED: usize = 10;

fn main() -> ExitCode {
    stage_kit::run_tool("slam-score", run)
}

fn run(args: Args) -> Result<()> {
    anyhow::ensure!(
        args.tolerance_ms.is_finite() && args.tolerance_ms >= 0.0,
        "--tolerance-ms must be a non-negative number, not {}",
        args.tolerance_ms
    );
    let tolerance_ns = (args.tolerance_ms * 1e6).round() as u64;
    let trajectory = Trajectory::read_tum(&args.trajectory)?;
    let read = read_relations_noted(&args.relations)?;
    for note in read.notes(&args.relations) {
        eprintln!("slam-score: {note}");
    }
    let mut relations = read.relations;
    if let Some(span_s) = args.min_span_s {
        anyhow::ensure!(
            span_s.is_finite() && span_s >= 0.0,
            "--min-span-s must be a non-negative number, not {span_s}"
        );
        let in_file = relations.len();
        let span_ns = (span_s * 1e9).round() as u64;
        relations.retain(|r| r.t2_ns.abs_diff(r.t1_ns) >= span_ns);
        anyhow::ensure!(
            !relations.is_empty(),
            "none of the {in_file} relations in {} spans {span_s} s or more",
            args.relations.display()
        );
        eprintln!(
            "slam-score: {} of the {in_file} relations span {span_s} s or more",
            relations.len()
        );
    }
    let score = score(&trajectory, &relations, tolerance_ns);

    for unmatched in score.unmatched.iter().take(LISTED_UNMATCHED) {
        eprintln!(
            "slam-score: {} line {}: no pose within {} ms of {} ({} -> {})",
            args.relations.display(),
            unmatched.line,
            args.tolerance_ms,
            unmatched.missing,
            format_stamp(unmatched.t1_ns),
            format_stamp(unmatched.t2_ns)
        );
    }
    if score.unmatched.len() > LISTED_UNMATCHED {
        eprintln!(
            "slam-score: ... and {} more relations without poses",
            score.unmatched.len() - LISTED_UNMATCHED
        );
    }
    anyhow::ensure!(
        score.used > 0,
        "none of the {} relations has both poses in {} ({} poses) within {} ms",
        score.relations,
        args.trajectory.display(),
        trajectory.len(),
        args.tolerance_ms
    );

    if args.json {
        let text = serde_json::to_string_pretty(&score).context("cannot format the score")?;
        println!("{text}");
    } else {
        print_text(&score);
    }
    Ok(())
}

fn print_text(score: &Score) {
    println!(
        "relations: {} used of {} ({} without poses within the tolerance)",
        score.used,
        score.relations,
        score.unmatched.len()
    );
    let row = |name: &str, unit: &str, stats: &ErrorStats| {
        println!(
            "{name:<12} mean {:.4} +- {:.4} {unit}   squared {:.6} +- {:.6} {unit}^2   max {:.4} {unit}",
            stats.mean, stats.std, stats.squared_mean, stats.squared_std, stats.max
        );
    };
    row("translation", "m", &score.translation_m);
    row("rotation", "deg", &score.rotation_deg);
    if let Some(ratio) = score.length_ratio {
        println!("{:<12} estimate / truth {ratio:.4}", "length");
    }
}
