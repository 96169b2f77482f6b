//! `lidar-replay`: publishes a recorded lidar log on a domain's scan topic (and its odometry
//! on the odometry topic) as a live driver would.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::prelude::*;
use lidar_replay::reorder::{DEFAULT_REORDER_CAP, DEFAULT_REORDER_WINDOW_NS};
use lidar_replay::{
    LOG_ODOMETRY_NOISE, LogFormat, LogRecord, OdometryCovariance, OpenError, Pacer, ReadError,
    Records, ReorderConfig, ReplaySummary, fill_odometry, fill_scan, open_log_until,
};
use stage_kit::{say, say_err};

/// Replays a recorded lidar log onto the pipeline: LaserScan on the scan topic and, where the
/// log has it, Odometry (published before the scan it goes with, with the same stamp).
///
/// Stamps are the log's own at full precision; seed-csv has none and is stamped every 0.1 s
/// from 0. A CARMEN log's records are put in time order within --reorder-window; what comes
/// later than that, or repeats a stamp, is dropped. Malformed lines are reported with their
/// line numbers and skipped; a file that is not of the format is refused. The replay ends
/// with a summary of everything not published, and why.
#[derive(Debug, Parser)]
#[command(name = "lidar-replay", version)]
struct Args {
    /// Log format: seed-csv (seed-hall scans.csv) or carmen (FLASER, ROBOTLASER1, ODOM).
    #[arg(long)]
    format: LogFormat,
    /// The log file.
    #[arg(long, value_name = "FILE")]
    file: PathBuf,
    /// Speed against the log's own timing (0.001 to 1000): 1 = as recorded, 2 = twice as
    /// fast; 0 = lockstep: each message waits until every subscriber has taken the previous
    /// one, nothing is lost.
    #[arg(long, default_value_t = 0.0, value_parser = lidar_replay::parse_rate)]
    rate: f64,
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// Scan subscribers to wait for before streaming (lockstep loses nothing at start).
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
    /// Do not publish the log's odometry.
    #[arg(long)]
    no_odometry: bool,
    /// Scans to publish; 0 = the whole log.
    #[arg(long, default_value_t = 0)]
    frames: u64,
    /// Log time (seconds) a record waits for older ones read after it (CARMEN logs that go
    /// back in time); records later than that are dropped. 0 = nothing may go back further
    /// than behind the newest record.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_REORDER_WINDOW_NS as f64 * 1e-9)]
    reorder_window: f64,
    /// Log lines held at most while reordering; beyond it the oldest goes out early.
    #[arg(long, value_name = "LINES", default_value_t = DEFAULT_REORDER_CAP)]
    reorder_cap: usize,
}

/// A real-time source does not wait long for its subscribers, as a live sensor would not.
const REAL_TIME_SUBSCRIBER_WAIT: Duration = Duration::from_secs(10);
/// How long the first odometry waits for a subscriber. feature-proc looks for the odometry
/// topic once it has found the scans, which may be after the first odometry is due; without
/// this wait the first readings would be lost, and which ones would depend on timing.
const ODOMETRY_SUBSCRIBER_WAIT: Duration = Duration::from_secs(5);
/// Malformed lines reported one by one; the rest are only counted.
const REPORTED_LINES: u64 = 100;

fn main() -> ExitCode {
    stage_kit::main("lidar-replay", run)
}

