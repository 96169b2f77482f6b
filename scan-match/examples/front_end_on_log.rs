//! Runs the front end over a recorded log, writes its trajectory (TUM) and scores it
//! against a `.relations` file.
//!
//!     cargo run --release -p scan-match --example front_end_on_log -- \
//!         ../shared/data/carmen/mit-csail.clf [--relations FILE] [--out FILE.tum] \
//!         [--no-odometry] [--format carmen|seed-csv] [--start N] [--limit N] \
//!         [--config FILE.toml] [--debug FILE] [--every N] [--max-range M]
//!
//! `--debug` writes one line per scan: stamp, the front end's increment (x y yaw), the
//! odometry's, points, inliers, iterations, keyframe, microseconds, status, odometry status.
//! `--every N` keeps one scan in N and `--max-range M` cuts the ranges at M metres, as
//! lidar-replay's `--every` and `--max-range` do. The scans come in the replay's order
//! with its stamps, their geometry as the message carries it; odometry is interpolated to
//! each scan's stamp and carried to the sensor's mount, as feature-proc does; the robot's
//! pose is written under the log's own stamp of each scan, as map-sink writes
//! `dead_reckoning.tum`, which the output matches. Without `--relations`
//! the log's own `.relations` beside it is used if there is one.

#[path = "../tests/support/logs.rs"]
mod logs;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use lidar_replay::{Degradation, LogFormat};
use scan_match::{FrontEnd, FrontEndConfig, MatchStatus};
use slam_eval::{Score, Trajectory, read_relations, score};

/// Relations spanning less than this are scored on their own as well.
const SHORT_RELATION_NS: u64 = 60_000_000_000;

struct Args {
    log: PathBuf,
    relations: Option<PathBuf>,
    out: PathBuf,
    odometry: bool,
    format: LogFormat,
    start: usize,
    limit: usize,
    config: Option<PathBuf>,
    debug: Option<PathBuf>,
    every: u64,
    max_range_m: Option<f64>,
}

fn parse_args() -> Result<Args> {
    let mut args = std::env::args().skip(1);
    let mut parsed = Args {
        log: PathBuf::new(),
        relations: None,
        out: PathBuf::from("front_end.tum"),
        odometry: true,
        format: LogFormat::Carmen,
        start: 0,
        limit: usize::MAX,
        config: None,
        debug: None,
        every: 1,
        max_range_m: None,
    };
    let mut log = None;
    while let Some(arg) = args.next() {
        let mut value = || args.next().with_context(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--relations" => parsed.relations = Some(value()?.into()),
            "--out" => parsed.out = value()?.into(),
            "--no-odometry" => parsed.odometry = false,
            "--format" => parsed.format = value()?.parse().map_err(anyhow::Error::msg)?,
            "--start" => parsed.start = value()?.parse()?,
            "--limit" => parsed.limit = value()?.parse()?,
            "--config" => parsed.config = Some(value()?.into()),
            "--debug" => parsed.debug = Some(value()?.into()),
            "--every" => parsed.every = value()?.parse()?,
            "--max-range" => parsed.max_range_m = Some(value()?.parse()?),
            other if other.starts_with("--") => bail!("unknown option {other}"),
            other => log = Some(PathBuf::from(other)),
        }
    }
    parsed.log = log.context("usage: front_end_on_log LOG [--relations FILE] [--out FILE] [--no-odometry] [--format F] [--start N] [--limit N] [--config FILE] [--debug FILE] [--every N] [--max-range M]")?;
    if parsed.relations.is_none() {
        let beside = parsed.log.with_extension("relations");
        if beside.exists() {
            parsed.relations = Some(beside);
        }
    }
    Ok(parsed)
}

