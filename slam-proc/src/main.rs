//! `slam-proc`: FastSLAM over corner maps, from the features topic to pose and map topics.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::prelude::*;
use slam_proc::{
    FastSlam, FilterStats, LineObservation, MeasuredMotion, Observation, OdometryInput, SlamConfig,
};
use stage_kit::{say, say_err};

/// Subscribes to features (each with the odometry at its scan's stamp, if the run has any),
/// publishes a pose estimate for every scan, the best particle's map every few scans and at
/// the end, and the best particle's whole path at the end.
#[derive(Debug, Parser)]
#[command(name = "slam-proc", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// Particles of the filter (overrides the config file).
    #[arg(long)]
    particles: Option<usize>,
    /// Seed of the filter's noise: the same seed gives the same run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Publish the map every this many scans (and at the end).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..))]
    map_every: u64,
    /// TOML file with filter settings (every field optional).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Pose subscribers to wait for before the first lockstep publish.
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
}

fn main() -> ExitCode {
    stage_kit::main("slam-proc", run)
}

fn run() -> Result<()> {
    let args = Args::parse();
    shutdown::install().context("cannot install the Ctrl-C handler")?;
    let mut config: SlamConfig = stage_kit::settings::load(args.config.as_deref())?;
    if let Some(particles) = args.particles {
        anyhow::ensure!(particles > 0, "--particles must be at least 1");
        config.particles = particles;
    }
    // Before the particles exist: a count the machine cannot hold would otherwise grow
    // until the kernel kills this process (or another one).
    slam_proc::memory::check(config.particles).context("refusing to start")?;
    let mut slam = FastSlam::new(config, args.seed).context("slam configuration")?;

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("slam-proc")?;
    let features = Inlet::open(&node, topic::FEATURES)?;
    let delivery = features.delivery();
    let maps = Outlet::create(&domain, &node, topic::MAP, delivery, 1)?;
    let poses = Outlet::create(&domain, &node, topic::POSE, delivery, 0)?;
    // The path goes out once, at the end, in many chunks: lossless whatever the run's
    // delivery, or a real-time run would keep only the last few.
    let path = Outlet::create(&domain, &node, topic::PATH, Delivery::Lossless, 0)?;
    say("ready");
    if delivery == Delivery::Lossless {
        poses.wait_for_subscribers(args.subscribers, None)?;
    }

    let mut observations = Vec::new();
    let mut lines = Vec::new();
    let mut processed = 0u64;
    let mut last_header = Header::new(0, 0, "map");
    // The most corners a map snapshot had to leave out (MAX_MAP_CORNERS fit in one).
    let mut left_out = 0u64;
    loop {
        if wait_any(&[&features], Duration::from_millis(100))? == Wake::Shutdown {
            break;
        }
        while let Some(sample) = features.receive()? {
            if sample.header.is_end_of_stream() {
                left_out = left_out.max(publish_map(&maps, &slam, last_header)?);
                publish_path(&path, &slam, last_header)?;
                poses.publish_end_of_stream(sample.header.seq, sample.header.stamp_ns)?;
                say_err(&summary(&slam.stats()));
                ipc_types::losses::report(&[("map_corners_not_published", left_out)]);
                return Ok(());
            }
            observations.clear();
            observations.extend(sample.corners().iter().map(to_observation));
            lines.clear();
            lines.extend(sample.lines().iter().map(to_line));
            let stamp = sample.header.stamp_ns;
            // feature-proc's front end measured the motion; without it (or with
            // `use_measured_motion = false`) the filter estimates it from the corners and
            // lines, on the odometry feature-proc paired with the scan.
            let front_end = sample.motion();
            let estimate = match &front_end {
                Some(motion) if slam.config().use_measured_motion => {
                    slam.process_measured(stamp, &observations, &lines, &to_motion(motion))
                }
                _ => {
                    let odometry_input = sample.odometry().map(to_odometry);
                    slam.process(stamp, &observations, &lines, odometry_input.as_ref())
                }
            };
            // The front end's own pose is the motion estimate alone, whatever moved the
            // particles: both start at the first scan's pose.
            let dead_reckoning = front_end.map_or(estimate.dead_reckoning.into(), |m| m.pose);
            let header = sample.header;
            poses.publish(|pose| {
                pose.header = header;
                pose.header.set_frame_id("map");
                pose.scan_sent_ns = sample.scan_sent_ns;
                pose.best = estimate.best.into();
                pose.mean = estimate.mean.into();
                pose.dead_reckoning = dead_reckoning;
                for r in 0..3 {
                    for c in 0..3 {
                        pose.covariance[r * 3 + c] = estimate.covariance[(r, c)];
                    }
                }
                pose.effective_particles = estimate.effective_particles;
                pose.particle_count = estimate.particle_count as u32;
                pose.map_corners = estimate.map_size as u32;
                pose.timing = StageTiming {
                    motion_ns: estimate.timing.motion_ns,
                    predict_ns: estimate.timing.predict_ns,
                    update_ns: estimate.timing.update_ns,
                    resample_ns: estimate.timing.resample_ns,
                    total_ns: estimate.timing.total_ns,
                };
            })?;
            last_header = header;
            processed += 1;
            if processed.is_multiple_of(args.map_every) {
                left_out = left_out.max(publish_map(&maps, &slam, header)?);
            }
        }
    }
    // Stopped by a signal: leave the map and the path as far as they got.
    left_out = left_out.max(publish_map(&maps, &slam, last_header)?);
    publish_path(&path, &slam, last_header)?;
    say_err(&format!("slam-proc: stopped after {processed} scans"));
    say_err(&summary(&slam.stats()));
    ipc_types::losses::report(&[("map_corners_not_published", left_out)]);
    Ok(())
}

