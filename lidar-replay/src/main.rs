//! `lidar-replay`: publishes a recorded lidar log on a domain's scan topic (and its odometry
//! on the odometry topic) as a live driver would.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;
use iceoryx2::prelude::{Node, ipc};
use ipc_types::prelude::*;
use lidar_replay::reorder::{DEFAULT_REORDER_CAP, DEFAULT_REORDER_WINDOW_NS};
use lidar_replay::rosbag::{BagError, BagOptions};
use lidar_replay::{
    Degradation, LOG_ODOMETRY_NOISE, LogFormat, LogRecord, OdometryCovariance, OpenError,
    ReadError, Records, ReorderConfig, ReplaySummary, fill_odometry, fill_scan, open_bag_until,
    open_log_until,
};
use recorder::Recorded;
use stage_kit::pacing::Pacer;
use stage_kit::{SourceArgs, say, say_err, shutdown};

/// Replays a recorded lidar log onto the pipeline: LaserScan on the scan topic and, where the
/// log has it, Odometry (published before the scan it goes with, with the same stamp).
///
/// Stamps are the log's own at full precision; seed-csv has none and is stamped every 0.1 s
/// from 0. A CARMEN log's records are put in time order within --reorder-window; what comes
/// later than that, or repeats a stamp, is dropped. When its scans show that the log has
/// them in the order they were taken, some stamped late, they keep that order and the late
/// ones are re-stamped, their own stamps carried along for the results. Malformed lines are reported with their
/// line numbers and skipped; a file that is not of the format is refused. The replay ends
/// with a summary of everything not published, and why.
///
/// mcap replays the run.mcap of slam-record: its scans and odometry exactly as they were
/// published, with their original stamps, sequence numbers and frames.
///
/// rosbag2 replays a ROS 2 bag (a bag directory with metadata.yaml and MCAP or SQLite3
/// files, or a bare .mcap or .db3): sensor_msgs/msg/LaserScan of --scan-topic, odometry
/// from nav_msgs/msg/Odometry or /tf interpolated to each scan's stamp, the laser's mount
/// from /tf_static, so that trajectories are base_link's.
#[derive(Debug, Parser)]
#[command(name = "lidar-replay", version)]
struct Args {
    /// Log format: seed-csv (seed-hall scans.csv), carmen (FLASER, ROBOTLASER1, ODOM), mcap
    /// (a run.mcap of slam-record) or rosbag2 (a ROS 2 bag). Default: told from the file (a
    /// directory, .db3 or a .mcap of ROS 2 messages: rosbag2; another .mcap: mcap; .clf:
    /// carmen; .csv: seed-csv).
    #[arg(long)]
    format: Option<LogFormat>,
    /// The log file (or a bag's directory).
    #[arg(long, value_name = "FILE")]
    file: PathBuf,
    /// rosbag2: the sensor_msgs/msg/LaserScan topic to replay (default: the bag's only one).
    #[arg(long, value_name = "TOPIC")]
    scan_topic: Option<String>,
    /// rosbag2: where the odometry comes from: odom (nav_msgs/msg/Odometry), tf (/tf, the
    /// odom frame to the base frame) or auto (the Odometry topic if the bag has one, else
    /// /tf).
    #[arg(long, value_name = "SOURCE", default_value = "auto")]
    odom_source: lidar_replay::rosbag::OdometryFrom,
    /// rosbag2: the nav_msgs/msg/Odometry topic (default: the bag's only one).
    #[arg(long, value_name = "TOPIC")]
    odom_topic: Option<String>,
    /// rosbag2: the robot's frame (REP 105): the odometry's child frame and the parent of
    /// the laser's mount on /tf_static.
    #[arg(long, value_name = "FRAME", default_value = "base_link")]
    base_frame: String,
    /// rosbag2: the odometry's frame, for --odom-source tf.
    #[arg(long, value_name = "FRAME", default_value = "odom")]
    odom_frame: String,
    /// Speed against the log's own timing (0.001 to 1000): 1 = as recorded, 2 = twice as
    /// fast; 0 = lockstep: each message waits until every subscriber has taken the previous
    /// one, nothing is lost.
    #[arg(long, default_value_t = 0.0, value_parser = lidar_replay::parse_rate)]
    rate: f64,
    #[command(flatten)]
    source: SourceArgs,
    /// Do not publish the log's odometry.
    #[arg(long)]
    no_odometry: bool,
    /// Scans to publish; 0 = the whole log.
    #[arg(long, default_value_t = 0)]
    frames: u64,
    /// Start at this scan of the log (from 0): the scans before it and their odometry are
    /// not published, but for the last odometry reading before it. Sequence numbers start
    /// at 0 at that scan; stamps stay the log's.
    #[arg(long, value_name = "SCANS", default_value_t = 0)]
    skip: u64,
    /// Publish the first scan (after --skip) and every N-th after it, all the odometry: a
    /// harder version of the log, as from a slower sensor. Sequence numbers stay
    /// consecutive.
    #[arg(long, value_name = "N", default_value_t = 1)]
    every: u64,
    /// Make ranges beyond this many metres no-returns, as from a shorter-range sensor.
    #[arg(long, value_name = "METRES")]
    max_range: Option<f64>,
    /// Log time (seconds) a record waits for older ones read after it (CARMEN logs that go
    /// back in time); records later than that are dropped. 0 = nothing may go back further
    /// than behind the newest record.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_REORDER_WINDOW_NS as f64 * 1e-9)]
    reorder_window: f64,
    /// Log lines held at most while reordering; beyond it the oldest goes out early.
    #[arg(long, value_name = "LINES", default_value_t = DEFAULT_REORDER_CAP)]
    reorder_cap: usize,
}

