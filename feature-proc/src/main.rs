//! `feature-proc`: lines and corners of every scan, from the scan topic to the features topic,
//! each scan paired with the odometry at its stamp.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Parser;
use feature_proc::{Extractor, FeatureConfig, ScanInput, scan_motion};
use ipc_types::prelude::*;
use scan_match::{FrontEnd, FrontEndConfig, FrontEndStats, OdometryRejections};
use slam_geom::ScanGeometry;
use stage_kit::odometry_buffer::{OdometryBuffer, OdometryReading, RefusedReading};
use stage_kit::{say, say_err};

/// Subscribes to scans (and odometry, when the source publishes it) and publishes their lines
/// and corners with the odometry pose at each scan's stamp.
#[derive(Debug, Parser)]
#[command(name = "feature-proc", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// TOML file with extraction thresholds (every field optional).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// TOML file with scan-matching front-end settings (every field optional; see
    /// scan_match::FrontEndConfig).
    #[arg(long, value_name = "FILE")]
    front_end_config: Option<PathBuf>,
    /// Feature subscribers to wait for before the first lockstep publish.
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
    /// In real time, how long a scan may wait for the odometry at its stamp before it goes on
    /// with what has come (lockstep always waits: the pairing must not depend on timing).
    #[arg(long, default_value_t = 100, value_name = "MS")]
    odometry_wait_ms: u64,
}

/// Longest sleep between looks at the inlets (and at the stop flag).
const IDLE_WAIT: Duration = Duration::from_millis(100);
/// How often a real-time run without odometry looks for it again.
const ODOMETRY_PROBE: Duration = Duration::from_secs(1);

fn main() -> ExitCode {
    stage_kit::run_stage("feature-proc", run)
}

fn run(args: Args) -> Result<()> {
    let front_end_config: FrontEndConfig =
        stage_kit::settings::load(args.front_end_config.as_deref())?;
    let mut config: FeatureConfig = stage_kit::settings::load(args.config.as_deref())?;
    // One setting of the scanner's range noise for both: the front end's.
    config.range_sigma = front_end_config.range_sigma;
    config.validate().context("feature configuration")?;
    let mut extractor = Extractor::new(config);
    let mut front_end = FrontEnd::new(front_end_config).context("front-end configuration")?;

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("feature-proc")?;
    let scans = Inlet::open(&node, topic::SCAN)?;
    // A source creates its odometry topic before its scans, so once the scans exist the
    // odometry does too, if the run has any.
    let mut odometry = Inlet::try_open(&node, topic::ODOMETRY)?;
    // The source chose lockstep or real time; the features follow it.
    let lockstep = scans.delivery() == Delivery::Lossless;
    let features = Outlet::create(&domain, &node, topic::FEATURES, scans.delivery(), 0)?;
    say("ready");
    if lockstep {
        features.wait_for_subscribers(args.subscribers, None)?;
    }
    let odometry_wait = Duration::from_millis(args.odometry_wait_ms);

    let mut track = OdometryBuffer::new();
    let mut pending: VecDeque<PendingScan> = VecDeque::new();
    // The held scans' range buffers, kept for the next scans: no allocation per scan.
    let mut spare_ranges: Vec<Vec<f32>> = Vec::new();
    let mut end_of_scans: Option<(u64, u64)> = None;
    let mut counts = Counts::default();
    let mut last_odometry_probe = Instant::now();
    let mut lines = Vec::new();
    let mut corners = Vec::new();
    loop {
        // A scan held for its odometry in real time must not wait past its bound.
        let timeout = match pending.front() {
            Some(scan) if !lockstep => odometry_wait
                .saturating_sub(scan.arrived.elapsed())
                .clamp(Duration::from_millis(1), IDLE_WAIT),
            _ => IDLE_WAIT,
        };
        let wake = match &odometry {
            Some(inlet) => wait_any(&[&scans, inlet], timeout)?,
            None => wait_any(&[&scans], timeout)?,
        };
        if wake == Wake::Shutdown {
            break;
        }
        if odometry.is_none() && !lockstep && last_odometry_probe.elapsed() > ODOMETRY_PROBE {
            // A live robot's odometry may start after its lidar.
            odometry = Inlet::try_open(&node, topic::ODOMETRY)?;
            last_odometry_probe = Instant::now();
        }
        // Scans first, odometry second: everything the source published before the last
        // scan taken here is then in the track too.
        while end_of_scans.is_none()
            && let Some(scan) = scans.receive()?
        {
            if scan.header.is_end_of_stream() {
                end_of_scans = Some((scan.header.seq, scan.header.stamp_ns));
            } else {
                let buffer = spare_ranges.pop().unwrap_or_default();
                pending.push_back(PendingScan::copy(&scan, buffer));
            }
        }
        if let Some(inlet) = &odometry {
            drain_odometry(inlet, &mut track, &mut counts)?;
        }
        if end_of_scans.is_some() {
            // The source sends its odometry before the scans' end: nothing more will come.
            track.end();
        }
        while let Some(scan) = pending.front() {
            let at = track.at(scan.header.stamp_ns);
            let ready = odometry.is_none()
                || at.is_final()
                || (!lockstep && scan.arrived.elapsed() >= odometry_wait);
            if !ready {
                break;
            }
            let Some(scan) = pending.pop_front() else {
                break;
            };
            let reading = odometry.as_ref().and_then(|_| at.reading());
            track.forget_before(scan.header.stamp_ns);
            if odometry.is_some() && reading.is_none() {
                counts.without_odometry += 1;
            }
            let motion = register(&mut front_end, &scan, reading.as_ref(), &mut counts);
            let paired = reading.as_ref().map(OdometryAtScan::from);
            let work = Work {
                extractor: &mut extractor,
                lines: &mut lines,
                corners: &mut corners,
                counts: &mut counts,
            };
            publish_features(&features, work, &scan, paired, motion)?;
            spare_ranges.push(scan.ranges);
        }
        if let Some((seq, stamp_ns)) = end_of_scans
            && pending.is_empty()
        {
            features.publish_end_of_stream(seq, stamp_ns)?;
            say_err(&format!("feature-proc: {}", counts.summary()));
            say_err(&front_end_summary(
                &front_end.stats(),
                front_end.odometry_scale(),
            ));
            ipc_types::losses::report(&counts.losses());
            return Ok(());
        }
    }
    say_err(&format!("feature-proc: stopped; {}", counts.summary()));
    say_err(&front_end_summary(
        &front_end.stats(),
        front_end.odometry_scale(),
    ));
    ipc_types::losses::report(&counts.losses());
    Ok(())
}

