//! `slam-proc`: FastSLAM over corner maps, from the features topic to pose and map topics.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::prelude::*;
use saved_map::SavedMap;
use slam_eval::{FitVerdict, MapFit};
use slam_proc::{
    FastSlam, FilterStats, LocalizeStats, Localizer, MeasuredCorner, MeasuredLine, MeasuredMotion,
    OdometryInput, Pose2, ScanRanges, SlamConfig, Start,
};
use stage_kit::held_scans::{HeldScan, HeldScans};
use stage_kit::{say, say_err};

/// Subscribes to features (each with the odometry at its scan's stamp, if the run has any),
/// publishes a pose estimate for every scan, the best particle's map every few scans and at
/// the end, and the best particle's whole path at the end.
#[derive(Debug, Parser)]
#[command(name = "slam-proc", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// Particles of the filter (overrides the config file).
    #[arg(long)]
    particles: Option<usize>,
    /// Seed of the filter's noise: the same seed gives the same run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Publish the map every this many scans (and at the end).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..))]
    map_every: u64,
    /// Publish every particle's pose and weight every this many scans (for a recording;
    /// without it the cloud is never published).
    #[arg(long, value_name = "SCANS", value_parser = clap::value_parser!(u64).range(1..))]
    particles_every: Option<u64>,
    /// TOML file with filter settings (every field optional).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Pose subscribers to wait for before the first lockstep publish.
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
    /// A saved map (a run's output directory): mapping extends its landmarks, and with
    /// --localize the filter localizes on it without changing it.
    #[arg(long, value_name = "DIR")]
    map: Option<PathBuf>,
    /// Localize on --map: the map stays fixed, the scans' beams weight the particles through
    /// its occupancy grid ([slam.localize] in the config file).
    #[arg(long, requires = "map")]
    localize: bool,
    /// Where the robot starts in the map's frame, `x,y,yaw` (metres, radians). Localizing
    /// without it searches the whole map; mapping on a map without it starts at the map's
    /// origin.
    #[arg(long, value_name = "X,Y,YAW", value_parser = slam_proc::parse_pose, requires = "map", allow_hyphen_values = true)]
    initial_pose: Option<Pose2>,
}

fn main() -> ExitCode {
    stage_kit::run_stage("slam-proc", run)
}