/// Malformed lines reported one by one; the rest are only counted.
const REPORTED_LINES: u64 = 100;

fn main() -> ExitCode {
    stage_kit::run_stage("lidar-replay", run)
}

fn run(args: Args) -> Result<()> {
    let format = match args.format {
        Some(format) => format,
        None => LogFormat::detect(&args.file).with_context(|| {
            format!(
                "cannot tell the format of {} from its name: give --format (seed-csv, \
                 carmen, mcap or rosbag2)",
                args.file.display()
            )
        })?,
    };
    match format {
        LogFormat::Mcap => replay_recording(&args),
        LogFormat::SeedCsv | LogFormat::Carmen | LogFormat::Rosbag => replay_log(&args, format),
    }
}

/// The replay's outlets and what went out on them.
struct Streams {
    scans: Outlet<LaserScan>,
    odometry: Option<Outlet<Odometry>>,
    /// The odometry's readers, waited for before the first reading goes out: they look for
    /// the odometry once they have found the scans, which may be after the first reading is
    /// due, and without the wait they would miss it (which ones, would depend on timing).
    odometry_subscribers: usize,
    odometry_waited: bool,
    pacer: Pacer,
    /// Scans published.
    published: u64,
    odometry_published: u64,
    last_stamp: u64,
    // The outlets' node and domain live as long as they do.
    _node: Node<ipc::Service>,
    _domain: Domain,
}

impl Streams {
    /// Creates the topics, odometry first (consumers look for the scans and then for the
    /// rest), and waits for the scans' subscribers.
    fn open(args: &Args, odometry: bool) -> Result<Self> {
        let pacer = Pacer::new(args.rate);
        let delivery = if pacer.is_lockstep() {
            Delivery::Lossless
        } else {
            Delivery::Latest
        };
        let domain = Domain::new(&args.source.domain)?;
        let node = domain.node("lidar-replay")?;
        let odometry = odometry
            .then(|| Outlet::create(&domain, &node, topic::ODOMETRY, delivery, 0))
            .transpose()?;
        let scans = Outlet::create(&domain, &node, topic::SCAN, delivery, 0)?;
        say("ready");

        let wait = SourceArgs::subscriber_wait(pacer.is_lockstep());
        scans.wait_for_subscribers(args.source.subscribers, wait)?;
        Ok(Self {
            scans,
            odometry,
            odometry_subscribers: args.source.odometry_subscribers,
            odometry_waited: false,
            pacer,
            published: 0,
            odometry_published: 0,
            last_stamp: 0,
            _node: node,
            _domain: domain,
        })
    }

