//! `slam-record`: records the pipeline's topics into DIR/run.mcap as the run goes.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use iceoryx2::prelude::{CallbackProgression, Node, SignalHandlingMode, WaitSetBuilder, ipc};
use ipc_types::Wakeable;
use ipc_types::prelude::*;
use recorder::Recording;
use stage_kit::{say, say_err, shutdown};

/// Subscribes to every topic of the pipeline (scans, odometry, features, pose estimates, map
/// snapshots, the final path and, from a simulator, the ground truth and the world's
/// corners) and writes them into DIR/run.mcap, in zstd-compressed chunks that reach the disk
/// as each is complete. In lockstep the publishers wait for it like for any subscriber, so
/// nothing is lost.
#[derive(Debug, Parser)]
#[command(name = "slam-record", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// Output directory; the recording is DIR/run.mcap.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

fn main() -> ExitCode {
    stage_kit::run_stage("slam-record", run)
}

/// Longest sleep without a notification: a wake-up missed under load costs at most this.
const WAIT: Duration = Duration::from_millis(100);

/// Every inlet of the recorder; the optional ones exist when their source publishes them.
struct Inlets {
    truth: Option<Inlet<GroundTruthPose>>,
    world: Option<Inlet<WorldCorners>>,
    odometry: Option<Inlet<Odometry>>,
    features: Inlet<Features>,
    poses: Inlet<PoseEstimate>,
    maps: Inlet<MapSnapshot>,
    path: Inlet<PathChunk>,
    scans: Inlet<LaserScan>,
}

impl Inlets {
    /// Subscribes to everything, the scans last: the source starts once it counts us among
    /// its scan subscribers, and by then we listen to every other topic too.
    fn open(node: &Node<ipc::Service>) -> Result<Self> {
        // The source creates its ground truth, world and odometry before its scans: once
        // the scans exist, so do they, if the source publishes them.
        wait_for_topic(node, topic::SCAN)?;
        let truth = Inlet::try_open(node, topic::GROUND_TRUTH)?;
        let world = Inlet::try_open(node, topic::WORLD_CORNERS)?;
        let odometry = Inlet::try_open(node, topic::ODOMETRY)?;
        let features = Inlet::open(node, topic::FEATURES)?;
        let poses = Inlet::open(node, topic::POSE)?;
        let maps = Inlet::open(node, topic::MAP)?;
        let path = Inlet::open(node, topic::PATH)?;
        let scans = Inlet::open(node, topic::SCAN)?;
        Ok(Self {
            truth,
            world,
            odometry,
            features,
            poses,
            maps,
            path,
            scans,
        })
    }

    fn wakeables(&self) -> Vec<&dyn Wakeable> {
        let mut all: Vec<&dyn Wakeable> = vec![
            &self.scans,
            &self.features,
            &self.poses,
            &self.maps,
            &self.path,
        ];
        if let Some(truth) = &self.truth {
            all.push(truth);
        }
        if let Some(world) = &self.world {
            all.push(world);
        }
        if let Some(odometry) = &self.odometry {
            all.push(odometry);
        }
        all
    }

    /// Records everything queued except the poses; returns what it took.
    fn drain_all_but_poses(&self, recording: &mut Recording) -> Result<u64> {
        let mut taken = 0;
        if let Some(world) = &self.world {
            taken += drain(world, |m| recording.world_corners(m))?;
        }
        if let Some(truth) = &self.truth {
            taken += drain(truth, |m| recording.ground_truth(m))?;
        }
        if let Some(odometry) = &self.odometry {
            taken += drain(odometry, |m| recording.odometry(m))?;
        }
        taken += drain(&self.scans, |m| recording.scan(m))?;
        taken += drain(&self.features, |m| recording.features(m))?;
        taken += drain(&self.maps, |m| recording.map(m))?;
        taken += drain(&self.path, |m| recording.path_chunk(m))?;
        Ok(taken)
    }
}

/// Records every message queued on `inlet` with `record`; returns how many.
fn drain<T: Message>(
    inlet: &Inlet<T>,
    mut record: impl FnMut(&T) -> Result<(), recorder::RecordError>,
) -> Result<u64> {
    let mut taken = 0;
    while let Some(sample) = inlet.receive()? {
        record(&sample)?;
        taken += 1;
    }
    Ok(taken)
}

fn run(args: Args) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create directory {}", args.out.display()))?;
    let mut recording = Recording::create(&args.out)?;

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("slam-record")?;
    let inlets = Inlets::open(&node)?;
    say("ready");
    let wakeables = inlets.wakeables();

    // One wait set for the whole run, not one per wake-up as `wait_any` makes: the recorder
    // wakes for every message of every topic (five per scan), and making and dropping a wait
    // set of eight listeners each time cost it more system time than its encoding took.
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("cannot create a wait set: {e:?}"))?;
    let mut guards = Vec::with_capacity(wakeables.len());
    for wakeable in &wakeables {
        guards.push(
            waitset
                .attach_notification(wakeable.wake_listener())
                .map_err(|e| anyhow::anyhow!("cannot wait on a topic: {e:?}"))?,
        );
    }

    let mut finished = false;
    while !finished && !shutdown::requested() {
        let woken = waitset.wait_and_process_once_with_timeout(
            |id| {
                // Consume the notifications of the topics that woke us, so the next wait
                // sleeps again; the queues are drained below whoever notified.
                for (guard, wakeable) in guards.iter().zip(&wakeables) {
                    if id.has_event_from(guard) {
                        let _ = wakeable.wake_listener().try_wait(|_| {});
                    }
                }
                CallbackProgression::Continue
            },
            WAIT,
        );
        if shutdown::requested() {
            break;
        }
        // A signal interrupting the wait surfaces as an error; the flag above tells.
        woken.map_err(|e| anyhow::anyhow!("cannot wait for messages: {e:?}"))?;
        inlets.drain_all_but_poses(&mut recording)?;
        while let Some(sample) = inlets.poses.receive()? {
            if sample.header.is_end_of_stream() {
                // slam-proc's last word: what every stage sent before it is queued (each
                // lossless send waited for our room), or comes right behind it.
                finished = true;
                break;
            }
            recording.pose(&sample)?;
        }
    }
    drop(guards);
    // Whatever is still queued belongs in the file; a few rounds take what was in flight.
    for _ in 0..3 {
        if inlets.drain_all_but_poses(&mut recording)? == 0 {
            break;
        }
    }

    let summary = recording.finish()?;
    let total: u64 = summary.channels.iter().map(|c| c.messages).sum();
    say_err(&format!(
        "slam-record: {total} messages on {} channels written to {}",
        summary.channels.len(),
        summary.path.display()
    ));
    for channel in &summary.channels {
        say_err(&format!(
            "slam-record:   {} ({}): {}",
            channel.topic, channel.schema, channel.messages
        ));
    }
    if summary.maps_left_out > 0 {
        say_err(&format!(
            "slam-record: {} map snapshots left out (one each {} s of data, and the last)",
            summary.maps_left_out,
            recorder::MAP_PERIOD_NS / 1_000_000_000
        ));
    }
    if summary.path_chunks_out_of_place > 0 {
        say_err(&format!(
            "slam-record: {} chunks of the final path came out of place; the path is not \
             recorded",
            summary.path_chunks_out_of_place
        ));
    }
    ipc_types::losses::report(&[("path_chunks_out_of_place", summary.path_chunks_out_of_place)]);
    Ok(())
}