fn run(args: Args) -> Result<()> {
    let mut config: SlamConfig = stage_kit::settings::load(args.config.as_deref())?;
    if let Some(particles) = args.particles {
        anyhow::ensure!(particles > 0, "--particles must be at least 1");
        config.particles = particles;
    }
    // Before the particles exist: a count the machine cannot hold would otherwise grow
    // until the kernel kills this process (or another one).
    slam_proc::memory::check(config.particles).context("refusing to start")?;
    let saved = match &args.map {
        Some(dir) => Some(load_map(dir)?),
        None => None,
    };
    if args.localize {
        let (saved, dir) = saved
            .zip(args.map.as_deref())
            .context("--localize needs --map")?;
        return localize(&args, config, &saved, dir);
    }
    let mut slam = match &saved {
        Some(saved) => FastSlam::with_prior_map_from(
            config,
            args.seed,
            &prior_corners(saved),
            args.initial_pose.unwrap_or(Pose2::IDENTITY),
        ),
        None => FastSlam::new(config, args.seed),
    }
    .context("slam configuration")?;
    // The saved grid keeps the particles in the saved map's frame scan by scan (a map
    // without one is extended from its corners alone).
    let saved_grid = saved.as_ref().and_then(|saved| saved.grid.as_ref());
    if let Some(grid) = saved_grid {
        anyhow::ensure!(
            grid.yaml.origin[2] == 0.0,
            "cannot map on the map in {}: its grid is rotated (origin yaw {}), which is not supported",
            args.map.as_deref().unwrap_or(Path::new("")).display(),
            grid.yaml.origin[2]
        );
        slam = slam.with_saved_grid(grid);
    }

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("slam-proc")?;
    let features = Inlet::open(&node, topic::FEATURES)?;
    // The scans' beams, only for the saved grid.
    let scans = match saved_grid {
        Some(_) => Some(Inlet::open(&node, topic::SCAN)?),
        None => None,
    };
    let mut held = HeldScans::default();
    let delivery = features.delivery();
    let maps = Outlet::create(&domain, &node, topic::MAP, delivery, 1)?;
    let poses = Outlet::create(&domain, &node, topic::POSE, delivery, 0)?;
    // The path goes out once, at the end, in many chunks: lossless whatever the run's
    // delivery, or a real-time run would keep only the last few.
    let path = Outlet::create(&domain, &node, topic::PATH, Delivery::Lossless, 0)?;
    let clouds = CloudOutlet::create(args.particles_every, || {
        Outlet::create(&domain, &node, topic::PARTICLES, delivery, 0)
    })?;
    say("ready");
    if delivery == Delivery::Lossless {
        poses.wait_for_subscribers(args.subscribers, None)?;
    }

    let mut observations = Vec::new();
    let mut lines = Vec::new();
    let mut processed = 0u64;
    let saved_dir = args.map.as_deref().unwrap_or(Path::new(""));
    let mut told_set_aside = false;
    let mut last_header = Header::new(0, 0, "map");
    // The most corners a map snapshot had to leave out (MAX_MAP_CORNERS fit in one).
    let mut left_out = 0u64;
    // Woken by the scans too: their queue must not fill while the features wait for them.
    let mut inlets: Vec<&dyn ipc_types::Wakeable> = vec![&features];
    if let Some(scans) = &scans {
        inlets.push(scans);
    }
    loop {
        if wait_any(&inlets, Duration::from_millis(100))? == Wake::Shutdown {
            break;
        }
        if let Some(scans) = &scans {
            held.hold(scans)?;
        }
        while let Some(sample) = features.receive()? {
            if sample.header.is_end_of_stream() {
                left_out = left_out.max(publish_map(&maps, &slam.best_map(), last_header)?);
                publish_path(&path, &slam, last_header)?;
                poses.publish_end_of_stream(sample.header.seq, sample.header.stamp_ns)?;
                say_err(&summary(&slam.stats(), saved_grid.map(|_| saved_dir)));
                ipc_types::losses::report(&[("map_corners_not_published", left_out)]);
                return Ok(());
            }
            if let Some(scans) = &scans {
                held.hold(scans)?;
                let scan = held
                    .wait_for(scans, sample.header.seq, delivery)?
                    .map(scan_ranges);
                slam.set_scan(scan.as_ref());
            }
            observations.clear();
            observations.extend(sample.corners().iter().map(|&c| MeasuredCorner::from(c)));
            lines.clear();
            lines.extend(sample.lines().iter().map(|&l| MeasuredLine::from(l)));
            let stamp = sample.header.stamp_ns;
            // feature-proc's front end measured the motion; without it the filter estimates
            // it from the corners and lines, on the odometry feature-proc paired with the
            // scan.
            let front_end = sample.motion();
            let estimate = match &front_end {
                Some(motion) => slam.process_measured(
                    stamp,
                    &observations,
                    &lines,
                    &MeasuredMotion::from(motion),
                ),
                _ => {
                    let odometry_input = sample.odometry().map(OdometryInput::from);
                    slam.process(stamp, &observations, &lines, odometry_input.as_ref())
                }
            };
            // The front end's own pose is the motion estimate alone, whatever moved the
            // particles: both start at the first scan's pose.
            let dead_reckoning = front_end.map_or(estimate.dead_reckoning.into(), |m| m.pose);
            let header = sample.header;
            poses.publish(|pose| {
                pose.header = header;
                pose.header.set_frame_id("map");
                pose.scan_sent_ns = sample.scan_sent_ns;
                fill_estimate(pose, &estimate);
                pose.dead_reckoning = dead_reckoning;
                pose.localization = PoseEstimate::MAPPING;
                fill_map_fit(pose, &slam.map_fit());
            })?;
            if let Some(at) = slam.stats().saved_map_set_aside_at
                && !told_set_aside
            {
                told_set_aside = true;
                say_err(&format!(
                    "slam-proc: at scan {at}: {}",
                    set_aside_text(&slam.map_fit(), saved_dir)
                ));
            }
            last_header = header;
            processed += 1;
            if processed.is_multiple_of(args.map_every) {
                left_out = left_out.max(publish_map(&maps, &slam.best_map(), header)?);
            }
            if let Some(outlet) = clouds.due(processed) {
                let log_weights: Vec<f64> = slam.particle_log_weights().collect();
                publish_cloud(outlet, header, slam.particle_poses(), &log_weights)?;
            }
        }
    }
    // Stopped by a signal: leave the map and the path as far as they got.
    left_out = left_out.max(publish_map(&maps, &slam.best_map(), last_header)?);
    publish_path(&path, &slam, last_header)?;
    say_err(&format!("slam-proc: stopped after {processed} scans"));
    say_err(&summary(&slam.stats(), saved_grid.map(|_| saved_dir)));
    ipc_types::losses::report(&[("map_corners_not_published", left_out)]);
    Ok(())
}

