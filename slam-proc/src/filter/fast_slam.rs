//! The filter: motion estimate, prediction, association and update, resampling.

use std::time::Instant;

use ipc_types::StageTiming;
use rand::Rng;
use rayon::prelude::*;

use crate::config::SlamConfig;
use crate::filter::estimate::{Estimate, weighted_mean_and_covariance};
use crate::math::chi2::Gates;
use crate::update::jcbb::PoseUncertainty;
use slam_geom::{MapCorner, MeasuredCorner, MeasuredLine};

use crate::filter::observation::{MeasuredMotion, OdometryInput, Prepared};
use crate::filter::particle::{
    CONFIRM_OBSERVATIONS, Particle, SEARCH_RADIUS, ScanContext, Scratch,
};
use crate::filter::resample::{
    effective_sample_size, heaviest, log_sum_exp, normalise, systematic,
};
use crate::filter::rng::Streams;
use crate::filter::saved_grid::{self, SavedGrid, drift_off_grid};
use crate::localize::localizer::ScanRanges;
use crate::map::corner_map::{CornerMap, CornerState};
use crate::motion::estimator::{Motion, MotionEstimator, MotionSource};
use crate::motion::predict::{self, MotionNoise};
use crate::path::particle_path::ScanLog;
use slam_eval::{FitVerdict, MapFit};
use slam_geom::Pose2;
use slam_geom::StampedPose;
use stage_kit::SettingError;

/// FastSLAM over corner maps. Feed it every scan's corners in order with [`FastSlam::process`].
///
/// The result depends only on the configuration, the seed and the inputs: particles are
/// updated in parallel, each drawing from its own random stream, so the thread count does
/// not change a single bit of it.
#[derive(Debug, Clone)]
pub struct FastSlam {
    config: SlamConfig,
    streams: Streams,
    /// Scans processed so far.
    scans: u64,
    particles: Vec<Particle>,
    motion: MotionEstimator,
    /// The front end's measured steps integrated, with their covariance in its frame.
    measured_track: OdometryInput,
    dead_reckoning: Pose2,
    /// The particle with the highest weight at the last scan (after resampling, one of
    /// its copies).
    best: usize,
    gates: Gates,
    log_weights: Vec<f64>,
    weights: Vec<f64>,
    parents: Vec<usize>,
    /// This scan's usable lines.
    lines: Vec<MeasuredLine>,
    /// One set of update buffers per chunk of `PARTICLES_PER_TASK` particles.
    scratch: Vec<Scratch>,
    /// The motion since the corners last updated the particles.
    since_update: SinceUpdate,
    /// The path length of the motion so far, metres.
    path_length: f64,
    /// The front end's pose at every scan, which places the scans a particle kept no pose
    /// for.
    scan_log: ScanLog,
    /// Scans whose corners updated the particles.
    updates: u64,
    /// Resamplings so far.
    resamplings: u64,
    /// The saved map's grid when mapping on top of it.
    saved_grid: Option<SavedGrid>,
    /// The saved map's corners, the first ids of every particle's map.
    saved_corners: u32,
    /// How well the saved grid explains the scans, judged at the filter's updates.
    map_fit: MapFit,
    /// The scan at which the saved map was set aside for not fitting the scans.
    set_aside_at: Option<u64>,
    /// The path length at the last scan the saved grid judged, metres.
    on_grid_at: f64,
}

/// What the filter did over a run, for its closing summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FilterStats {
    /// Scans processed.
    pub scans: u64,
    /// Scans whose corners updated the particles (with measured motion, one per
    /// `update_min_distance` of path or `update_min_rotation` of turn).
    pub updates: u64,
    /// Times the particles were resampled.
    pub resamplings: u64,
    /// Confirmed corners of the best particle's map.
    pub map_corners: usize,
    /// Mapping on a saved grid: how well it explains the scans, from the best particle at
    /// each update (all 0 without one).
    pub map_fit: MapFit,
    /// The scan at which the saved map was set aside: it did not fit the scans
    /// ([`FastSlam::with_saved_grid`]).
    pub saved_map_set_aside_at: Option<u64>,
}

/// The motion since the corners last updated the particles.
#[derive(Debug, Clone, Copy, Default)]
struct SinceUpdate {
    /// Path length, metres.
    distance: f64,
    /// Rotation, radians, summed in absolute value.
    rotation: f64,
    /// The particles' motion noise, summed.
    noise: nalgebra::Matrix3<f64>,
}