/// The closing summary block (launch shows it on the console at the end of a run).
fn summary(stats: &FilterStats) -> String {
    format!(
        "slam-proc: summary of the filter\n  \
         scans:           {} ({} updated the particles with their corners)\n  \
         resamplings:     {}\n  \
         loops closed:    {} by revisits of the best particle\n  \
         map:             {} corners",
        stats.scans, stats.updates, stats.resamplings, stats.loops_closed, stats.map_corners,
    )
}

/// Publishes the best particle's map; returns how many corners did not fit the message.
fn publish_map(maps: &Outlet<MapSnapshot>, slam: &FastSlam, header: Header) -> Result<u64> {
    let corners: Vec<MapCorner> = slam
        .best_map()
        .iter()
        .map(|&c| MapCorner::from(c))
        .collect();
    let keep = corners.len().min(ipc_types::MAX_MAP_CORNERS);
    if keep < corners.len() {
        say_err(&format!(
            "slam-proc: the map has {} corners; publishing {keep}",
            corners.len()
        ));
    }
    maps.publish(|message| {
        message.header = header;
        message.header.set_frame_id("map");
        // Cut to capacity above, so this cannot fail.
        let _ = message.set(&corners[..keep]);
    })?;
    Ok((corners.len() - keep) as u64)
}

/// The best particle's whole path, in chunks numbered from 0.
fn publish_path(outlet: &Outlet<PathChunk>, slam: &FastSlam, last: Header) -> Result<()> {
    let path: Vec<StampedPose> = slam
        .best_path()
        .iter()
        .map(|p| StampedPose {
            stamp_ns: p.stamp_ns,
            pose: p.pose.into(),
        })
        .collect();
    let total = path.len() as u64;
    for (index, chunk) in path.chunks(ipc_types::MAX_PATH_CHUNK_POSES).enumerate() {
        outlet.publish(|message| {
            message.header = Header::new(index as u64, last.stamp_ns, "map");
            message.first = (index * ipc_types::MAX_PATH_CHUNK_POSES) as u64;
            message.total = total;
            // Chunks are cut to the capacity, so this cannot fail.
            let _ = message.set(chunk);
        })?;
    }
    Ok(())
}

fn to_observation(corner: &Corner) -> Observation {
    Observation {
        x: corner.x,
        y: corner.y,
        heading: corner.heading,
        angle: corner.angle,
        covariance: nalgebra::Matrix4::from_row_slice(&corner.covariance),
    }
}

fn to_line(line: &Line) -> LineObservation {
    LineObservation {
        rho: line.rho,
        theta: line.theta,
        covariance: nalgebra::Matrix2::from_row_slice(&line.covariance),
    }
}

fn to_motion(motion: &ScanMotion) -> MeasuredMotion {
    MeasuredMotion {
        increment: motion.increment.into(),
        covariance: nalgebra::Matrix3::from_row_slice(&motion.increment_covariance),
    }
}

fn to_odometry(odometry: OdometryAtScan) -> OdometryInput {
    OdometryInput {
        pose: odometry.pose.into(),
        covariance: nalgebra::Matrix3::from_row_slice(&odometry.covariance),
    }
}
