//! `lidar-sim`: a simulated Hokuyo UTM-30LX-class lidar driving through a world, publishing
//! scans, ground truth, the world's true corners and optionally noisy odometry.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::prelude::*;
use lidar_sim::{SensorConfig, Simulation, VehicleConfig, World};
use serde::Deserialize;
use stage_kit::{say, say_err};

/// What `--config` may set: the sensor and the vehicle (every field optional).
#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct SimFileConfig {
    sensor: SensorConfig,
    vehicle: VehicleConfig,
}

/// Simulated 2D lidar with ground truth, on the shared-memory scan topic of a domain.
#[derive(Debug, Parser)]
#[command(name = "lidar-sim", version)]
struct Args {
    /// hall, office, corridor, or a world file: {"walls": [[[x, y], ...], ...],
    /// "waypoints": [[x, y], ...], "speed": 1.0}
    #[arg(long, default_value = "office")]
    world: String,
    /// Scans to publish; 0 = until the end of the path.
    #[arg(long, default_value_t = 0)]
    frames: u64,
    /// Scans per second (0.001 to 1000); 0 = lockstep: each scan is sent only when every
    /// subscriber has taken the previous one, so nothing is lost and a run repeats exactly
    /// for its seed.
    #[arg(long, default_value_t = 0.0, value_parser = lidar_sim::parse_rate)]
    rate: f64,
    /// Seed of the sensor and odometry noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// Scan subscribers to wait for before streaming (lockstep loses nothing at start).
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
    /// Publish noisy wheel odometry as well.
    #[arg(long)]
    odometry: bool,
    /// TOML file with sensor and vehicle settings.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

fn main() -> ExitCode {
    stage_kit::main("lidar-sim", run)
}

fn run() -> Result<()> {
    let args = Args::parse();
    shutdown::install().context("cannot install the Ctrl-C handler")?;
    let settings: SimFileConfig = stage_kit::settings::load(args.config.as_deref())?;
    let world = World::resolve(&args.world).with_context(|| format!("world '{}'", args.world))?;
    let true_corners: Vec<TrueCorner> = world
        .true_corners()
        .iter()
        .map(|&c| TrueCorner::from(c))
        .collect();
    let sensor = settings.sensor.clone();
    let geometry = sensor.scan_geometry();
    let odometry_noise = settings.vehicle.odometry.clone();
    let mut sim = Simulation::new(world, settings.sensor, settings.vehicle, args.seed)?;

    let delivery = if args.rate == 0.0 {
        Delivery::Lossless
    } else {
        Delivery::Latest
    };
    let domain = Domain::new(&args.domain)?;
    let node = domain.node("lidar-sim")?;
    // Everything a subscriber of the scans may want is created before the scan topic, so a
    // process that has found the scans finds the rest too.
    let truth = Outlet::create(&domain, &node, topic::GROUND_TRUTH, delivery, 0)?;
    let corners = Outlet::create(&domain, &node, topic::WORLD_CORNERS, delivery, 1)?;
    let odometry = if args.odometry {
        Some(Outlet::create(
            &domain,
            &node,
            topic::ODOMETRY,
            delivery,
            0,
        )?)
    } else {
        None
    };
    // A message holds MAX_WORLD_CORNERS; the rest are not scored.
    let corners_left_out = true_corners
        .len()
        .saturating_sub(ipc_types::MAX_WORLD_CORNERS) as u64;
    let losses = [("world_corners_not_published", corners_left_out)];
    corners.publish(|message| {
        message.header = Header::new(0, 0, "map");
        if let Err(e) = message.set(&true_corners) {
            say_err(&format!(
                "lidar-sim: only part of the world's corners are published: {e}"
            ));
            let _ = message.set(&true_corners[..ipc_types::MAX_WORLD_CORNERS]);
        }
    })?;
    let scans = Outlet::create(&domain, &node, topic::SCAN, delivery, 0)?;
    say("ready");

    let wait = match delivery {
        Delivery::Lossless => None,
        // A live sensor does not wait for anyone for long.
        Delivery::Latest => Some(Duration::from_secs(10)),
    };
    scans.wait_for_subscribers(args.subscribers, wait)?;

    let period = (args.rate > 0.0).then(|| Duration::from_secs_f64(1.0 / args.rate));
    let start = Instant::now();
    let mut published = 0u64;
    let mut last_stamp = 0;
    // Odometry's covariance grows with the distance and turn it has integrated.
    let mut odometry_variance = [0.0f64; 3];
    let mut last_odometry: Option<lidar_sim::Pose2> = None;
    while args.frames == 0 || published < args.frames {
        if shutdown::requested() {
            break;
        }
        let Some(frame) = sim.next_frame() else {
            break;
        };
        if let Some(period) = period {
            // A slow rate means long waits: sliced, so Ctrl-C is not held up by them.
            let due = start + period.mul_f64(published as f64);
            if !shutdown::sleep_until(due) {
                break;
            }
        }
        let header = Header::new(frame.seq, frame.stamp_ns, "laser");
        truth.publish(|message| {
            message.header = header;
            message.header.set_frame_id("map");
            message.pose = frame.pose.into();
        })?;
        if let Some(odometry) = &odometry {
            if let Some(last) = last_odometry {
                let step = (frame.odometry.x - last.x).hypot(frame.odometry.y - last.y);
                let turn = lidar_sim::wrap_angle(frame.odometry.yaw - last.yaw).abs();
                odometry_variance[0] += odometry_noise.sigma_forward.powi(2) * step;
                odometry_variance[1] += odometry_noise.sigma_lateral.powi(2) * step;
                odometry_variance[2] += odometry_noise.sigma_yaw_per_m.powi(2) * step
                    + odometry_noise.sigma_yaw_per_rad.powi(2) * turn;
            }
            last_odometry = Some(frame.odometry);
            let position_variance = odometry_variance[0] + odometry_variance[1];
            odometry.publish(|message| {
                message.header = header;
                message.header.set_frame_id("odom");
                message.pose = frame.odometry.into();
                message.covariance[0] = position_variance;
                message.covariance[4] = position_variance;
                message.covariance[8] = odometry_variance[2];
                message.linear_velocity = frame.linear_velocity;
                message.angular_velocity = frame.angular_velocity;
            })?;
        }
        let mut fill_error = None;
        scans.publish(|scan| {
            scan.header = header;
            scan.set_geometry(&geometry);
            fill_error = scan.set_beams(&frame.ranges, &[]).err();
        })?;
        if let Some(e) = fill_error {
            anyhow::bail!("scan {}: {e}", frame.seq);
        }
        // Hand the world's corners to subscribers that connected late.
        corners.update_connections()?;
        last_stamp = frame.stamp_ns;
        published += 1;
    }
    if shutdown::requested() {
        say_err(&format!("lidar-sim: stopped after {published} scans"));
        ipc_types::losses::report(&losses);
        return Ok(());
    }
    // The odometry's end first: a consumer that sees the scans' end has all of it.
    if let Some(odometry) = &odometry {
        odometry.publish_end_of_stream(published, last_stamp)?;
    }
    scans.publish_end_of_stream(published, last_stamp)?;
    say_err(&format!("lidar-sim: published {published} scans"));
    ipc_types::losses::report(&losses);
    Ok(())
}
