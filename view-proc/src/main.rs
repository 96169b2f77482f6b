//! `slam-view`: serves the pipeline's topics live to Foxglove over its WebSocket protocol.

mod inlets;

use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::{Domain, wait_loop};
use recorder::Recording;
use stage_kit::{say, say_err};
use view_proc::{LiveChannels, ViewAddress, ViewServer};

use crate::inlets::Inlets;

/// Reads the scans, the pose estimates, the features, the map snapshots, the filter's path
/// and, when the run has them, the particle cloud and the back end's path and grid, and
/// serves them on ws://ADDR to the Foxglove app, as the recording has them. It reads lossy:
/// no publisher waits for it, and nothing about the run changes with it.
#[derive(Debug, Parser)]
#[command(name = "slam-view", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// HOST:PORT to serve on (port 0: any free one, said on stdout).
    #[arg(long, value_name = "HOST:PORT", default_value = view_proc::DEFAULT_ADDRESS)]
    addr: ViewAddress,
    /// slam-proc publishes its particle cloud every few scans: show it.
    #[arg(long)]
    particles: bool,
    /// graph-proc publishes the back end's path and grid as they stand: show them.
    #[arg(long)]
    back_end: bool,
}

fn main() -> std::process::ExitCode {
    stage_kit::run_stage("slam-view", run)
}

/// How often the sensor's place on the robot (`base_link` → `laser`, sent once in a file)
/// is said again, for the clients that connected since: without it their scans are not
/// placed in the map.
const RESTATE_SENSOR_FRAMES: Duration = Duration::from_secs(1);

/// Longest sleep without a notification: a wake-up missed under load costs at most this,
/// and a stop is seen within it.
const WAIT: Duration = Duration::from_millis(100);

fn run(args: Args) -> Result<()> {
    let server = ViewServer::start(&args.addr)?;
    let mut channels = LiveChannels::new(server.context().clone());
    inlets::declare_channels(&mut channels).context("cannot open the live channels")?;
    say(&format!(
        "Foxglove live view on ws://{} (Foxglove: Open connection, Foxglove WebSocket)",
        server.address()
    ));
    let mut view = Recording::to(channels);

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("slam-view")?;
    let inlets = Inlets::open(&node, args.particles, args.back_end)?;
    say("ready");
    serve(&inlets, &mut view)?;

    let sent = view.output().sent();
    let clients = server.clients();
    if !server.stop() {
        say_err(&format!(
            "slam-view: a client's connection did not close within {} s; left",
            view_proc::SHUTDOWN_GRACE.as_secs_f64()
        ));
    }
    say_err(&format!(
        "slam-view: {sent} messages served; {clients} client(s) connected at the end"
    ));
    // What the view does not keep up with is lost by design (it reads lossy), and none of
    // the run's data: it has no losses to report.
    ipc_types::losses::report(&[]);
    Ok(())
}

/// Converts and serves whatever comes, until slam-launch stops the view (the view has no
/// end of its own: it may have missed any stage's end-of-stream marker).
fn serve(inlets: &Inlets, view: &mut Recording<LiveChannels>) -> Result<()> {
    let wakeables = inlets.wakeables();
    let mut restated = Instant::now();
    wait_loop(&wakeables, WAIT, || -> Result<bool> {
        if restated.elapsed() >= RESTATE_SENSOR_FRAMES {
            view.restate_sensor_frames();
            restated = Instant::now();
        }
        inlets.drain(view)?;
        Ok(true)
    })
}