/// The closing summary block (launch shows it on the console at the end of a run), with
/// the saved map's fit when mapping on the grid of the map in `saved`.
fn summary(stats: &FilterStats, saved: Option<&Path>) -> String {
    let mut text = format!(
        "slam-proc: summary of the filter\n  \
         scans:           {} ({} updated the particles with their corners)\n  \
         resamplings:     {}\n  \
         map:             {} corners",
        stats.scans, stats.updates, stats.resamplings, stats.map_corners,
    );
    if let Some(dir) = saved {
        let fit = match stats.saved_map_set_aside_at {
            Some(at) => format!(
                "set aside at scan {at}: {}",
                set_aside_text(&stats.map_fit, dir)
            ),
            None => fit_text(&stats.map_fit),
        };
        text.push_str(&format!("\n  saved map:       {fit}"));
    }
    text
}

/// How well a saved map explained the beams: `explains 97.1 % of 12034 beams (at least
/// 50 % needed)`, or that too few were judged to say.
fn fit_text(fit: &MapFit) -> String {
    match fit.share() {
        Some(share) if fit.verdict() != FitVerdict::TooFewBeams => format!(
            "explains {:.1} % of {} beams (at least {:.0} % needed)",
            100.0 * share,
            fit.beams_judged,
            100.0 * slam_eval::MAP_FIT_FLOOR
        ),
        _ => format!(
            "judged only {} beams, too few to say how well it fits (it takes {})",
            fit.beams_judged,
            slam_eval::MAP_FIT_MIN_BEAMS
        ),
    }
}

/// Why the saved map in `dir` was set aside while mapping on it.
fn set_aside_text(fit: &MapFit, dir: &Path) -> String {
    format!(
        "the saved map in {} does not fit this run's scans, it {}; mapping on without it, \
         its corners and grid left out",
        dir.display(),
        fit_text(fit)
    )
}

/// The saved map's fit so far, in a pose message.
fn fill_map_fit(pose: &mut PoseEstimate, fit: &MapFit) {
    pose.map_beams_judged = fit.beams_judged;
    pose.map_beams_explained = fit.beams_explained;
}

/// Publishes a map (the best particle's, or the saved one being localized on); returns
/// how many corners did not fit the message.
fn publish_map(
    maps: &Outlet<MapSnapshot>,
    map: &[slam_proc::MapCorner],
    header: Header,
) -> Result<u64> {
    let corners: Vec<MapCorner> = map.iter().map(|&c| MapCorner::from(c)).collect();
    let keep = corners.len().min(ipc_types::MAX_MAP_CORNERS);
    if keep < corners.len() {
        say_err(&format!(
            "slam-proc: the map has {} corners; publishing {keep}",
            corners.len()
        ));
    }
    maps.publish(|message| {
        message.header = header;
        message.header.set_frame_id("map");
        // Cut to capacity above, so this cannot fail.
        let _ = message.set(&corners[..keep]);
    })?;
    Ok((corners.len() - keep) as u64)
}

/// The best particle's whole path, in chunks numbered from 0.
fn publish_path(outlet: &Outlet<PathChunk>, slam: &FastSlam, last: Header) -> Result<()> {
    let path: Vec<StampedPose> = slam
        .best_path()
        .iter()
        .map(|&p| StampedPose::from(p))
        .collect();
    outlet.publish_path(&path, last.stamp_ns, Form::Final)?;
    Ok(())
}

/// The particle cloud's topic, when the run records it: every `every` scans.
struct CloudOutlet {
    outlet: Option<(Outlet<ParticleCloud>, u64)>,
}

impl CloudOutlet {
    /// The topic, opened with `open` only when the cloud is wanted (`every` given): a run
    /// that does not record it neither makes the cloud nor has its shared memory.
    fn create(
        every: Option<u64>,
        open: impl FnOnce() -> Result<Outlet<ParticleCloud>, ipc_types::OpenError>,
    ) -> Result<Self> {
        let outlet = match every {
            Some(every) => Some((open()?, every)),
            None => None,
        };
        Ok(Self { outlet })
    }

