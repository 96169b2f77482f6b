//! Runs the front end and the back end over a recorded log, writes the back end's
//! trajectory (TUM) and scores it and the front end's against the log's `.relations`.
//!
//!     cargo run --release -p back-end --example back_end_on_log -- \
//!         ../shared/data/carmen/mit-csail.clf [--out FILE.tum] [--no-odometry] [--limit N]

#[path = "../../scan-match/tests/support/logs.rs"]
mod logs;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use back_end::{GlobalConfig, GlobalSlam, ScanRanges};
use lidar_replay::LogFormat;
use scan_match::{FrontEnd, FrontEndConfig};
use slam_eval::{Trajectory, read_relations, score};
use slam_geom::Pose2;

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let mut log = None;
    let mut out = PathBuf::from("back_end.tum");
    let mut odometry = true;
    let mut limit = usize::MAX;
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--out" => out = args.next().context("--out needs a value")?.into(),
            "--no-odometry" => odometry = false,
            "--limit" => limit = args.next().context("--limit needs a value")?.parse()?,
            other if other.starts_with("--") => bail!("unknown option {other}"),
            other => log = Some(PathBuf::from(other)),
        }
    }
    let log = log.context("usage: back_end_on_log LOG [--out FILE] [--no-odometry] [--limit N]")?;
    let scans = logs::load(&log, LogFormat::Carmen, limit)?;
    let config = FrontEndConfig::default();
    let mut front_end = FrontEnd::new(config.clone())?;
    let mut back_end = GlobalSlam::new(GlobalConfig::for_front_end(&config))?;
    let mut front_path = Vec::new();
    let wall = Instant::now();
    let mut back_ns = 0u128;
    let mut back_cpu_ns = 0u64;
    for scan in &scans {
        let input = scan.input(odometry);
        let output = front_end.process(&input)?;
        front_path.push((output.stamp_ns, output.odom_from_robot));
        let started = Instant::now();
        // The CPU clock costs a system call: read around the scans it takes only, where the
        // work is.
        let wanted = back_end.wants_scan(&output.odom_from_robot);
        let cpu = wanted.then(thread_cpu_ns);
        let scan = wanted.then_some(ScanRanges {
            geometry: &input.geometry,
            ranges: input.ranges,
        });
        back_end.add_scan(
            output.stamp_ns,
            &output.odom_from_robot,
            &output.increment,
            &output.increment_covariance,
            scan,
        )?;
        let elapsed = started.elapsed().as_nanos();
        back_ns += elapsed;
        back_cpu_ns += cpu.map_or(elapsed as u64, |cpu| thread_cpu_ns() - cpu);
    }
    let finish = Instant::now();
    let cpu = thread_cpu_ns();
    back_end.finish()?;
    back_ns += finish.elapsed().as_nanos();
    back_cpu_ns += thread_cpu_ns() - cpu;
    println!(
        "{} scans, wall {:.2} s, back end {:.2} s (cpu {:.2} s); {:?}",
        scans.len(),
        wall.elapsed().as_secs_f64(),
        back_ns as f64 * 1e-9,
        back_cpu_ns as f64 * 1e-9,
        back_end.stats()
    );
    let front_file = out.with_extension("front.tum");
    write_tum(&front_file, &front_path)?;
    write_tum(&out, &back_end.path())?;
    let started = Instant::now();
    if let Some(grid) = back_end.grid()? {
        let grid_file = out.with_extension("pgm");
        write_pgm(&grid_file, &grid)?;
        println!(
            "grid {} x {} cells in {:.2} s: {}",
            grid.width(),
            grid.height(),
            started.elapsed().as_secs_f64(),
            grid_file.display()
        );
    }
    let relations = log.with_extension("relations");
    if relations.exists() {
        let relations = read_relations(&relations)?;
        for (label, path) in [("front end", &front_file), ("back end", &out)] {
            let s = score(&Trajectory::read_tum(path)?, &relations, 1_000_000);
            println!(
                "{label}: {} of {} relations: translation {:.4} +- {:.4} m (max {:.3}), rotation {:.4} deg",
                s.used,
                s.relations,
                s.translation_m.mean,
                s.translation_m.std,
                s.translation_m.max,
                s.rotation_deg.mean
            );
        }
    }
    Ok(())
}

/// This thread's time on a CPU so far, nanoseconds (Linux; 0 elsewhere): the back end's
/// cost without the waits of a machine shared with other work.
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// The grid as a trinary PGM (map_server's pixels), top row the highest y.
fn write_pgm(path: &Path, grid: &back_end::occupancy_grid::OccupancyGrid) -> Result<()> {
    use back_end::occupancy_grid::CellState;
    let mut bytes = format!("P5\n{} {}\n255\n", grid.width(), grid.height()).into_bytes();
    for row in (0..grid.height()).rev() {
        bytes.extend((0..grid.width()).map(|col| match grid.state(col, row) {
            CellState::Occupied => 0u8,
            CellState::Free => 254,
            CellState::Unknown => 205,
        }));
    }
    std::fs::write(path, bytes)?;
    Ok(())
}

fn write_tum(path: &Path, poses: &[(u64, Pose2)]) -> Result<()> {
    let mut text = String::new();
    let mut last = None;
    for (stamp, p) in poses {
        if last.is_some_and(|s| *stamp <= s) {
            continue;
        }
        last = Some(*stamp);
        let (s, c) = (0.5 * p.yaw).sin_cos();
        writeln!(
            text,
            "{} {:.6} {:.6} 0 0 0 {s:.9} {c:.9}",
            slam_geom::format_stamp(*stamp),
            p.x,
            p.y
        )?;
    }
    std::fs::write(path, text)?;
    Ok(())
}