    /// Publishes an odometry message stamped `stamp_ns` when it is due. `Ok(false)` when
    /// Ctrl-C came first.
    fn odometry(&mut self, stamp_ns: u64, fill: impl FnOnce(&mut Odometry)) -> Result<bool> {
        let Some(outlet) = &self.odometry else {
            return Ok(true);
        };
        if !self.odometry_waited {
            self.odometry_waited = true;
            let wait = SourceArgs::subscriber_wait(self.pacer.is_lockstep());
            if !outlet.wait_for_subscribers(self.odometry_subscribers, wait)? {
                say_err(&format!(
                    "lidar-replay: fewer than {} odometry subscribers within {} s; \
                     publishing it anyway",
                    self.odometry_subscribers,
                    SourceArgs::REAL_TIME_WAIT.as_secs()
                ));
            }
        }
        // Sliced, so a long wait (a slow rate, a gap in the log) does not hold up Ctrl-C.
        if !self.pacer.wait(stamp_ns, shutdown::requested) {
            return Ok(false);
        }
        outlet.publish(fill)?;
        self.odometry_published += 1;
        Ok(true)
    }

    /// Publishes a scan stamped `stamp_ns` when it is due. `Ok(false)` when Ctrl-C came
    /// first.
    fn scan(&mut self, stamp_ns: u64, fill: impl FnOnce(&mut LaserScan)) -> Result<bool> {
        if !self.pacer.wait(stamp_ns, shutdown::requested) {
            return Ok(false);
        }
        self.scans.publish(fill)?;
        self.last_stamp = stamp_ns;
        self.published += 1;
        Ok(true)
    }

    /// Ends the streams: the odometry's end first, so a consumer that sees the scans' end
    /// has all of it, and scans waiting for odometry after their stamp know that none will
    /// come.
    fn end(&self) -> Result<()> {
        if let Some(outlet) = &self.odometry {
            outlet.publish_end_of_stream(self.odometry_published, self.last_stamp)?;
        }
        self.scans
            .publish_end_of_stream(self.published, self.last_stamp)?;
        Ok(())
    }

    /// Whether the replay stops before its next record: Ctrl-C, or `--frames` reached (said
    /// in the summary).
    fn stops_before_next(&self, args: &Args, summary: &mut ReplaySummary) -> bool {
        if shutdown::requested() {
            return true;
        }
        if args.frames > 0 && self.published == args.frames {
            summary.stopped = Some(format!("--frames {} reached", args.frames));
            return true;
        }
        false
    }

    fn published(&self) -> Records {
        Records {
            scans: self.published,
            odometry: self.odometry_published,
        }
    }
}

