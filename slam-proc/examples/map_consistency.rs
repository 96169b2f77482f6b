//! How well a saved map agrees with the path that drew it, as the localizer sees the map.
//! Every scan of the log that the run's path holds is placed at its pose, moved uphill on
//! its likelihood over the saved grid (the converged localizer's field, by the wall faces a
//! beam can end on, its beam model and its beams), and the distance from the pose to that
//! best fit is the scan's disagreement with the map. Where the passes of a building agree,
//! each scan's best fit lies within a few centimetres of its pose; where two passes along a
//! corridor part, the scans of one fit the walls the others drew some decimetres away, and
//! a localizer on the map parts from the mapping path there by as much. No ground truth is
//! needed.
//!
//!     cargo run --release -p slam-proc --example map_consistency -- \
//!         runs/aces ../shared/data/carmen/aces.clf [--trajectory FILE] [--out FILE]
//!
//! `--trajectory` checks another path on the same map (a localization run's, say) instead of
//! the map's own `trajectory.tum`; `--out` writes a line per scan: stamp, the best fit's
//! offset in x, y (metres) and yaw (radians), its distance, and how much more likely a beam
//! is there than at the pose (log-likelihood per beam). A scan that sees only a corridor's
//! two walls fixes nothing along it: its best fit may slide there for a gain of next to
//! nothing, and the distance alone overstates what the map disagrees with.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Parser;
use lidar_replay::{LogFormat, LogRecord, ReorderConfig, open_log};
use saved_map::SavedMap;
use slam_eval::{ErrorStats, percentile};
use slam_geom::{Pose2, read_tum, wrap_angle};
use slam_proc::{
    HillClimb, LocalizeConfig, ScanRanges, TrackingField, beam_bearings, sample_beam_ends,
};
use stage_kit::{say, say_err};

/// The climb from each pose: first steps of 0.1 m and 0.02 rad, halved four times (to 6 mm
/// and 1.3 mrad), which reach a best fit some decimetres away; a scan farther off than that
/// is beyond every threshold the summary counts anyway.
const CLIMB: HillClimb = HillClimb {
    xy: 0.1,
    yaw: 0.02,
    levels: 5,
    passes: 4,
};

/// Disagreements the summary counts the scans beyond, metres.
const BEYOND_M: [f64; 3] = [0.05, 0.10, 0.20];

/// A stretch is scans beyond this, metres, ...
const STRETCH_M: f64 = 0.10;

/// ... that ends after this long within it, seconds.
const STRETCH_GAP_S: f64 = 2.0;

/// The summary lists the stretches that reach this, metres.
const SHOWN_M: f64 = 0.20;

