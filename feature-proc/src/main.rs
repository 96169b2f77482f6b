//! `feature-proc`: lines and corners of every scan, from the scan topic to the features topic.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Parser;
use feature_proc::{Extractor, FeatureConfig, ScanInput};
use ipc_types::prelude::*;

/// Subscribes to scans, publishes their lines and corners.
#[derive(Debug, Parser)]
#[command(name = "feature-proc", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// TOML file with extraction thresholds (every field optional).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Feature subscribers to wait for before the first lockstep publish.
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("feature-proc: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn load_config(path: Option<&PathBuf>) -> Result<FeatureConfig> {
    let Some(path) = path else {
        return Ok(FeatureConfig::default());
    };
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    toml::from_str(&text).with_context(|| format!("config {}", path.display()))
}

fn run() -> Result<()> {
    let args = Args::parse();
    shutdown::install().context("cannot install the Ctrl-C handler")?;
    let config = load_config(args.config.as_ref())?;
    config.validate().context("feature configuration")?;
    let mut extractor = Extractor::new(config);

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("feature-proc")?;
    let scans = Inlet::open(&node, topic::SCAN)?;
    // The source chose lockstep or real time; the features follow it.
    let features = Outlet::create(&domain, &node, topic::FEATURES, scans.delivery(), 0)?;
    println!("ready");
    if scans.delivery() == Delivery::Lossless {
        features.wait_for_subscribers(args.subscribers, None)?;
    }

    let mut processed = 0u64;
    let mut skipped = 0u64;
    let mut lines = Vec::new();
    let mut corners = Vec::new();
    loop {
        if wait_any(&[&scans], Duration::from_millis(100))? == Wake::Shutdown {
            break;
        }
        while let Some(scan) = scans.receive()? {
            if scan.header.is_end_of_stream() {
                features.publish_end_of_stream(scan.header.seq, scan.header.stamp_ns)?;
                eprintln!("feature-proc: {processed} scans, {skipped} skipped");
                return Ok(());
            }
            let started = Instant::now();
            let input = ScanInput {
                angle_min: f64::from(scan.angle_min),
                angle_increment: f64::from(scan.angle_increment),
                range_min: f64::from(scan.range_min),
                range_max: f64::from(scan.range_max),
                ranges: scan.ranges(),
            };
            lines.clear();
            corners.clear();
            match extractor.extract(&input) {
                Ok(found) => {
                    lines.extend(found.lines.iter().map(to_line));
                    corners.extend(found.corners.iter().map(to_corner));
                }
                Err(e) => {
                    // A malformed scan is counted and dropped; the slot still goes downstream
                    // (empty) so every scan has its features message and the stream has no gap.
                    skipped += 1;
                    eprintln!("feature-proc: scan {} skipped: {e}", scan.header.seq);
                }
            }
            let processing_ns = started.elapsed().as_nanos() as u64;
            let mut overflow = None;
            features.publish(|message| {
                message.header = scan.header;
                message.scan_sent_ns = scan.header.sent_ns;
                message.processing_ns = processing_ns;
                let keep_lines = lines.len().min(ipc_types::MAX_LINES);
                let keep_corners = corners.len().min(ipc_types::MAX_FEATURE_CORNERS);
                if keep_lines < lines.len() || keep_corners < corners.len() {
                    overflow = Some((lines.len(), corners.len()));
                }
                // Cut to capacity above, so this cannot fail.
                let _ = message.set(&lines[..keep_lines], &corners[..keep_corners]);
            })?;
            if let Some((l, c)) = overflow {
                eprintln!(
                    "feature-proc: scan {} had {l} lines and {c} corners; kept what fits",
                    scan.header.seq
                );
            }
            processed += 1;
        }
    }
    eprintln!("feature-proc: stopped after {processed} scans");
    Ok(())
}

fn to_line(line: &feature_proc::Line) -> Line {
    Line {
        rho: line.rho,
        theta: line.theta,
        covariance: [
            line.covariance[(0, 0)],
            line.covariance[(0, 1)],
            line.covariance[(1, 0)],
            line.covariance[(1, 1)],
        ],
        start: line.start,
        end: line.end,
        point_count: u32::try_from(line.point_count).unwrap_or(u32::MAX),
        reserved: 0,
    }
}

fn to_corner(corner: &feature_proc::Corner) -> Corner {
    let mut covariance = [0.0; 16];
    for r in 0..4 {
        for c in 0..4 {
            covariance[r * 4 + c] = corner.covariance[(r, c)];
        }
    }
    Corner {
        x: corner.x,
        y: corner.y,
        heading: corner.heading,
        angle: corner.angle,
        covariance,
    }
}