/// Replays a text log (seed-csv, CARMEN) or a ROS 2 bag.
fn replay_log(args: &Args, format: LogFormat) -> Result<()> {
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
    let degradation = Degradation::new(args.every, args.max_range)?;
    // Refuse a file that is not of the format before anyone sees a port.
    let opened = if format == LogFormat::Rosbag {
        let options = BagOptions {
            scan_topic: args.scan_topic.clone(),
            odometry: args.odom_source,
            odometry_topic: args.odom_topic.clone(),
            base_frame: args.base_frame.clone(),
            odom_frame: args.odom_frame.clone(),
            reorder,
        };
        match open_bag_until(&args.file, &options, shutdown::requested) {
            Ok((log, info)) => Ok((log, Some(info))),
            Err(e @ BagError::Stopped { .. }) => Err(e.to_string()),
            Err(e) => return Err(e.into()),
        }
    } else {
        match open_log_until(format, &args.file, reorder, shutdown::requested) {
            Ok(log) => Ok((log, None)),
            Err(e @ OpenError::Stopped { .. }) => Err(e.to_string()),
            Err(e) => return Err(e.into()),
        }
    };
    let (mut log, bag) = match opened {
        Ok(opened) => opened,
        // Ctrl-C is how a user ends a replay, before its first scan as after it.
        Err(stopped) => {
            say_err(&format!("lidar-replay: {stopped}"));
            return Ok(());
        }
    };
    for line in bag.iter().flat_map(|info| info.describe()) {
        say(&format!("lidar-replay: {line}"));
    }
    let odometry = match &bag {
        Some(info) => info.has_odometry(),
        None => format.can_have_odometry(),
    };
    if let Some(verdict) = log.odometry_verdict()
        && !args.no_odometry
    {
        say(&format!("lidar-replay: {}", verdict.describe()));
    }
    if let Some(order) = log.order_verdict().and_then(|verdict| verdict.describe()) {
        say(&format!("lidar-replay: {order}"));
    }
    let mut streams = Streams::open(args, odometry && !args.no_odometry)?;
    let mut odometry_covariance = OdometryCovariance::new(LOG_ODOMETRY_NOISE);
    let mut summary = ReplaySummary {
        file: args.file.display().to_string(),
        recording: log.reads_messages(),
        degradation,
        ..ReplaySummary::default()
    };
    let mut skipped = 0u64;
    // Scans of the log from the start (after --skip), published or left out.
    let mut scans_read = 0u64;
    // The newest odometry reading while skipping: it goes out before the first scan, so
    // that scan's stamp has a reading at or before it to pair with.
    let mut odometry_before_start = None;
    for record in log.by_ref() {
        if streams.stops_before_next(args, &mut summary) {
            break;
        }
        let record = match record {
            Ok(record) => record,
            Err(ReadError::Line(e)) => {
                summary.malformed_line(&e);
                report_malformed(&summary, &args.file, &e);
                continue;
            }
            Err(ReadError::Stopped) => break,
            Err(e @ ReadError::Cut { .. }) => {
                say_err(&format!("lidar-replay: {}: {e}", args.file.display()));
                summary.cut = Some(e.to_string());
                continue;
            }
            Err(e @ (ReadError::Io(_) | ReadError::NotText)) => {
                return Err(e).with_context(|| format!("{}", args.file.display()));
            }
        };
        if skipped < args.skip {
            match record {
                LogRecord::Scan(_) => skipped += 1,
                LogRecord::Odometry(pose) => odometry_before_start = Some(pose),
            }
            continue;
        }
        let records = match (odometry_before_start.take(), record) {
            (Some(before), record @ LogRecord::Scan(_)) => {
                vec![LogRecord::Odometry(before), record]
            }
            (_, record) => vec![record],
        };
        for record in records {
            let published = match record {
                LogRecord::Odometry(pose) => {
                    if streams.odometry.is_none() {
                        summary.odometry_unpublished += 1;
                        continue;
                    }
                    let seq = streams.published;
                    // The log's own covariance (a bag's) over the model's growth.
                    let mut covariance = odometry_covariance.update(pose.pose());
                    for (total, given) in covariance.iter_mut().zip(pose.log_covariance) {
                        *total += given;
                    }
                    streams.odometry(pose.stamp_ns, |message| {
                        fill_odometry(message, seq, &pose, covariance)
                    })?
                }
                LogRecord::Scan(mut scan) => {
                    scans_read += 1;
                    if !degradation.keeps(scans_read - 1) {
                        summary.scans_left_out += 1;
                        continue;
                    }
                    summary.beams_shortened += degradation.shorten(&mut scan);
                    let seq = streams.published;
                    let mut fill_error = None;
                    let published = streams.scan(scan.stamp_ns, |message| {
                        fill_error = fill_scan(message, seq, &scan).err();
                    })?;
                    if let Some(e) = fill_error {
                        anyhow::bail!("line {}: {e}", scan.line);
                    }
                    published
                }
            };
            // Ctrl-C: the outer loop sees the request and stops too.
            if !published {
                break;
            }
        }
    }
    anyhow::ensure!(
        shutdown::requested() || skipped == args.skip,
        "--skip {}: {} has only {skipped} scans",
        args.skip,
        args.file.display()
    );
    if args.skip > 0 {
        say_err(&format!(
            "lidar-replay: started at scan {} of the log (--skip)",
            args.skip
        ));
    }
    finish(&streams, &mut summary)?;
    summary.lines_read = log.line_number();
    summary.reordering = log.reordering();
    summary.not_replayed = log.skipped_records();
    report(&summary);
    Ok(())
}