#[derive(Parser)]
#[command(about = "How far each scan's best fit on a saved map lies from its pose")]
struct Args {
    /// The saved map: a run's output directory.
    map: PathBuf,
    /// The log the run replayed.
    log: PathBuf,
    /// The path to check (default: the map's own trajectory.tum).
    #[arg(long)]
    trajectory: Option<PathBuf>,
    /// The log's format: carmen or seed-csv.
    #[arg(long, default_value = "carmen")]
    format: String,
    /// Write a line per scan here: stamp, offset x, y, yaw, its distance and the gain per
    /// beam.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn main() -> ExitCode {
    match run(&Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            say_err(&format!("map_consistency: {error:#}"));
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<()> {
    let format: LogFormat = args.format.parse().map_err(anyhow::Error::msg)?;
    if format == LogFormat::Mcap {
        bail!("--format: carmen or seed-csv (a run.mcap holds no saved map to check)");
    }
    let map = SavedMap::load(&args.map)
        .with_context(|| format!("cannot use the map in {}", args.map.display()))?;
    let Some(grid) = map.grid else {
        bail!("{} has no occupancy grid", args.map.display());
    };
    let config = LocalizeConfig::default();
    let field = TrackingField::new(&grid, &config);
    let path_file = args
        .trajectory
        .clone()
        .unwrap_or_else(|| args.map.join("trajectory.tum"));
    let poses: HashMap<u64, Pose2> = read_tum(&path_file)
        .with_context(|| format!("reading {}", path_file.display()))?
        .into_iter()
        .map(|(_, p)| {
            let pose = Pose2::new(p.position[0], p.position[1], p.yaw());
            (p.stamp_ns, pose)
        })
        .collect();

    let reader = open_log(format, &args.log, ReorderConfig::default())
        .with_context(|| format!("opening {}", args.log.display()))?;
    let mut points = Vec::new();
    let mut bearings = Vec::new();
    let mut fits: Vec<Fit> = Vec::new();
    let mut unreadable = 0_usize;
    for record in reader {
        let scan = match record {
            Ok(LogRecord::Scan(scan)) => scan,
            Ok(_) => continue,
            Err(error) => {
                unreadable += 1;
                say_err(&format!("map_consistency: skipped: {error:#}"));
                continue;
            }
        };
        let Some(pose) = poses.get(&scan.stamp_ns) else {
            continue;
        };
        let ranges = ScanRanges {
            angle_min: scan.geometry.angle_min,
            angle_increment: scan.geometry.angle_increment,
            range_min: scan.geometry.range_min,
            range_max: scan.geometry.range_max,
            ranges: &scan.ranges,
        };
        if !sample_beam_ends(&ranges, config.beams, &mut points) {
            continue;
        }
        beam_bearings(&points, &mut bearings);
        let score = |pose: &Pose2| field.scan_score(&points, &bearings, pose);
        let best = CLIMB.climb_on(score, *pose);
        let offset = Pose2::new(
            best.x - pose.x,
            best.y - pose.y,
            wrap_angle(best.yaw - pose.yaw),
        );
        let gain = (score(&best) - score(pose)) / points.len() as f64;
        fits.push(Fit {
            stamp_ns: scan.stamp_ns,
            offset,
            distance: offset.x.hypot(offset.y),
            gain,
        });
    }
    if fits.is_empty() {
        bail!(
            "no scan of {} has a pose in {}",
            args.log.display(),
            path_file.display()
        );
    }
    say(&summary(&fits));
    if unreadable > 0 {
        say(&format!(
            "  records of the log not read (skipped): {unreadable}"
        ));
    }
    if let Some(out) = &args.out {
        let mut text = String::from("# stamp dx dy dyaw distance gain_per_beam\n");
        for fit in &fits {
            writeln!(
                text,
                "{} {:.4} {:.4} {:.5} {:.4} {:.4}",
                slam_geom::format_stamp(fit.stamp_ns),
                fit.offset.x,
                fit.offset.y,
                fit.offset.yaw,
                fit.distance,
                fit.gain
            )?;
        }
        std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
    }
    Ok(())
}

/// One scan's best fit on the map.
struct Fit {
    stamp_ns: u64,
    /// From the pose to the best fit, in the map's frame.
    offset: Pose2,
    /// Of the offset's translation, metres.
    distance: f64,
    /// How much more likely a beam is at the best fit than at the pose (log-likelihood).
    gain: f64,
}

/// Scans in a row whose best fits lie beyond `STRETCH_M`.
struct Stretch {
    first_ns: u64,
    last_ns: u64,
    /// The farthest best fit, metres ...
    worst_m: f64,
    /// ... and the largest gain per beam.
    best_gain: f64,
}

/// The distribution of the disagreements and the worst stretches.
fn summary(fits: &[Fit]) -> String {
    let distances: Vec<f64> = fits.iter().map(|fit| fit.distance).collect();
    let n = distances.len();
    let stats = ErrorStats::of(&distances);
    let at = |p: f64| percentile(&distances, p).unwrap_or(f64::NAN);
    let mut text = format!(
        "{n} scans: best fit {:.3} m from the pose on average, median {:.3} m, 95 % {:.3} m, at most {:.3} m",
        stats.mean,
        at(50.0),
        at(95.0),
        stats.max
    );
    for beyond in BEYOND_M {
        let count = distances.iter().filter(|d| **d > beyond).count();
        let share = 100.0 * count as f64 / n as f64;
        let _ = write!(text, "\n  beyond {beyond:.2} m: {count} ({share:.1} %)");
    }
    let mut stretch: Option<Stretch> = None;
    let mut stretches = Vec::new();
    for fit in fits {
        if fit.distance <= STRETCH_M {
            if let Some(open) = &stretch
                && fit.stamp_ns.saturating_sub(open.last_ns) as f64 * 1e-9 > STRETCH_GAP_S
            {
                stretches.extend(stretch.take());
            }
            continue;
        }
        let open = stretch.get_or_insert(Stretch {
            first_ns: fit.stamp_ns,
            last_ns: fit.stamp_ns,
            worst_m: 0.0,
            best_gain: 0.0,
        });
        open.last_ns = fit.stamp_ns;
        open.worst_m = open.worst_m.max(fit.distance);
        open.best_gain = open.best_gain.max(fit.gain);
    }
    stretches.extend(stretch);
    stretches.retain(|stretch| stretch.worst_m > SHOWN_M);
    if !stretches.is_empty() {
        let _ = write!(
            text,
            "\n  stretches beyond {STRETCH_M:.2} m that reach {SHOWN_M:.2} m (stamps in s; the most \
             a beam gained at a best fit, in log-likelihood):"
        );
        for stretch in stretches {
            let _ = write!(
                text,
                "\n    {} - {}: up to {:.2} m, gain up to {:.2}",
                slam_geom::format_stamp(stretch.first_ns),
                slam_geom::format_stamp(stretch.last_ns),
                stretch.worst_m,
                stretch.best_gain
            );
        }
    }
    text
}