fn run() -> Result<()> {
    let args = Args::parse();
    // An hour is far beyond any log's disorder, and keeps the nanoseconds within u64.
    anyhow::ensure!(
        args.reorder_window.is_finite() && (0.0..=3600.0).contains(&args.reorder_window),
        "--reorder-window must be between 0 and 3600 seconds, not {}",
        args.reorder_window
    );
    let reorder = ReorderConfig {
        window_ns: (args.reorder_window * 1e9).round() as u64,
        max_held: args.reorder_cap,
    };
    shutdown::install().context("cannot install the Ctrl-C handler")?;
    // Refuse a file that is not of the format before anyone sees a port.
    let mut log = match open_log_until(args.format, &args.file, reorder, shutdown::requested) {
        Ok(log) => log,
        // Ctrl-C is how a user ends a replay, before its first scan as after it.
        Err(e @ OpenError::Stopped { .. }) => {
            say_err(&format!("lidar-replay: {e}"));
            return Ok(());
        }
        Err(e) => return Err(e.into()),
    };

    let mut pacer = Pacer::new(args.rate);
    let delivery = if pacer.is_lockstep() {
        Delivery::Lossless
    } else {
        Delivery::Latest
    };
    let domain = Domain::new(&args.domain)?;
    let node = domain.node("lidar-replay")?;
    // Consumers look for the scan topic and then for the rest, so the rest comes first.
    let odometry = if args.format.can_have_odometry() && !args.no_odometry {
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
    let scans = Outlet::create(&domain, &node, topic::SCAN, delivery, 0)?;
    say("ready");

    let wait = (!pacer.is_lockstep()).then_some(REAL_TIME_SUBSCRIBER_WAIT);
    scans.wait_for_subscribers(args.subscribers, wait)?;

    let mut published = 0u64;
    let mut odometry_published = 0u64;
    let mut odometry_waited = false;
    let mut odometry_covariance = OdometryCovariance::new(LOG_ODOMETRY_NOISE);
    let mut summary = ReplaySummary {
        file: args.file.display().to_string(),
        ..ReplaySummary::default()
    };
    let mut last_stamp = 0;
    for record in log.by_ref() {
        if shutdown::requested() {
            break;
        }
        if args.frames > 0 && published == args.frames {
            summary.stopped = Some(format!("--frames {} reached", args.frames));
            break;
        }
        let record = match record {
            Ok(record) => record,
            Err(ReadError::Line(e)) => {
                summary.malformed_line(&e);
                let malformed = summary.malformed_total();
                if malformed <= REPORTED_LINES {
                    say_err(&format!(
                        "lidar-replay: {}: {e} (skipped)",
                        args.file.display()
                    ));
                }
                if malformed == REPORTED_LINES {
                    say_err("lidar-replay: further malformed lines are only counted");
                }
                continue;
            }
            Err(ReadError::Stopped) => break,
            Err(e @ ReadError::Io(_)) => {
                return Err(e).with_context(|| format!("{}", args.file.display()));
            }
        };
        match record {
            LogRecord::Odometry(pose) => {
                let Some(outlet) = &odometry else {
                    summary.odometry_unpublished += 1;
                    continue;
                };
                if !odometry_waited {
                    odometry_waited = true;
                    if !outlet.wait_for_subscribers(1, Some(ODOMETRY_SUBSCRIBER_WAIT))? {
                        say_err(&format!(
                            "lidar-replay: nobody subscribed to the odometry within {} s; \
                             publishing it anyway",
                            ODOMETRY_SUBSCRIBER_WAIT.as_secs()
                        ));
                    }
                }
                if !sleep_until(pacer.due(pose.stamp_ns, Instant::now())) {
                    break;
                }
                let covariance = odometry_covariance.update(&pose);
                outlet.publish(|message| fill_odometry(message, published, &pose, covariance))?;
                odometry_published += 1;
            }
            LogRecord::Scan(scan) => {
                if !sleep_until(pacer.due(scan.stamp_ns, Instant::now())) {
                    break;
                }
                let mut fill_error = None;
                scans.publish(|message| fill_error = fill_scan(message, published, &scan).err())?;
                if let Some(e) = fill_error {
                    anyhow::bail!("line {}: {e}", scan.line);
                }
                last_stamp = scan.stamp_ns;
                published += 1;
            }
        }
    }
    let interrupted = shutdown::requested();
    if interrupted {
        summary.stopped = Some(format!("interrupted after {published} scans"));
    } else {
        // The odometry's end first: a consumer that sees the scans' end has all of it, and
        // scans waiting for odometry after their stamp know that none will come.
        if let Some(outlet) = &odometry {
            outlet.publish_end_of_stream(odometry_published, last_stamp)?;
        }
        scans.publish_end_of_stream(published, last_stamp)?;
    }
    summary.lines_read = log.line_number();
    summary.published = Records {
        scans: published,
        odometry: odometry_published,
    };
    summary.reordering = log.reordering();
    summary.not_replayed = log.skipped_records();
    // One block at the very end, so slam-launch can show it whole (see SUMMARY_HEAD).
    say_err(&summary.to_string());
    ipc_types::losses::report(&summary.losses());
    Ok(())
}

/// Sleeps until `due` (at once when `None` or past). Returns false when Ctrl-C came first.
fn sleep_until(due: Option<Instant>) -> bool {
    match due {
        // Sliced, so a long wait (a slow rate, a gap in the log) does not hold up Ctrl-C.
        Some(due) => shutdown::sleep_until(due),
        None => !shutdown::requested(),
    }
}