/// The rotation by `yaw` acting on `(x, y)`, leaving yaw as it is.
fn rotation3(yaw: f64) -> nalgebra::Matrix3<f64> {
    let (s, c) = yaw.sin_cos();
    nalgebra::Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Where a scan's motion comes from.
#[derive(Debug, Clone, Copy)]
enum StepMotion<'a> {
    /// The filter estimates it from the scan's corners and lines, on odometry if given.
    Estimate(Option<&'a OdometryInput>),
    /// A front end measured it.
    Measured(&'a MeasuredMotion),
}

/// Resample when the effective number of particles falls below this fraction of the
/// particle count: resampling only then keeps the diversity that constant resampling loses,
/// and half is the usual threshold (Doucet et al.).
const RESAMPLE_THRESHOLD: f64 = 0.5;

/// Added in quadrature to each observation's position standard deviation, metres: covers
/// what the extractor's propagated covariance leaves out (wall roughness, timing, a moving
/// sensor), about a centimetre.
const OBSERVATION_EXTRA_SIGMA_XY: f64 = 0.01;
/// Added in quadrature to each observation's heading and angle standard deviations,
/// radians, for the same reasons.
const OBSERVATION_EXTRA_SIGMA_ANGLE: f64 = 0.01;

/// Gate probability of the individual (4 dof) and joint (4k dof) chi-square tests of data
/// association: a true pairing is rejected one time in a thousand.
pub(crate) const ASSOCIATION_PROBABILITY: f64 = 0.999;

/// Cell size of each map's spatial hash grid, metres: twice the search radius keeps a
/// corner lookup to four cells.
const GRID_CELL_SIZE: f64 = 3.0;
const _: () = assert!(GRID_CELL_SIZE >= 2.0 * SEARCH_RADIUS);

/// Particles per parallel task of the update: enough that a task outweighs its
/// scheduling, few enough that two cores share 100 particles evenly.
const PARTICLES_PER_TASK: usize = 8;

impl FastSlam {
    /// A filter with every particle at the origin and an empty map.
    pub fn new(config: SlamConfig, seed: u64) -> Result<Self, SettingError> {
        Self::with_prior_map(config, seed, &[])
    }

    /// A filter whose particles start at the origin with `corners` as a confirmed map, for
    /// localising in a known map. Every particle shares the one map until it updates it.
    /// Corners with non-finite values are skipped.
    pub fn with_prior_map(
        config: SlamConfig,
        seed: u64,
        corners: &[MapCorner],
    ) -> Result<Self, SettingError> {
        Self::with_prior_map_from(config, seed, corners, Pose2::IDENTITY)
    }

    /// As [`FastSlam::with_prior_map`], with the particles starting at `start` in the map's
    /// frame: mapping on top of a saved map from where the robot stands in it.
    pub fn with_prior_map_from(
        config: SlamConfig,
        seed: u64,
        corners: &[MapCorner],
        start: Pose2,
    ) -> Result<Self, SettingError> {
        config.validate()?;
        let mut map = CornerMap::new(GRID_CELL_SIZE);
        let mut saved_corners = 0;
        for corner in corners {
            let state = CornerState {
                mean: nalgebra::Vector4::new(corner.x, corner.y, corner.heading, corner.angle),
                covariance: corner.covariance,
                observations: corner.observations.max(CONFIRM_OBSERVATIONS),
            };
            if state
                .mean
                .iter()
                .chain(state.covariance.iter())
                .all(|v| v.is_finite())
            {
                map.insert(state, CONFIRM_OBSERVATIONS);
                saved_corners += 1;
            }
        }
        Ok(Self {
            streams: Streams::new(seed),
            scans: 0,
            particles: vec![
                Particle {
                    pose: start,
                    ..Particle::new(map)
                };
                config.particles
            ],
            motion: MotionEstimator::new(),
            measured_track: OdometryInput {
                pose: Pose2::IDENTITY,
                covariance: nalgebra::Matrix3::zeros(),
            },
            dead_reckoning: Pose2::IDENTITY,
            best: 0,
            gates: Gates::new(ASSOCIATION_PROBABILITY),
            log_weights: Vec::new(),
            weights: Vec::new(),
            parents: Vec::new(),
            lines: Vec::new(),
            scratch: Vec::new(),
            since_update: SinceUpdate::default(),
            path_length: 0.0,
            scan_log: ScanLog::default(),
            updates: 0,
            resamplings: 0,
            saved_grid: None,
            saved_corners,
            map_fit: MapFit::default(),
            set_aside_at: None,
            on_grid_at: 0.0,
            config,
        })
    }

    /// The filter fitting its particles to the saved map's occupancy grid at every corner
    /// update (each particle climbs the scan's likelihood on it, the localizer's faced field
    /// and beam model, `[slam.localize]`'s `sigma_hit`), with the beams given by
    /// [`FastSlam::set_scan`]: mapping on top of a saved map stays in its frame between
    /// corner sightings instead of drifting with the front end.
    ///
    /// The grid also judges how well the saved map explains the scans ([`MapFit`], from the
    /// best particle at each update). Once the verdict is that it does not, the saved map
    /// is set aside for the rest of the run: its grid no longer holds the particles and its
    /// corners leave every particle's map, so that the run maps on its own rather than
    /// merging this building's corners with another's.
    pub fn with_saved_grid(mut self, grid: &saved_map::GridMap) -> Self {
        self.saved_grid = Some(SavedGrid::new(grid, &self.config.localize));
        self
    }

    /// The beams of the scan the next [`FastSlam::process`] or
    /// [`FastSlam::process_measured`] brings (`None`: they did not arrive); only a filter
    /// with a saved grid reads them.
    pub fn set_scan(&mut self, scan: Option<&ScanRanges<'_>>) {
        if let Some(grid) = &mut self.saved_grid {
            grid.set_scan(scan, saved_grid::BEAMS);
        }
    }

    pub fn config(&self) -> &SlamConfig {
        &self.config
    }

    /// Scans processed so far.
    pub fn scans(&self) -> u64 {
        self.scans
    }

    /// Every particle's pose, in particle order.
    pub fn particle_poses(&self) -> impl Iterator<Item = Pose2> + '_ {
        self.particles.iter().map(|p| p.pose)
    }

    /// Every particle's log weight (since the last resampling), in particle order.
    pub fn particle_log_weights(&self) -> impl Iterator<Item = f64> + '_ {
        self.particles.iter().map(|p| p.log_weight)
    }

    /// The whole path of the particle that carries the most weight now, one pose per scan
    /// from the first: the filter's answer for the trajectory, consistent with
    /// [`FastSlam::best_map`] (the map was built from these poses).
    pub fn best_path(&self) -> Vec<StampedPose> {
        self.particles
            .get(self.best)
            .map(|p| p.path.poses(&self.scan_log))
            .unwrap_or_default()
    }

    /// What the filter did so far.
    pub fn stats(&self) -> FilterStats {
        let best = self.particles.get(self.best);
        FilterStats {
            scans: self.scans,
            updates: self.updates,
            resamplings: self.resamplings,
            map_corners: best.map_or(0, |p| p.map.confirmed_count()),
            map_fit: self.map_fit,
            saved_map_set_aside_at: self.set_aside_at,
        }
    }

    /// How well the saved grid explains the scans so far (all 0 without one); counting
    /// stops when the saved map is set aside.
    pub fn map_fit(&self) -> MapFit {
        self.map_fit
    }

    /// The confirmed corners of the best particle's map.
    pub fn best_map(&self) -> Vec<MapCorner> {
        self.particles
            .get(self.best)
            .map(|p| p.map.confirmed(CONFIRM_OBSERVATIONS))
            .unwrap_or_default()
    }

    /// Updates the filter with one scan: its acquisition time, its corners and wall lines
    /// in the sensor frame (lines steady the motion estimate; pass none if the extractor
    /// gives none) and, when the robot has odometry, the odometry pose at the scan.
    /// Features that are not usable (non-finite, an angle outside `(0, pi)`, a covariance
    /// that is not positive definite) are ignored.
    pub fn process(
        &mut self,
        stamp_ns: u64,
        observations: &[MeasuredCorner],
        lines: &[MeasuredLine],
        odometry: Option<&OdometryInput>,
    ) -> Estimate {
        self.step(
            stamp_ns,
            observations,
            lines,
            StepMotion::Estimate(odometry),
        )
    }

    /// Updates the filter with one scan whose motion a front end measured (scan matching
    /// fused with odometry, [`MeasuredMotion`]): the particles move by it, spread by the
    /// front end's drift, and the corners then weight them and correct their poses. A motion
    /// that is not usable (not finite) falls back to the filter's own corner and line fit.
    pub fn process_measured(
        &mut self,
        stamp_ns: u64,
        observations: &[MeasuredCorner],
        lines: &[MeasuredLine],
        motion: &MeasuredMotion,
    ) -> Estimate {
        let step = if motion.is_usable() {
            StepMotion::Measured(motion)
        } else {
            StepMotion::Estimate(None)
        };
        self.step(stamp_ns, observations, lines, step)
    }

    fn step(
        &mut self,
        stamp_ns: u64,
        observations: &[MeasuredCorner],
        lines: &[MeasuredLine],
        step: StepMotion<'_>,
    ) -> Estimate {
        let start = Instant::now();
        let config = &self.config;
        let prepared: Vec<Prepared> = observations
            .iter()
            .filter_map(|o| {
                Prepared::new(o, OBSERVATION_EXTRA_SIGMA_XY, OBSERVATION_EXTRA_SIGMA_ANGLE)
            })
            .collect();
        self.lines.clear();
        self.lines
            .extend(lines.iter().filter(|l| l.is_well_formed()).copied());
        let motion = match step {
            StepMotion::Estimate(odometry) => {
                self.motion
                    .estimate(stamp_ns, &prepared, &self.lines, odometry)
            }
            StepMotion::Measured(measured) => {
                // The front end's track, as odometry for the corner fit: the covariance
                // of each step turned into the track's frame and summed, as an odometry
                // publisher integrates it (docs/CONVENTIONS.md, "Odometry").
                let before = self.measured_track;
                let turn = rotation3(before.pose.yaw);
                self.measured_track = OdometryInput {
                    pose: before.pose.compose(&measured.increment),
                    covariance: before.covariance + turn * measured.covariance * turn.transpose(),
                };
                // The corner fit still runs every scan, on the front end's track, so its
                // last corners stay the last scan's for a step that comes without a
                // usable measurement. Its result is not taken: the front end registered
                // every beam against its keyframes (and, without odometry, learned the
                // motion along a corridor from what came into view), which a fit of a
                // few corners and lines only makes noisier.
                self.motion
                    .estimate(stamp_ns, &prepared, &self.lines, Some(&self.measured_track));
                Motion {
                    delta: measured.increment,
                    covariance: measured.covariance,
                    source: MotionSource::Measured,
                    inliers: 0,
                }
            }
        };
        self.dead_reckoning = self.dead_reckoning.compose(&motion.delta);
        self.scan_log.push(stamp_ns, self.dead_reckoning);
        let motion_done = Instant::now();

        // The first scan defines the map frame: nothing moves.
        let noise = if self.scans == 0 {
            MotionNoise::NONE
        } else {
            MotionNoise::for_step(&motion, config)
        };
        // On this thread: a particle's prediction is a few normal draws (about 0.1 us),
        // and handing a parallel pass to the thread pool and back costs tens of
        // microseconds (seed-hall, 100 particles: 7-14 us here, 23-190 us as a pass).
        if self.scans > 0 {
            let (scan, delta) = (self.scans, motion.delta);
            for (i, particle) in self.particles.iter_mut().enumerate() {
                let mut rng = self.streams.particle(scan, i);
                particle.increment = predict::sample(&delta, &noise, &mut rng);
                particle.pose = particle.pose.compose(&particle.increment);
            }
        }
        let predict_done = Instant::now();

        self.path_length += motion.delta.translation_norm();
        // With measured motion the corners wait until the robot has moved (see
        // `SlamConfig::update_min_distance`); the particles' uncertainty relative to their
        // maps is then the noise of every step since.
        self.since_update.distance += motion.delta.translation_norm();
        self.since_update.rotation += motion.delta.yaw.abs();
        self.since_update.noise += noise.covariance();
        let skip = matches!(step, StepMotion::Measured(_))
            && self.scans > 0
            && config.update_min_distance > 0.0
            && self.since_update.distance < config.update_min_distance
            && self.since_update.rotation < config.update_min_rotation;
        if skip {
            // No pose kept: the scan follows the last kept one by the front end's motion.
            for particle in &mut self.particles {
                particle.path.pass();
            }
            return self.finish([start, motion_done, predict_done, predict_done], false);
        }
        let variance = std::mem::take(&mut self.since_update).noise;
        self.updates += 1;
        self.gates.ensure(prepared.len());
        // The grid judges the scan only where the saved map has seen what the beams hit.
        let best_pose = self.particles.get(self.best).map(|p| p.pose);
        let judged = match (&mut self.saved_grid, best_pose) {
            (Some(grid), Some(pose)) => grid.select_known(&pose, saved_grid::MIN_KNOWN),
            _ => false,
        };
        let saved_grid = self.saved_grid.as_ref().filter(|_| judged);
        // Back on the grid after a stretch off it (`saved_grid::SEARCH_AFTER_M`), the
        // particles climb once from the search's wider steps.
        let off_grid = self.path_length - self.on_grid_at;
        let returned = judged && off_grid >= saved_grid::SEARCH_AFTER_M;
        let drift = drift_off_grid(off_grid);
        if judged {
            self.on_grid_at = self.path_length;
        }
        let context = ScanContext {
            observations: &prepared,
            pose: PoseUncertainty::from_variances(
                variance[(0, 0)],
                variance[(1, 1)],
                variance[(2, 2)],
            ),
            gates: &self.gates,
            config,
            // The first pose is the map frame: nothing to draw.
            draw_pose: self.scans > 0,
            cos_half_fov: (0.5 * config.view_fov).cos(),
        };
        let (streams, scan) = (&self.streams, self.scans);
        // Fixed chunks, each with its own scratch kept across scans: the buffers grow once,
        // not at every split of the work.
        let chunks = self.particles.len().div_ceil(PARTICLES_PER_TASK);
        self.scratch.resize_with(chunks, Scratch::default);
        let update_chunk = |chunk: usize, (particles, scratch): (&mut [Particle], &mut Scratch)| {
            for (k, particle) in particles.iter_mut().enumerate() {
                let mut rng = streams.proposal(scan, chunk * PARTICLES_PER_TASK + k);
                if let Some(grid) = saved_grid {
                    particle.pose = if returned {
                        grid.search(particle.pose, &drift, saved_grid::PULL)
                    } else {
                        grid.refine(particle.pose, saved_grid::PULL)
                    };
                }
                particle.log_weight += particle.update(&context, scratch, &mut rng);
                particle.path.push(StampedPose {
                    stamp_ns,
                    pose: particle.pose,
                });
            }
        };
        if rayon::current_num_threads() > 1 {
            self.particles
                .par_chunks_mut(PARTICLES_PER_TASK)
                .zip(self.scratch.par_iter_mut())
                .enumerate()
                .for_each(|(chunk, work)| update_chunk(chunk, work));
        } else {
            // One worker runs the chunks in order anyway: on this thread, without the
            // hand-off to the pool and back.
            self.particles
                .chunks_mut(PARTICLES_PER_TASK)
                .zip(self.scratch.iter_mut())
                .enumerate()
                .for_each(|(chunk, work)| update_chunk(chunk, work));
        }
        let update_done = Instant::now();
        self.finish([start, motion_done, predict_done, update_done], true)
    }

    /// Weighs and resamples, judges the saved map's fit after an update (`updated`),
    /// counts the scan and reports it; `times` are the step's start and the ends of its
    /// motion estimate, prediction and update.
    fn finish(&mut self, times: [Instant; 4], updated: bool) -> Estimate {
        let [start, motion_done, predict_done, update_done] = times;
        let (effective_particles, best, mean, covariance) = self.weigh_and_resample();
        if let Some(grid) = &mut self.saved_grid {
            // At updates only: the scans between them see the same walls from a few
            // centimetres on, and would only weigh the fit towards where the robot stood.
            if updated {
                grid.judge_fit(&best, &mut self.map_fit);
            }
            grid.clear_scan();
        }
        if self.map_fit.verdict() == FitVerdict::DoesNotFit && self.set_aside_at.is_none() {
            self.set_aside_saved_map();
        }
        let map_size = self
            .particles
            .get(self.best)
            .map_or(0, |p| p.map.confirmed_count());
        self.scans += 1;
        let end = Instant::now();
        Estimate {
            best,
            mean,
            covariance,
            effective_particles,
            particle_count: self.particles.len(),
            dead_reckoning: self.dead_reckoning,
            map_size,
            timing: StageTiming::between([start, motion_done, predict_done, update_done, end]),
        }
    }

    /// Leaves the saved map out from now on: its grid, and its corners from every
    /// particle's map (those the run observed too: on a map that does not fit the scans,
    /// their pairings were wrong).
    fn set_aside_saved_map(&mut self) {
        self.saved_grid = None;
        self.set_aside_at = Some(self.scans);
        for particle in &mut self.particles {
            for id in 0..self.saved_corners {
                particle.map.remove(id, CONFIRM_OBSERVATIONS);
            }
        }
    }

    /// Normalises the weights, takes the statistics of the weighted particles and resamples
    /// when too few particles carry the weight. Returns the effective particle count, the
    /// best pose, the mean pose and the spread.
    fn weigh_and_resample(&mut self) -> (f64, Pose2, Pose2, nalgebra::Matrix3<f64>) {
        self.log_weights.clear();
        self.log_weights
            .extend(self.particles.iter().map(|p| p.log_weight));
        normalise(&self.log_weights, &mut self.weights);
        let effective = effective_sample_size(&self.weights);
        let best = heaviest(&self.weights);
        self.best = best;
        let best_pose = self.particles.get(best).map_or(Pose2::IDENTITY, |p| p.pose);
        let weighted = |pose_of: fn(&Particle) -> Pose2| {
            let samples = self.particles.iter().zip(&self.weights);
            weighted_mean_and_covariance(samples.map(|(p, w)| (pose_of(p), *w)))
        };
        let (mean, covariance) = weighted(|p| p.pose);
        let (increment, _) = weighted(|p| p.increment);
        self.motion.set_last_motion(increment);

        let n = self.particles.len();
        if effective < RESAMPLE_THRESHOLD * n as f64 {
            let u = self.streams.resample(self.scans).random::<f64>();
            systematic(&self.weights, u, &mut self.parents);
            self.resamplings += 1;
            // Cloning a particle copies its pose and three pointers of its map: the copies
            // share every corner until one of them writes.
            let resampled: Vec<Particle> = self
                .parents
                .iter()
                .map(|&i| Particle {
                    log_weight: 0.0,
                    ..self.particles[i].clone()
                })
                .collect();
            self.particles = resampled;
            self.best = self.parents.iter().position(|&p| p == best).unwrap_or(0);
        } else {
            // Keep the log weights near zero so they never lose precision.
            let total = log_sum_exp(&self.log_weights);
            if total.is_finite() {
                for p in &mut self.particles {
                    p.log_weight -= total;
                }
            }
        }
        (effective, best_pose, mean, covariance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Matrix4};

    fn observation(x: f64, y: f64, heading: f64, angle: f64) -> MeasuredCorner {
        MeasuredCorner {
            x,
            y,
            heading,
            angle,
            covariance: Matrix4::identity() * 1e-4,
        }
    }

    fn scan() -> Vec<MeasuredCorner> {
        vec![
            observation(3.0, 1.0, 0.5, 1.2),
            observation(5.0, -2.0, 2.0, 1.6),
            observation(-1.0, 4.0, -1.0, 1.9),
            observation(7.0, 3.0, 3.0, 1.4),
        ]
    }

    #[test]
    fn a_measured_motion_moves_the_particles_and_the_best_path_follows() {
        let config = SlamConfig {
            particles: 20,
            ..SlamConfig::default()
        };
        let mut slam = FastSlam::new(config, 5).unwrap();
        let step = MeasuredMotion {
            increment: Pose2::new(0.1, 0.0, 0.02),
            covariance: Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-6, 1e-6, 1e-7)),
            wheel_increment: None,
        };
        // A front end's first scan has no motion.
        let first = MeasuredMotion {
            increment: Pose2::IDENTITY,
            ..step
        };
        let mut truth = Pose2::IDENTITY;
        for k in 0..50 {
            let motion = if k == 0 { &first } else { &step };
            let estimate = slam.process_measured(k * 25_000_000, &[], &[], motion);
            truth = truth.compose(&motion.increment);
            // The front end's step is the dead reckoning, exactly.
            assert!((estimate.dead_reckoning.x - truth.x).abs() < 1e-9);
        }
        let path = slam.best_path();
        assert_eq!(path.len(), 50);
        assert_eq!(path[49].stamp_ns, 49 * 25_000_000);
        let end = path[49].pose;
        // 49 steps of 0.1 m spread by the drift of 4.9 m of path: millimetres.
        assert!(
            (end.x - truth.x).hypot(end.y - truth.y) < 0.01,
            "{end:?} vs {truth:?}"
        );
    }

    #[test]
    fn corners_update_the_particles_once_the_robot_has_moved_half_a_metre() {
        // 40 scans 5 cm apart (2 m) in front of the same corners: updates at the first
        // scan and then every 0.5 m, not at every scan.
        let world = [
            (3.0, 1.0, 0.5, 1.2),
            (5.0, -2.0, 2.0, 1.6),
            (4.0, 4.0, -1.0, 1.9),
        ];
        let step = MeasuredMotion {
            increment: Pose2::new(0.05, 0.0, 0.0),
            covariance: Matrix3::identity() * 1e-6,
            wheel_increment: None,
        };
        let observed = |update_min_distance: f64| {
            let config = SlamConfig {
                particles: 10,
                update_min_distance,
                ..SlamConfig::default()
            };
            let mut slam = FastSlam::new(config, 4).unwrap();
            for k in 0..40u32 {
                let x = 0.05 * f64::from(k);
                let scan: Vec<MeasuredCorner> = world
                    .iter()
                    .map(|&(cx, cy, heading, angle)| observation(cx - x, cy, heading, angle))
                    .collect();
                slam.process_measured(u64::from(k) * 25_000_000, &scan, &[], &step);
            }
            let stats = slam.stats();
            assert_eq!(stats.scans, 40);
            let seen = slam
                .best_map()
                .iter()
                .map(|c| c.observations)
                .collect::<Vec<_>>();
            (seen, stats.updates)
        };
        // The first scan starts them; then one update per 0.5 m of the 1.95 m travelled
        // (the distance summed in floating point may cross a threshold one scan late).
        let (gated, updates) = observed(0.5);
        assert_eq!(gated.len(), 3, "{gated:?}");
        assert!(gated.iter().all(|&n| u64::from(n) == updates), "{gated:?}");
        assert!(updates == 4 || updates == 5, "{updates}");
        assert_eq!(observed(0.0), (vec![40, 40, 40], 40));
    }

    #[test]
    fn resampled_particles_share_maps_and_writes_stay_private() {
        let config = SlamConfig {
            particles: 50,
            ..SlamConfig::default()
        };
        // A big map (5000 corners on a grid far from the robot) plus what the scans add.
        let prior: Vec<MapCorner> = (0..5000)
            .map(|i| MapCorner {
                x: 100.0 + f64::from(i % 100),
                y: f64::from(i / 100),
                heading: 0.0,
                angle: 1.5,
                covariance: Matrix4::identity() * 1e-4,
                observations: 5,
            })
            .collect();
        let mut slam = FastSlam::with_prior_map(config, 3, &prior).unwrap();
        for k in 0..3 {
            slam.process(k * 25_000_000, &scan(), &[], None);
        }
        // Make one particle carry all the weight: everyone becomes its copy.
        for (i, p) in slam.particles.iter_mut().enumerate() {
            p.log_weight = if i == 7 { 0.0 } else { -1e3 };
        }
        slam.weigh_and_resample();
        assert_eq!(slam.particles.len(), 50);
        assert_eq!(slam.particles[0].map.confirmed_count(), 5000 + 4);
        // 50 pointer copies of one map, not 50 maps of 5000 corners.
        assert_eq!(slam.particles[0].map.corner_tree_holders(), 50);
        assert!(
            slam.particles
                .iter()
                .all(|p| p.map.shares_corners_with(&slam.particles[0].map))
        );

        let before: Vec<_> = slam.particles[1].map.confirmed(2);
        let mut changed = slam.particles[0].map.clone();
        let id = 0;
        let corner = *changed.get(id).unwrap();
        changed.update(id, 2, |c| (c.mean.add_scalar(0.5), c.covariance));
        slam.particles[0].map = changed;
        assert_eq!(slam.particles[1].map.confirmed(2), before);
        assert!(
            (slam.particles[0].map.get(id).unwrap().mean.x - corner.mean.x - 0.5).abs() < 1e-12
        );
        assert_eq!(slam.particles[1].map.corner_tree_holders(), 49);
    }
}