/// What the run skipped or made do without, for the summary at its end.
#[derive(Debug, Default)]
struct Counts {
    processed: u64,
    skipped: u64,
    odometry_not_finite: u64,
    odometry_out_of_order: u64,
    /// Scans the front end refused (geometry that defines no bearing or range).
    unregistered: u64,
    without_odometry: u64,
}

impl Counts {
    /// What was lost, for the launcher (`ipc_types::losses`). A scan without odometry is
    /// not: a run may have none.
    fn losses(&self) -> [(&'static str, u64); 4] {
        [
            ("skipped_scans", self.skipped),
            ("odometry_not_finite", self.odometry_not_finite),
            ("odometry_out_of_order", self.odometry_out_of_order),
            ("scans_not_registered", self.unregistered),
        ]
    }

    fn summary(&self) -> String {
        let mut text = format!("{} scans, {} skipped", self.processed, self.skipped);
        let notes = [
            (
                self.odometry_not_finite,
                "non-finite odometry readings refused",
            ),
            (
                self.odometry_out_of_order,
                "odometry readings not after the one before them refused",
            ),
            (self.unregistered, "scans the front end could not register"),
            (self.without_odometry, "scans without odometry"),
        ];
        for (count, what) in notes {
            if count > 0 {
                text.push_str(&format!(", {count} {what}"));
            }
        }
        text
    }
}

/// A scan held until its odometry is known, copied out of shared memory so the source's
/// slots are free meanwhile.
struct PendingScan {
    header: Header,
    geometry: ScanGeometry,
    /// Where the sensor sits on the robot.
    robot_from_sensor: slam_geom::Pose2,
    ranges: Vec<f32>,
    arrived: Instant,
}

impl PendingScan {
    /// Copies `scan`, its ranges into `buffer`.
    fn copy(scan: &LaserScan, mut buffer: Vec<f32>) -> Self {
        buffer.clear();
        buffer.extend_from_slice(scan.ranges());
        Self {
            header: scan.header,
            geometry: scan.geometry(),
            robot_from_sensor: scan.robot_from_sensor.into(),
            ranges: buffer,
            arrived: Instant::now(),
        }
    }
}

fn drain_odometry(
    inlet: &Inlet<Odometry>,
    track: &mut OdometryBuffer,
    counts: &mut Counts,
) -> Result<()> {
    while let Some(sample) = inlet.receive()? {
        if sample.header.is_end_of_stream() {
            track.end();
            continue;
        }
        match track.push(OdometryReading::from(&*sample)) {
            Ok(()) => {}
            Err(RefusedReading::NotFinite) => counts.odometry_not_finite += 1,
            Err(RefusedReading::OutOfOrder | RefusedReading::Duplicate) => {
                counts.odometry_out_of_order += 1;
            }
        }
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
/// Registers a scan with the front end; `None` for a scan it cannot take (counted).
fn register(
    front_end: &mut FrontEnd,
    scan: &PendingScan,
    odometry: Option<&OdometryReading>,
    counts: &mut Counts,
) -> Option<ScanMotion> {
    let input = scan_match::ScanInput {
        stamp_ns: scan.header.stamp_ns,
        geometry: scan.geometry,
        ranges: &scan.ranges,
        odometry: odometry.map(|o| {
            scan_match::OdometryInput::of_sensor(o.pose, o.covariance, &scan.robot_from_sensor)
        }),
    };
    match front_end.process(&input) {
        Ok(output) => Some(scan_motion(&output)),
        Err(e) => {
            counts.unregistered += 1;
            say_err(&format!(
                "feature-proc: scan {} not registered: {e}",
                scan.header.seq
            ));
            None
        }
    }
}

/// The front end's counts over the run and the wheels' distance scale it learnt, as a
/// summary block slam-launch shows at the end.
fn front_end_summary(stats: &FrontEndStats, odometry_scale: f64) -> String {
    let per_scan_ms = if stats.scans > 0 {
        stats.busy_ns as f64 / stats.scans as f64 * 1e-6
    } else {
        0.0
    };
    format!(
        "feature-proc: summary of the scan-matching front end\n  \
         scans:           {} ({} matched, {} with a direction left to the prior, {} not \
         registered)\n  \
         odometry steps:  {} used, {}; wheel distances x {odometry_scale:.3} \
         (learnt from the fits)\n  \
         recoveries:      {} wide searches (after a gap, a fast turn or scans not \
         registered), {} of them taken; longest stretch not registered: {} scans\n  \
         keyframes:       {}\n  \
         time:            {per_scan_ms:.3} ms per scan",
        stats.scans,
        stats.matched,
        stats.degenerate,
        stats.failed_matches,
        stats.odometry_used,
        rejected_summary(&stats.odometry_rejected),
        stats.wide_searches,
        stats.recovered,
        stats.longest_unregistered,
        stats.keyframes,
    )
}

/// "12 rejected (9 stale, 3 inconsistent with the scan)": the reasons that occurred.
fn rejected_summary(rejected: &OdometryRejections) -> String {
    let reasons: Vec<String> = [
        (rejected.stale, "stale"),
        (rejected.inconsistent, "inconsistent with the scan"),
        (rejected.implausible, "faster than a robot"),
        (rejected.not_finite, "not finite"),
    ]
    .iter()
    .filter(|(count, _)| *count > 0)
    .map(|(count, why)| format!("{count} {why}"))
    .collect();
    if reasons.is_empty() {
        "0 rejected".to_string()
    } else {
        format!("{} rejected ({})", rejected.total(), reasons.join(", "))
    }
}

/// The extractor and the buffers and counts it works with.
struct Work<'a> {
    extractor: &'a mut Extractor,
    lines: &'a mut Vec<Line>,
    corners: &'a mut Vec<Corner>,
    counts: &'a mut Counts,
}

fn publish_features(
    features: &Outlet<Features>,
    work: Work<'_>,
    scan: &PendingScan,
    odometry: Option<OdometryAtScan>,
    motion: Option<ScanMotion>,
) -> Result<()> {
    let Work {
        extractor,
        lines,
        corners,
        counts,
    } = work;
    let started = Instant::now();
    let input = ScanInput {
        geometry: scan.geometry,
        ranges: &scan.ranges,
    };
    lines.clear();
    corners.clear();
    match extractor.extract(&input) {
        Ok(found) => {
            lines.extend(found.lines.iter().map(|&l| Line::from(l)));
            corners.extend(found.corners.iter().map(|&c| Corner::from(c)));
        }
        Err(e) => {
            // A malformed scan is counted and dropped; the slot still goes downstream
            // (empty) so every scan has its features message and the stream has no gap.
            counts.skipped += 1;
            say_err(&format!(
                "feature-proc: scan {} skipped: {e}",
                scan.header.seq
            ));
        }
    }
    let processing_ns = started.elapsed().as_nanos() as u64;
    let mut overflow = None;
    features.publish(|message| {
        message.header = scan.header;
        message.scan_sent_ns = scan.header.sent_ns;
        message.processing_ns = processing_ns;
        message.set_odometry(odometry);
        message.set_motion(motion);
        let keep_lines = lines.len().min(ipc_types::MAX_LINES);
        let keep_corners = corners.len().min(ipc_types::MAX_FEATURE_CORNERS);
        if keep_lines < lines.len() || keep_corners < corners.len() {
            overflow = Some((lines.len(), corners.len()));
        }
        // Cut to capacity above, so this cannot fail.
        let _ = message.set(&lines[..keep_lines], &corners[..keep_corners]);
    })?;
    if let Some((l, c)) = overflow {
        say_err(&format!(
            "feature-proc: scan {} had {l} lines and {c} corners; kept what fits",
            scan.header.seq
        ));
    }
    counts.processed += 1;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_names_the_reasons_steps_were_rejected() {
        let none = OdometryRejections::default();
        assert_eq!(rejected_summary(&none), "0 rejected");
        let some = OdometryRejections {
            stale: 9,
            inconsistent: 3,
            ..OdometryRejections::default()
        };
        assert_eq!(
            rejected_summary(&some),
            "12 rejected (9 stale, 3 inconsistent with the scan)"
        );
    }
}