    /// The outlet when the `processed`th scan is one whose cloud goes out.
    fn due(&self, processed: u64) -> Option<&Outlet<ParticleCloud>> {
        self.outlet
            .as_ref()
            .filter(|(_, every)| processed.is_multiple_of(*every))
            .map(|(outlet, _)| outlet)
    }
}

/// Every particle's pose and normalised weight at the scan of `header`, in pieces.
fn publish_cloud(
    outlet: &Outlet<ParticleCloud>,
    header: Header,
    poses: impl Iterator<Item = Pose2>,
    log_weights: &[f64],
) -> Result<()> {
    let weights = slam_proc::normalised_weights(log_weights);
    let particles: Vec<Particle> = poses
        .zip(weights)
        .map(|(pose, weight)| Particle {
            pose: pose.into(),
            weight,
        })
        .collect();
    let total = particles.len() as u64;
    for (index, piece) in particles
        .chunks(ipc_types::MAX_CLOUD_CHUNK_PARTICLES)
        .enumerate()
    {
        outlet.publish(|message| {
            message.header = header;
            message.header.set_frame_id("map");
            message.first = (index * ipc_types::MAX_CLOUD_CHUNK_PARTICLES) as u64;
            message.total = total;
            // Pieces are cut to the capacity, so this cannot fail.
            let _ = message.set(piece);
        })?;
    }
    Ok(())
}

/// The estimate's fields of a pose message.
fn fill_estimate(pose: &mut PoseEstimate, estimate: &slam_proc::Estimate) {
    pose.best = estimate.best.into();
    pose.mean = estimate.mean.into();
    pose.dead_reckoning = estimate.dead_reckoning.into();
    for r in 0..3 {
        for c in 0..3 {
            pose.covariance[r * 3 + c] = estimate.covariance[(r, c)];
        }
    }
    pose.effective_particles = estimate.effective_particles;
    pose.particle_count = u32::try_from(estimate.particle_count).unwrap_or(u32::MAX);
    pose.map_corners = u32::try_from(estimate.map_size).unwrap_or(u32::MAX);
    pose.timing = estimate.timing;
}

/// The saved map in `dir`, refused with the file and the reason when it cannot be used.
fn load_map(dir: &Path) -> Result<SavedMap> {
    SavedMap::load(dir).with_context(|| format!("cannot use the map in {}", dir.display()))
}

/// The saved landmarks as the filter's corners.
fn prior_corners(saved: &SavedMap) -> Vec<slam_proc::MapCorner> {
    saved.landmarks.map_corners()
}

/// A held scan's beams as the localizer and the saved grid take them.
fn scan_ranges(scan: &HeldScan) -> ScanRanges<'_> {
    let g = &scan.geometry;
    ScanRanges {
        angle_min: g.angle_min,
        angle_increment: g.angle_increment,
        range_min: g.range_min,
        range_max: g.range_max,
        ranges: &scan.ranges,
    }
}

