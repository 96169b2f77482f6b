//! `lidar-hokuyo`: publishes the scans of a Hokuyo Ethernet lidar (SCIP 2.0 over TCP) on the
//! scan topic of a domain, in real time.

use std::io::Write;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::prelude::*;
use lidar_hokuyo::{
    ConnectionNotices, Driver, DriverConfig, DriverStats, Finish, ScanRequest, TcpConnector,
};
use stage_kit::{SourceArgs, say, say_err, shutdown};

/// Live Hokuyo lidar (UTM-30LX-EW, UST-10LX/20LX, ...) on the shared-memory scan topic.
#[derive(Debug, Parser)]
#[command(name = "lidar-hokuyo", version)]
struct Args {
    /// HOST:PORT of the sensor.
    #[arg(long, default_value = "192.168.0.10:10940")]
    addr: String,
    #[command(flatten)]
    source: SourceArgs,
    /// First bearing to measure, radians (x forward, counter-clockwise); default: the
    /// sensor's first step.
    #[arg(long, allow_negative_numbers = true)]
    min_angle: Option<f64>,
    /// Last bearing to measure, radians; default: the sensor's last step.
    #[arg(long, allow_negative_numbers = true)]
    max_angle: Option<f64>,
    /// Adjacent steps merged into one beam (1 to 99); the sensor reports the shortest.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=99))]
    cluster: u8,
    /// Ask for intensities too (ME instead of MD). Takes an optional true/false.
    #[arg(
        long,
        num_args = 0..=1,
        default_value_t = false,
        default_missing_value = "true",
        action = clap::ArgAction::Set
    )]
    intensities: bool,
    /// Scans to publish before stopping; 0 = until Ctrl-C.
    #[arg(long, default_value_t = 0)]
    frames: u64,
    /// frame_id of the scans.
    #[arg(long, default_value = "laser")]
    frame_id: String,
}

fn main() -> ExitCode {
    stage_kit::run_stage("lidar-hokuyo", run)
}

fn run(args: Args) -> Result<()> {
    // A typo in the address would otherwise be retried for ever, quietly.
    lidar_hokuyo::resolve(&args.addr).context("--addr")?;
    let config = DriverConfig {
        request: ScanRequest {
            min_angle: args.min_angle,
            max_angle: args.max_angle,
            cluster: args.cluster,
            intensities: args.intensities,
        },
        frames: (args.frames > 0).then_some(args.frames),
        frame_id: args.frame_id.clone(),
        ..DriverConfig::default()
    };

    let domain = Domain::new(&args.source.domain)?;
    let node = domain.node("lidar-hokuyo")?;
    // A live sensor never waits for a slow subscriber: the oldest scans are dropped instead.
    let mut scans = Outlet::create(&domain, &node, topic::SCAN, Delivery::Latest, 0)?;
    say("ready");
    std::io::stdout()
        .flush()
        .context("cannot write to stdout")?;
    let wait = SourceArgs::REAL_TIME_WAIT;
    match scans.wait_for_subscribers(args.source.subscribers, Some(wait)) {
        Ok(true) => {}
        Ok(false) => say_err(&format!(
            "lidar-hokuyo: fewer than {} subscribers after {} s; starting anyway",
            args.source.subscribers,
            wait.as_secs()
        )),
        Err(_) if shutdown::requested() => return Ok(()),
        Err(e) => return Err(e.into()),
    }

    // Reads time out every 100 ms so Ctrl-C is noticed while the sensor is quiet.
    let mut connector = TcpConnector::new(
        &args.addr,
        Duration::from_secs(2),
        Duration::from_millis(100),
    );
    let clock = now_ns;
    let mut driver = Driver {
        config: &config,
        connector: &mut connector,
        sink: &mut scans,
        stop: shutdown::requested,
        clock: &clock,
        stats: DriverStats::default(),
        notices: ConnectionNotices::default(),
    };
    let finish = driver.run()?;
    let stats = driver.stats;
    let notices = driver.notices;
    // The stream ends either way, so the stages after us finish their work and write.
    if let Err(e) = scans.publish_end_of_stream(stats.published, stats.last_stamp_ns) {
        say_err(&format!(
            "lidar-hokuyo: cannot publish the end of the stream: {e}"
        ));
    }
    let how = match finish {
        Finish::Frames => "done",
        Finish::Stopped => "stopped",
    };
    say_err(&format!(
        "lidar-hokuyo: {how}: published {} scans, dropped {} damaged scans, {} connections",
        stats.published, stats.damaged, stats.connections
    ));
    ipc_types::losses::report(&[("damaged_scans", stats.damaged)]);
    // A live source that never delivered has failed, however it was stopped.
    if stats.published == 0 {
        let why = match notices.last_problem() {
            Some(problem) => format!(
                "{} failed attempts; the last: {problem}",
                notices.failed_total()
            ),
            None => "stopped before the first".to_owned(),
        };
        anyhow::bail!("no scan arrived from {} ({why})", args.addr);
    }
    Ok(())
}
