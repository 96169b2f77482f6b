//! `lidar-sim`: a simulated Hokuyo UTM-30LX-class lidar driving through a world, publishing
//! scans, ground truth, the world's true corners and optionally noisy odometry.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::prelude::*;
use lidar_sim::{Laps, SimSettings, Simulation, World};
use stage_kit::odometry_covariance::OdometryCovariance;
use stage_kit::pacing::Pacer;
use stage_kit::{SourceArgs, say, say_err, shutdown};

/// Simulated 2D lidar with ground truth, on the shared-memory scan topic of a domain.
#[derive(Debug, Parser)]
#[command(name = "lidar-sim", version)]
struct Args {
    /// hall, office, corridor, or a world file: {"walls": [[[x, y], ...], ...],
    /// "waypoints": [[x, y], ...], "speed": 1.0}
    #[arg(long, default_value = "office")]
    world: String,
    /// Scans to publish; 0 = until the end of the path's last lap.
    #[arg(long, default_value_t = 0)]
    frames: u64,
    /// Times to drive the world's route in a row (1 to 1000): a route that ends where it
    /// starts is driven round again, any other back and forth along itself.
    #[arg(long, value_name = "N", default_value = "1", value_parser = lidar_sim::parse_laps)]
    laps: Laps,
    /// Scans per second (0.001 to 1000); 0 = lockstep: each scan is sent only when every
    /// subscriber has taken the previous one, so nothing is lost and a run repeats exactly
    /// for its seed.
    #[arg(long, default_value_t = 0.0, value_parser = lidar_sim::parse_rate)]
    rate: f64,
    /// Seed of the sensor and odometry noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    source: SourceArgs,
    /// Publish noisy wheel odometry as well.
    #[arg(long)]
    odometry: bool,
    /// TOML file with sensor and vehicle settings.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

fn main() -> ExitCode {
    stage_kit::run_stage("lidar-sim", run)
}

fn run(args: Args) -> Result<()> {
    let settings: SimSettings = stage_kit::settings::load(args.config.as_deref())?;
    let world = World::resolve(&args.world).with_context(|| format!("world '{}'", args.world))?;
    let true_corners: Vec<TrueCorner> = world
        .true_corners()
        .iter()
        .map(|&c| TrueCorner::from(c))
        .collect();
    let sensor = settings.sensor.clone();
    let geometry = sensor.scan_geometry();
    let mut odometry_covariance = OdometryCovariance::new(settings.vehicle.odometry.noise());
    let mut sim = Simulation::with_laps(
        world,
        settings.sensor,
        settings.vehicle,
        args.seed,
        args.laps,
    )?;

    let delivery = if args.rate == 0.0 {
        Delivery::Lossless
    } else {
        Delivery::Latest
    };
    let domain = Domain::new(&args.source.domain)?;
    let node = domain.node("lidar-sim")?;
    // Everything a subscriber of the scans may want is created before the scan topic, so a
    // process that has found the scans finds the rest too.
    let truth = Outlet::create(&domain, &node, topic::GROUND_TRUTH, delivery, 0)?;
    let corners = Outlet::create(&domain, &node, topic::WORLD_CORNERS, delivery, 1)?;
    let odometry = args
        .odometry
        .then(|| Outlet::create(&domain, &node, topic::ODOMETRY, delivery, 0))
        .transpose()?;
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

    let wait = SourceArgs::subscriber_wait(delivery == Delivery::Lossless);
    scans.wait_for_subscribers(args.source.subscribers, wait)?;
    // Its readers look for the odometry once they have found the scans: in lockstep none
    // may miss the first readings.
    if let Some(odometry) = &odometry {
        odometry.wait_for_subscribers(args.source.odometry_subscribers, wait)?;
    }

    let mut pacer = Pacer::new(args.rate);
    let mut published = 0u64;
    let mut last_stamp = 0;
    while args.frames == 0 || published < args.frames {
        if shutdown::requested() {
            break;
        }
        let Some(frame) = sim.next_frame() else {
            break;
        };
        // A slow rate means long waits: sliced, so Ctrl-C is not held up by them.
        if !pacer.wait(Pacer::nth(published), shutdown::requested) {
            break;
        }
        let header = Header::new(frame.seq, frame.stamp_ns, "laser");
        truth.publish(|message| {
            message.header = header;
            message.header.set_frame_id("map");
            message.pose = frame.pose.into();
        })?;
        if let Some(odometry) = &odometry {
            // Grows with the distance and turn the odometry has integrated.
            let covariance = odometry_covariance.update(frame.odometry);
            odometry.publish(|message| {
                message.header = header;
                message.header.set_frame_id("odom");
                message.pose = frame.odometry.into();
                message.covariance = covariance;
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