/// Replays a recording of slam-record: its scans and odometry as they were published.
fn replay_recording(args: &Args) -> Result<()> {
    anyhow::ensure!(
        args.skip == 0,
        "--skip starts a text log part-way; a recording replays whole"
    );
    anyhow::ensure!(
        args.every == 1 && args.max_range.is_none(),
        "--every and --max-range make a harder version of a text log; a recording replays \
         as it was published"
    );
    // Refuse a file that is no recording before anyone sees a port.
    let (mut recording, info) = recorder::open_recording(&args.file)?;
    let mut streams = Streams::open(args, info.has_odometry && !args.no_odometry)?;
    let mut summary = ReplaySummary {
        file: args.file.display().to_string(),
        recording: true,
        ..ReplaySummary::default()
    };
    for next in recording.by_ref() {
        if streams.stops_before_next(args, &mut summary) {
            break;
        }
        let published = match next {
            Ok(Recorded::Scan(scan)) => {
                streams.scan(scan.header.stamp_ns, |message| *message = *scan)?
            }
            Ok(Recorded::Odometry(odometry)) => {
                if streams.odometry.is_none() {
                    summary.odometry_unpublished += 1;
                    continue;
                }
                streams.odometry(odometry.header.stamp_ns, |message| *message = *odometry)?
            }
            Err(
                e @ (recorder::ReadError::Message { .. } | recorder::ReadError::Channel { .. }),
            ) => {
                let error = lidar_replay::LineError::undecodable(&e);
                summary.malformed_line(&error);
                report_malformed(&summary, &args.file, &error);
                continue;
            }
            Err(e @ recorder::ReadError::Cut { .. }) => {
                say_err(&format!("lidar-replay: {}: {e}", args.file.display()));
                summary.cut = Some(e.to_string());
                break;
            }
        };
        if !published {
            break;
        }
    }
    finish(&streams, &mut summary)?;
    summary.lines_read = recording.messages_read();
    summary.not_replayed = recording
        .passed_over()
        .iter()
        .map(|(topic, count)| (topic.clone(), *count))
        .collect();
    report(&summary);
    Ok(())
}

/// Says why a line (a message) was skipped, for the first [`REPORTED_LINES`].
fn report_malformed(summary: &ReplaySummary, file: &std::path::Path, e: &lidar_replay::LineError) {
    let malformed = summary.malformed_total();
    if malformed <= REPORTED_LINES {
        say_err(&format!("lidar-replay: {}: {e} (skipped)", file.display()));
    }
    if malformed == REPORTED_LINES {
        say_err("lidar-replay: further malformed lines are only counted");
    }
}

/// Ends the streams unless Ctrl-C stopped the replay, and notes what was published.
fn finish(streams: &Streams, summary: &mut ReplaySummary) -> Result<()> {
    if shutdown::requested() {
        summary.stopped = Some(format!("interrupted after {} scans", streams.published));
    } else {
        streams.end()?;
    }
    summary.published = streams.published();
    Ok(())
}

/// The summary as one block at the very end, so slam-launch can show it whole (see
/// SUMMARY_HEAD), and its losses for the launcher.
fn report(summary: &ReplaySummary) {
    say_err(&summary.to_string());
    ipc_types::losses::report(&summary.losses());
}