/// Localization on the saved map: scans and features in, a pose per scan out, the map
/// published as it is.
fn localize(args: &Args, config: SlamConfig, saved: &SavedMap, dir: &Path) -> Result<()> {
    let grid = saved.grid.as_ref().with_context(|| {
        format!(
            "cannot localize on the map in {}: it has no occupancy grid",
            dir.display()
        )
    })?;
    // The likelihood field reads the grid with its cells along the map's axes.
    anyhow::ensure!(
        grid.yaml.origin[2] == 0.0,
        "cannot localize on the map in {}: its grid is rotated (origin yaw {}), which is not supported",
        dir.display(),
        grid.yaml.origin[2]
    );
    let corners = prior_corners(saved);
    let start = args.initial_pose.map_or(Start::Global, Start::Known);
    let mut localizer = Localizer::new(config.localize, grid, start, args.seed, corners.len())
        .with_context(|| format!("cannot localize on the map in {}", dir.display()))?;

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("slam-proc")?;
    let features = Inlet::open(&node, topic::FEATURES)?;
    let scans = Inlet::open(&node, topic::SCAN)?;
    let delivery = features.delivery();
    let maps = Outlet::create(&domain, &node, topic::MAP, delivery, 1)?;
    let poses = Outlet::create(&domain, &node, topic::POSE, delivery, 0)?;
    let clouds = CloudOutlet::create(args.particles_every, || {
        Outlet::create(&domain, &node, topic::PARTICLES, delivery, 0)
    })?;
    // map-sink waits for the path's topic; no path comes (no particle keeps one here), so
    // it writes the online estimate as the trajectory.
    let _path = Outlet::<PathChunk>::create(&domain, &node, topic::PATH, Delivery::Lossless, 0)?;
    say("ready");
    if delivery == Delivery::Lossless {
        poses.wait_for_subscribers(args.subscribers, None)?;
    }
    let mut held = HeldScans::default();
    let mut last_header = Header::new(0, 0, "map");
    let mut left_out = publish_map(&maps, &corners, last_header)?;
    let mut step_ms: Vec<f64> = Vec::new();
    let mut processed = 0u64;
    loop {
        if wait_any(&[&features, &scans], Duration::from_millis(100))? == Wake::Shutdown {
            break;
        }
        held.hold(&scans)?;
        while let Some(sample) = features.receive()? {
            // Its scan was published before feature-proc could take it.
            held.hold(&scans)?;
            if sample.header.is_end_of_stream() {
                left_out = left_out.max(publish_map(&maps, &corners, last_header)?);
                poses.publish_end_of_stream(sample.header.seq, sample.header.stamp_ns)?;
                say_err(&localize_summary(&localizer.stats(), &step_ms));
                ipc_types::losses::report(&[
                    ("map_corners_not_published", left_out),
                    ("scans_without_beams", localizer.stats().scans_without_beams),
                ]);
                return Ok(());
            }
            let scan = held
                .wait_for(&scans, sample.header.seq, delivery)?
                .map(scan_ranges);
            // A first scan, or a source without a front end, brings no step: stand still.
            let motion = sample
                .motion()
                .map_or(MeasuredMotion::standing_still(), |m| {
                    MeasuredMotion::from(&m)
                });
            let located = localizer.step(&motion, scan.as_ref());
            step_ms.push(located.estimate.timing.total_ns as f64 * 1e-6);
            let front_end = sample.motion().map(|m| m.pose);
            let header = sample.header;
            poses.publish(|pose| {
                pose.header = header;
                pose.header.set_frame_id("map");
                pose.scan_sent_ns = sample.scan_sent_ns;
                fill_estimate(pose, &located.estimate);
                if let Some(front_end) = front_end {
                    pose.dead_reckoning = front_end;
                }
                pose.localization = if located.converged {
                    PoseEstimate::CONVERGED
                } else {
                    PoseEstimate::SEARCHING
                };
                fill_map_fit(pose, &localizer.stats().map_fit);
            })?;
            last_header = header;
            processed += 1;
            if let Some(outlet) = clouds.due(processed) {
                let poses = localizer.particle_poses().iter().copied();
                publish_cloud(outlet, header, poses, localizer.particle_log_weights())?;
            }
        }
    }
    publish_map(&maps, &corners, last_header)?;
    say_err("slam-proc: stopped");
    say_err(&localize_summary(&localizer.stats(), &step_ms));
    ipc_types::losses::report(&[
        ("map_corners_not_published", left_out),
        ("scans_without_beams", localizer.stats().scans_without_beams),
    ]);
    Ok(())
}

/// The closing summary of a localization run, with the time per scan.
fn localize_summary(stats: &LocalizeStats, step_ms: &[f64]) -> String {
    let at = |p: f64| slam_eval::percentile(step_ms, p).unwrap_or(0.0);
    format!(
        "slam-proc: summary of the localization\n  \
         scans:           {} ({} weighted the particles, {} of them tempered; {} without beams)\n  \
         converged:       {}\n  \
         map fit:         {}\n  \
         particles:       at most {}\n  \
         time per scan:   median {:.3} ms, 99th percentile {:.3} ms, max {:.3} ms",
        stats.scans,
        stats.updates,
        stats.tempered_updates,
        stats.scans_without_beams,
        stats
            .converged_at
            .map_or("never".to_owned(), |scan| format!("at scan {scan}")),
        fit_text(&stats.map_fit),
        stats.peak_particles,
        at(50.0),
        at(99.0),
        at(100.0),
    )
}
