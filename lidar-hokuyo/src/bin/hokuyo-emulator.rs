//! `hokuyo-emulator`: a Hokuyo UTM-30LX on TCP serving recorded scans over SCIP 2.0, so
//! `lidar-hokuyo` and the pipeline can run without the sensor.

use std::collections::BTreeSet;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use lidar_hokuyo::emulator::{Emulator, EmulatorConfig, Faults, load_scans};
use stage_kit::shutdown;

/// Emulated Hokuyo UTM-30LX (SCIP 2.0 over TCP) serving the scans of a CSV file.
#[derive(Debug, Parser)]
#[command(name = "hokuyo-emulator", version)]
struct Args {
    /// TCP port; 0 = any free port (printed on stdout).
    #[arg(long, default_value_t = 10940)]
    port: u16,
    /// Address to listen on.
    #[arg(long, default_value = "127.0.0.1")]
    host: String,
    /// Scans to serve: one line per scan, 1081 ranges in mm (steps 0..=1080), as
    /// seed-hall/scans.csv.
    #[arg(long)]
    file: PathBuf,
    /// Start over at the end of the file instead of going quiet and exiting.
    #[arg(long = "loop")]
    looping: bool,
    /// Motor speed reported and kept, rpm (2400 = 40 scans a second).
    #[arg(long, default_value_t = 2400, value_parser = clap::value_parser!(u32).range(1..))]
    rpm: u32,
    /// The sensor's millisecond counter at start (24 bits; near 16777215 to see it wrap).
    #[arg(long, default_value_t = 0)]
    clock_start: u32,
    /// Send the scan at this position (0 = first sent) with a wrong checksum; repeatable.
    #[arg(long)]
    corrupt: Vec<u64>,
    /// Cut the scan at this position in half and drop the connection; repeatable.
    #[arg(long)]
    drop: Vec<u64>,
}

fn main() -> ExitCode {
    stage_kit::run_stage("hokuyo-emulator", run)
}

fn run(args: Args) -> Result<()> {
    let scans = load_scans(&args.file)?;
    let mut config = EmulatorConfig::utm_30lx(scans);
    config.params.scan_rpm = args.rpm;
    config.looping = args.looping;
    config.clock_start_ms = args.clock_start;
    config.faults = Faults {
        corrupt: args.corrupt.iter().copied().collect::<BTreeSet<_>>(),
        drop: args.drop.iter().copied().collect::<BTreeSet<_>>(),
    };
    let scan_count = config.scans.len();
    let emulator = Emulator::start(config, (args.host.as_str(), args.port))?;
    println!("listening on {}", emulator.addr());
    std::io::stdout()
        .flush()
        .context("cannot write to stdout")?;
    eprintln!(
        "hokuyo-emulator: serving {scan_count} scans of {}{}",
        args.file.display(),
        if args.looping { " in a loop" } else { "" }
    );
    while !shutdown::requested() && !emulator.is_finished() {
        std::thread::sleep(Duration::from_millis(50));
    }
    let finished = emulator.is_finished();
    let stats = emulator.stop();
    eprintln!(
        "hokuyo-emulator: {}: sent {} scans to {} connections",
        if finished {
            "end of the file"
        } else {
            "stopped"
        },
        stats.sent.len(),
        stats.connections
    );
    Ok(())
}