fn main() -> Result<()> {
    let args = parse_args()?;
    let config = match &args.config {
        Some(path) => toml::from_str(&std::fs::read_to_string(path)?)?,
        None => FrontEndConfig::default(),
    };
    let degradation = Degradation::new(args.every, args.max_range_m)?;
    let scans = logs::load_degraded(
        &args.log,
        args.format,
        args.start.saturating_add(args.limit),
        degradation,
    )?;
    // The front end starts cold at `--start`, as a run replayed from there does.
    let scans = scans.get(args.start..).unwrap_or_default();
    if scans.is_empty() {
        bail!(
            "{} has no scans from --start {} (with --limit {})",
            args.log.display(),
            args.start,
            args.limit
        );
    }
    let mut front_end = FrontEnd::new(config)?;
    let mut tum = String::new();
    let mut written = std::collections::HashSet::new();
    let mut debug = String::new();
    let mut previous_odometry = None;
    let mut times_us: Vec<f64> = Vec::with_capacity(scans.len());
    let wall = Instant::now();
    for scan in scans {
        let out = front_end.process(&scan.input(args.odometry))?;
        times_us.push(out.elapsed.as_secs_f64() * 1e6);
        if args.debug.is_some() {
            let odometry_step = match (previous_odometry, scan.odometry) {
                (Some(a), Some(b)) => {
                    let a: scan_match::OdometryInput = a;
                    a.odom_from_robot.between(&b.odom_from_robot)
                }
                _ => slam_geom::Pose2::IDENTITY,
            };
            previous_odometry = scan.odometry;
            let i = out.increment;
            writeln!(
                debug,
                "{} {:.5} {:.5} {:.5} {:.5} {:.5} {:.5} {} {} {} {} {:.0} {:?} {:?}",
                slam_geom::format_stamp(out.stamp_ns),
                i.x,
                i.y,
                i.yaw,
                odometry_step.x,
                odometry_step.y,
                odometry_step.yaw,
                out.points,
                out.inliers,
                out.iterations,
                out.keyframe as u8,
                out.elapsed.as_secs_f64() * 1e6,
                out.status,
                out.odometry
            )?;
        }
        if let MatchStatus::Failed(why) = out.status {
            eprintln!(
                "{}: match failed ({why:?})",
                slam_geom::format_stamp(out.stamp_ns)
            );
        }
        // The replay drops a scan that repeats a stamp; a trajectory cannot repeat one.
        if !written.insert(scan.log_stamp_ns) {
            continue;
        }
        // The robot's pose (the front end tracks the sensor's), as map-sink writes it.
        let p = out
            .odom_from_robot
            .compose(&scan.robot_from_sensor.inverse());
        let (s, c) = (0.5 * p.yaw).sin_cos();
        // Under the log's own stamp, which the relations name.
        writeln!(
            tum,
            "{} {:.6} {:.6} 0 0 0 {:.9} {:.9}",
            slam_geom::format_stamp(scan.log_stamp_ns),
            p.x,
            p.y,
            s,
            c
        )?;
    }
    let wall = wall.elapsed();
    std::fs::write(&args.out, tum)?;
    if let Some(path) = &args.debug {
        std::fs::write(path, debug)?;
    }
    times_us.sort_by(f64::total_cmp);
    let pick = |q: f64| times_us[((times_us.len() - 1) as f64 * q) as usize];
    let stats = front_end.stats();
    println!(
        "{} scans ({}), odometry {}: {:.1} us/scan mean, p50 {:.1}, p99 {:.1}, max {:.1} (wall {:.2} s)",
        scans.len(),
        args.log.display(),
        if args.odometry {
            "used where the log has it"
        } else {
            "off"
        },
        times_us.iter().sum::<f64>() / times_us.len().max(1) as f64,
        pick(0.5),
        pick(0.99),
        pick(1.0),
        wall.as_secs_f64()
    );
    println!("{stats:?}; map points {}", front_end.map_points());
    println!("trajectory: {}", args.out.display());
    if let Some(relations) = &args.relations {
        let trajectory = Trajectory::read_tum(&args.out)?;
        let relations = read_relations(relations)?;
        print_score("relations", &score(&trajectory, &relations, 1_000_000));
        // Drift over minutes is the loop closure's to fix; the front end's own accuracy
        // shows on the short relations.
        let short: Vec<_> = relations
            .iter()
            .filter(|r| r.t2_ns.abs_diff(r.t1_ns) < SHORT_RELATION_NS)
            .cloned()
            .collect();
        print_score(
            "relations under 60 s",
            &score(&trajectory, &short, 1_000_000),
        );
    }
    Ok(())
}

fn print_score(label: &str, s: &Score) {
    println!(
        "{label} {} used {}: translation {:.4} +- {:.4} m (max {:.3}), rotation {:.4} +- {:.4} deg",
        s.relations,
        s.used,
        s.translation_m.mean,
        s.translation_m.std,
        s.translation_m.max,
        s.rotation_deg.mean,
        s.rotation_deg.std
    );
}
