//! Localization on a saved map: Monte Carlo localization (AMCL's scheme) over the map's
//! occupancy grid. The particles move by the front end's measured steps (spread between
//! them and the wheels' where the front end weighed the wheels against the scan), the beams
//! weight them through the grid's likelihood field (once converged, against the wall faces
//! a beam going their way can end on: [`FacedField`]), and KLD-sampling sizes the particle
//! set at each resampling: many while the pose is uncertain, few once it is not. The map is
//! shared and never changes.

use std::f64::consts::PI;
use std::time::Instant;

use ipc_types::StageTiming;
use nalgebra::Matrix3;
use rand::Rng;
use rayon::prelude::*;

use crate::filter::estimate::{Estimate, weighted_mean_and_covariance};
use crate::filter::observation::MeasuredMotion;
use crate::filter::resample::{effective_sample_size, heaviest, normalise};
use crate::filter::rng::Streams;
use crate::localize::hill_climb::{HillClimb, scan_score};
use crate::localize::kld::{Bins, kld_count};
use crate::localize::likelihood_field::{BEAM_FLOOR, BeamModel, LikelihoodField, MAX_DISTANCE_M};
use crate::localize::map_fit::FitField;
use crate::localize::tracking_field::{TrackingField, beam_bearings};
use crate::localize_config::LocalizeConfig;
use crate::motion::predict::{self, MotionNoise};
use saved_map::GridMap;
use slam_eval::MapFit;
use slam_geom::Pose2;
use stage_kit::SettingError;

/// KLD-sampling's bound on the divergence between the particles and the posterior: smaller
/// asks for more particles everywhere, and 5 % keeps a converged cloud near
/// `min_particles`.
const KLD_EPSILON: f64 = 0.05;
/// Upper standard normal quantile of KLD-sampling's confidence: 2.326 is 99 %.
const KLD_Z: f64 = 2.326;
/// KLD-sampling's histogram bins: edge in x and y, metres, and in yaw, radians. Coarser
/// than the converged spread, so that a converged cloud fills a few bins and KLD keeps few
/// particles; fine enough that a spread cloud fills many.
const KLD_BIN_XY: f64 = 0.5;
const KLD_BIN_YAW: f64 = 10f64.to_radians();
/// Standard deviation of a beam end's distance to the nearest wall while the particles
/// search, metres: four times the converged figure, a smooth field on which a particle some
/// way off the true pose still scores well.
const SEARCH_SIGMA_HIT: f64 = 0.2;
/// Each beam's log-likelihood is multiplied by this: beams of one scan are not independent
/// (AMCL cubes and sums for the same reason), and a cloud that believes every beam
/// collapses before the robot has moved enough to tell places apart.
const BEAM_EXPONENT: f64 = 0.3;
/// A scan's likelihood is tempered (its exponent lowered) so that at least this fraction
/// of the particles stays effective: no single scan collapses a spread cloud.
const MIN_EFFECTIVE_FRACTION: f64 = 0.1;
/// While the particles search, each climbs the scan's likelihood on every this many of the
/// weighting beams: the climb runs on every particle dozens of times, and a quarter of the
/// beams still places it.
const REFINE_BEAM_STRIDE: usize = 4;
/// Converged: the weighted particles' position spread (the larger standard deviation of
/// their x-y covariance) under this, metres, ...
const CONVERGED_SIGMA_XY: f64 = 0.15;
/// ... and their yaw spread under this, radians: a spread of a hand's width and a few
/// degrees is one place, not several.
const CONVERGED_SIGMA_YAW: f64 = 0.05;
/// Once converged, the particles count as lost only when their spread exceeds this many
/// times [`CONVERGED_SIGMA_XY`] or [`CONVERGED_SIGMA_YAW`]: a cloud that widens for a moment
/// (the front end's step was off, a corridor says little along itself) keeps tracking on
/// the sharp field instead of falling back to the global search, whose smooth field and
/// wide hill-climbing steps can carry it to another place.
const LOST_SIGMA_FACTOR: f64 = 2.0;

/// Bisection steps of the tempering exponent: 2^-12 of [`BEAM_EXPONENT`] is fine enough.
const TEMPERING_STEPS: usize = 12;

/// Particles per parallel task of the hill-climb.
const CLIMB_PARTICLES_PER_TASK: usize = 256;

/// Fills `points` with the ends (sensor frame) of at most `beams` of the scan's valid
/// beams, spread evenly over them, the first and the last included; false when the scan
/// has no valid beam.
pub fn sample_beam_ends(scan: &ScanRanges<'_>, beams: usize, points: &mut Vec<[f64; 2]>) -> bool {
    points.clear();
    let valid: Vec<usize> = scan
        .ranges
        .iter()
        .enumerate()
        .filter(|(_, r)| {
            let r = f64::from(**r);
            r.is_finite() && r >= scan.range_min && r <= scan.range_max
        })
        .map(|(i, _)| i)
        .collect();
    if valid.is_empty() {
        return false;
    }
    let take = beams.min(valid.len());
    for k in 0..take {
        let i = valid[k * valid.len() / take];
        let bearing = scan.angle_min + i as f64 * scan.angle_increment;
        let r = f64::from(scan.ranges[i]);
        points.push([r * bearing.cos(), r * bearing.sin()]);
    }
    true
}

/// Where the robot starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// Near a known pose: the particles spread around it by the configured
    /// `initial_sigma_xy` / `initial_sigma_yaw`.
    Known(Pose2),
    /// Anywhere: the particles spread uniformly over the grid's free cells, yaw uniform.
    Global,
}

/// One scan's ranges with their geometry, as in `LaserScan` (docs/CONVENTIONS.md).
#[derive(Debug, Clone, Copy)]
pub struct ScanRanges<'a> {
    pub angle_min: f64,
    pub angle_increment: f64,
    pub range_min: f64,
    pub range_max: f64,
    pub ranges: &'a [f32],
}

/// The estimate after one scan, with whether the particles have converged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Localization {
    pub estimate: Estimate,
    /// The weighted particles' spread is under 0.15 m and 0.05 rad (once converged, under
    /// twice that).
    pub converged: bool,
}

/// What the localizer did over a run, for its closing summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LocalizeStats {
    pub scans: u64,
    /// Scans whose beams weighted the particles.
    pub updates: u64,
    /// The first scan (from 0) at which the particles had converged.
    pub converged_at: Option<u64>,
    /// Scans that came without their beams (lost in a real-time run): moved, not weighted.
    pub scans_without_beams: u64,
    /// Front-end steps that were not usable: the particles stood still.
    pub motions_not_usable: u64,
    /// Scans without a valid beam.
    pub scans_without_valid_beams: u64,
    /// The most particles held at once.
    pub peak_particles: usize,
    /// Weightings whose likelihood was tempered to keep enough particles effective.
    pub tempered_updates: u64,
    /// The beams of the scans that weighted the converged particles, judged against the
    /// map from the estimate: how well the map explains the scans.
    pub map_fit: MapFit,
}

/// Monte Carlo localization on a fixed grid. The result depends only on the configuration,
/// the seed and the inputs.
#[derive(Debug, Clone)]
pub struct Localizer {
    config: LocalizeConfig,
    /// The grid's field for tracking, sharp ...
    field: TrackingField,
    /// ... and for the search, smooth: a particle some way off the true pose still scores
    /// well there, and a map's small flaws do not decide between places that look alike.
    search_field: LikelihoodField,
    /// The grid as the map's fit judges a beam.
    fit_field: FitField,
    streams: Streams,
    poses: Vec<Pose2>,
    log_weights: Vec<f64>,
    weights: Vec<f64>,
    /// The front end's motion since the beams last weighted the particles, as one step:
    /// the net motion, so that a standing robot's scan-matching jitter, millimetres back
    /// and forth, never adds up to a move (AMCL measures its odometry the same way).
    since_weighted: Pose2,
    dead_reckoning: Pose2,
    /// This scan's beam ends in the sensor frame ...
    points: Vec<[f64; 2]>,
    /// ... and the bearings of their beams.
    bearings: Vec<f64>,
    /// The ends of this scan's beams the map's fit judges, sensor frame.
    fit_points: Vec<[f64; 2]>,
    /// Each particle's log-likelihood of this scan's beams.
    scan_log_likelihoods: Vec<f64>,
    bins: Bins,
    /// Corners of the map, reported with each estimate.
    map_corners: usize,
    stats: LocalizeStats,
    /// Whether the last estimate had converged.
    converged: bool,
}

/// Error of [`Localizer::new`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocalizeError {
    #[error(transparent)]
    Config(#[from] SettingError),
    #[error("the map's occupancy grid has no free cell to spread the particles over")]
    NoFreeSpace,
}

impl Localizer {
    /// Particles placed by `start` on `grid`, drawn from `seed`; `map_corners` is only
    /// reported.
    pub fn new(
        config: LocalizeConfig,
        grid: &GridMap,
        start: Start,
        seed: u64,
        map_corners: usize,
    ) -> Result<Self, LocalizeError> {
        config.validate()?;
        let field = TrackingField::new(grid, &config);
        let search_model = BeamModel {
            sigma_hit: SEARCH_SIGMA_HIT,
            floor: BEAM_FLOOR,
        };
        let search_field = LikelihoodField::new(grid, MAX_DISTANCE_M, search_model);
        let fit_field = FitField::new(grid, slam_eval::MAP_FIT_WITHIN_M);
        let streams = Streams::new(seed);
        let mut rng = streams.resample(u64::MAX);
        let poses: Vec<Pose2> = match start {
            Start::Known(pose) => {
                // Independent normal offsets in x, y and yaw, as a step's noise.
                let spread = MotionNoise {
                    sigma_xy: config.initial_sigma_xy,
                    sigma_yaw: config.initial_sigma_yaw,
                };
                (0..config.min_particles.max(1))
                    .map(|_| predict::sample(&pose, &spread, &mut rng))
                    .collect()
            }
            Start::Global => {
                let cells = search_field.free_cells();
                if cells == 0 {
                    return Err(LocalizeError::NoFreeSpace);
                }
                let mut poses = Vec::with_capacity(config.max_particles);
                while poses.len() < config.max_particles {
                    let Some((centre, edge)) = search_field.free_cell(rng.random_range(0..cells))
                    else {
                        continue;
                    };
                    poses.push(Pose2::new(
                        centre[0] + edge * (rng.random::<f64>() - 0.5),
                        centre[1] + edge * (rng.random::<f64>() - 0.5),
                        rng.random_range(-PI..PI),
                    ));
                }
                poses
            }
        };
        let n = poses.len();
        Ok(Self {
            field,
            search_field,
            fit_field,
            streams,
            log_weights: vec![0.0; n],
            weights: Vec::new(),
            since_weighted: Pose2::IDENTITY,
            dead_reckoning: Pose2::IDENTITY,
            points: Vec::new(),
            bearings: Vec::new(),
            fit_points: Vec::new(),
            scan_log_likelihoods: Vec::new(),
            bins: Bins::default(),
            map_corners,
            stats: LocalizeStats {
                peak_particles: n,
                ..LocalizeStats::default()
            },
            poses,
            config,
            converged: false,
        })
    }

    /// What the localizer did so far.
    pub fn stats(&self) -> LocalizeStats {
        self.stats
    }

    /// Every particle's pose.
    pub fn particle_poses(&self) -> &[Pose2] {
        &self.poses
    }

    /// Every particle's log weight, in the order of [`Localizer::particle_poses`].
    pub fn particle_log_weights(&self) -> &[f64] {
        &self.log_weights
    }

    /// Moves the particles by the front end's step and, once the robot has moved enough
    /// (and at the first scan), weights them by the scan's beams and resamples. `scan` is
    /// `None` when the scan's beams did not arrive.
    pub fn step(&mut self, motion: &MeasuredMotion, scan: Option<&ScanRanges<'_>>) -> Localization {
        let start = Instant::now();
        let first = self.stats.scans == 0;
        let (delta, wheels) = if motion.is_usable() {
            let wheels = motion
                .wheel_increment
                .filter(|w| [w.x, w.y, w.yaw].iter().all(|v| v.is_finite()));
            (motion.increment, wheels)
        } else {
            self.stats.motions_not_usable += 1;
            (Pose2::IDENTITY, None)
        };
        self.dead_reckoning = self.dead_reckoning.compose(&delta);
        let motion_done = Instant::now();
        if !first {
            self.predict(&delta, wheels.as_ref());
        }
        self.since_weighted = self.since_weighted.compose(&delta);
        let predict_done = Instant::now();

        let due = first
            || self.since_weighted.translation_norm() >= self.config.update_min_distance
            || self.since_weighted.yaw.abs() >= self.config.update_min_rotation;
        let weighted = match scan {
            Some(scan) if due => self.weigh(scan),
            Some(_) => false,
            None => {
                self.stats.scans_without_beams += 1;
                false
            }
        };
        let update_done = Instant::now();
        if weighted {
            self.since_weighted = Pose2::IDENTITY;
        }
        // Between weightings the statistics are those of the cloud as it moved.
        let (best, mean, covariance, effective) = self.summarise_and_resample(weighted);
        let converged = self.is_converged(&covariance);
        self.converged = converged;
        if let Some(scan) = scan.filter(|_| weighted && converged) {
            // At the estimate the run publishes, whatever the beam count weighting takes.
            sample_beam_ends(
                scan,
                slam_eval::MAP_FIT_BEAMS_PER_SCAN,
                &mut self.fit_points,
            );
            self.fit_field
                .judge(&self.fit_points, &mean, &mut self.stats.map_fit);
        }
        if converged && self.stats.converged_at.is_none() {
            self.stats.converged_at = Some(self.stats.scans);
        }
        self.stats.scans += 1;
        let end = Instant::now();
        Localization {
            estimate: Estimate {
                best,
                mean,
                covariance,
                effective_particles: effective,
                particle_count: self.poses.len(),
                dead_reckoning: self.dead_reckoning,
                map_size: self.map_corners,
                timing: StageTiming::between([start, motion_done, predict_done, update_done, end]),
            },
            converged,
        }
    }

    /// Each particle moves by `delta` in its own frame, spread by the configured drift.
    /// Given the `wheels`' step too, each moves to a position drawn uniformly between the
    /// two steps': the fit and the wheels err independently, and where they disagree (a
    /// fit that slid along a corridor, or overruled the wheels and was wrong) the robot is
    /// as likely anywhere between them, further than the drift spreads the particles over
    /// a step. The beams then decide; where the two agree nothing changes. The heading
    /// stays the front end's: spread between the two as well, the localized headings
    /// erred more against the benchmark logs' ground truth.
    fn predict(&mut self, delta: &Pose2, wheels: Option<&Pose2>) {
        let c = &self.config;
        let (t, r) = (delta.translation_norm(), delta.yaw.abs());
        let noise = MotionNoise {
            sigma_xy: (c.xy_variance_per_metre * t + c.xy_variance_per_radian * r).sqrt(),
            sigma_yaw: (c.yaw_variance_per_metre * t + c.yaw_variance_per_radian * r).sqrt(),
        };
        let scan = self.stats.scans;
        for (i, pose) in self.poses.iter_mut().enumerate() {
            let mut rng = self.streams.particle(scan, i);
            let step = match wheels {
                Some(wheels) => {
                    let share = rng.random::<f64>();
                    Pose2::new(
                        delta.x + share * (wheels.x - delta.x),
                        delta.y + share * (wheels.y - delta.y),
                        delta.yaw,
                    )
                }
                None => *delta,
            };
            let noisy = predict::sample(&step, &noise, &mut rng);
            *pose = pose.compose(&noisy);
        }
    }

    /// Adds every particle's log-likelihood of the scan's beams; false when the scan has
    /// no valid beam.
    fn weigh(&mut self, scan: &ScanRanges<'_>) -> bool {
        if !sample_beam_ends(scan, self.config.beams, &mut self.points) {
            self.stats.scans_without_valid_beams += 1;
            return false;
        }
        self.scan_log_likelihoods.clear();
        if self.converged {
            // Only the faced field reads them; a scan's worth of atan2 is nothing beside
            // the particles' lookups.
            beam_bearings(&self.points, &mut self.bearings);
            for pose in &self.poses {
                self.scan_log_likelihoods.push(self.field.scan_score(
                    &self.points,
                    &self.bearings,
                    pose,
                ));
            }
        } else {
            let field = &self.search_field;
            // Each particle moves uphill on the scan's likelihood before it is weighted (a
            // few steps of halving size): a global start then needs far fewer particles
            // than would have to fall on the true pose by chance.
            let coarse: Vec<[f64; 2]> = self
                .points
                .iter()
                .step_by(REFINE_BEAM_STRIDE)
                .copied()
                .collect();
            self.poses
                .par_iter_mut()
                .with_min_len(CLIMB_PARTICLES_PER_TASK)
                .for_each(|pose| *pose = HillClimb::SEARCH.climb(field, &coarse, *pose));
            for pose in &self.poses {
                self.scan_log_likelihoods
                    .push(scan_score(field, &self.points, pose));
            }
        }
        let exponent = self.tempering();
        for (log_weight, ll) in self.log_weights.iter_mut().zip(&self.scan_log_likelihoods) {
            *log_weight += exponent * ll;
        }
        self.stats.updates += 1;
        true
    }

    /// The exponent of this scan's likelihood: [`BEAM_EXPONENT`], or, while the particles
    /// have not converged, less when that would leave fewer than
    /// [`MIN_EFFECTIVE_FRACTION`] of the particles effective. One scan
    /// then cannot collapse a spread cloud onto whichever wrong place happens to match it
    /// best: the cloud narrows over several scans, as the robot moves and places that
    /// looked alike stop looking alike.
    fn tempering(&mut self) -> f64 {
        let full = BEAM_EXPONENT;
        // Converged, the cloud is one place: every scan counts in full, or the estimate
        // would lag behind the front end's drift.
        if self.converged {
            return full;
        }
        let target = MIN_EFFECTIVE_FRACTION * self.poses.len() as f64;
        let effective = |beta: f64, work: &mut Vec<f64>, weights: &mut Vec<f64>| {
            work.clear();
            work.extend(
                self.log_weights
                    .iter()
                    .zip(&self.scan_log_likelihoods)
                    .map(|(w, ll)| w + beta * ll),
            );
            normalise(work, weights);
            effective_sample_size(weights)
        };
        let (mut work, mut weights) = (Vec::new(), Vec::new());
        if effective(full, &mut work, &mut weights) >= target {
            return full;
        }
        // The effective count falls as the exponent grows: bisect.
        let (mut low, mut high) = (0.0, full);
        for _ in 0..TEMPERING_STEPS {
            let mid = 0.5 * (low + high);
            if effective(mid, &mut work, &mut weights) >= target {
                low = mid;
            } else {
                high = mid;
            }
        }
        self.stats.tempered_updates += 1;
        low
    }

    /// The weighted statistics; after a weighting, a KLD-sized resampling. Returns the
    /// best pose, the mean, the covariance and the effective particle count.
    fn summarise_and_resample(&mut self, resample: bool) -> (Pose2, Pose2, Matrix3<f64>, f64) {
        normalise(&self.log_weights, &mut self.weights);
        let effective = effective_sample_size(&self.weights);
        let best = heaviest(&self.weights);
        let best_pose = self.poses.get(best).copied().unwrap_or(Pose2::IDENTITY);
        let (mean, covariance) = weighted_mean_and_covariance(
            self.poses.iter().copied().zip(self.weights.iter().copied()),
        );
        if resample {
            self.resample();
        }
        (best_pose, mean, covariance, effective)
    }

    /// Draws the next particle set from the weighted one, as many as KLD-sampling asks for
    /// the bins the draws fill, within `[min_particles, max_particles]`.
    fn resample(&mut self) {
        let c = &self.config;
        let mut cumulative = Vec::with_capacity(self.weights.len());
        let mut total = 0.0;
        for w in &self.weights {
            total += w;
            cumulative.push(total);
        }
        if total.is_nan() || total <= 0.0 {
            return;
        }
        let mut rng = self.streams.resample(self.stats.scans);
        self.bins.clear();
        let mut drawn = Vec::with_capacity(self.poses.len());
        while drawn.len() < c.max_particles {
            let u = rng.random::<f64>() * total;
            let i = cumulative
                .partition_point(|&c| c < u)
                .min(self.poses.len() - 1);
            let pose = self.poses[i];
            drawn.push(pose);
            let bins = self
                .bins
                .insert(pose.x, pose.y, pose.yaw, KLD_BIN_XY, KLD_BIN_YAW);
            if drawn.len() >= c.min_particles && drawn.len() >= kld_count(bins, KLD_EPSILON, KLD_Z)
            {
                break;
            }
        }
        self.poses = drawn;
        self.log_weights.clear();
        self.log_weights.resize(self.poses.len(), 0.0);
        normalise(&self.log_weights, &mut self.weights);
        self.stats.peak_particles = self.stats.peak_particles.max(self.poses.len());
    }

    /// Whether the cloud `covariance` describes has converged: its spread under the
    /// thresholds, or, if it had converged already, under [`LOST_SIGMA_FACTOR`] times them.
    fn is_converged(&self, covariance: &Matrix3<f64>) -> bool {
        let scale = if self.converged {
            LOST_SIGMA_FACTOR
        } else {
            1.0
        };
        let (a, b, d) = (covariance[(0, 0)], covariance[(0, 1)], covariance[(1, 1)]);
        // The larger eigenvalue of the x-y block.
        let largest = 0.5 * (a + d) + (0.25 * (a - d).powi(2) + b * b).sqrt();
        largest.sqrt() < scale * CONVERGED_SIGMA_XY
            && covariance[(2, 2)].sqrt() < scale * CONVERGED_SIGMA_YAW
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use saved_map::{CellState, MapYaml};

    const RESOLUTION: f64 = 0.05;
    const WIDTH: usize = 240;
    const HEIGHT: usize = 140;

    /// A 12 m x 7 m room, walls on its border, an L-shaped wall and a pillar inside so that
    /// no two places look alike.
    fn room() -> GridMap {
        let mut cells = vec![CellState::Free; WIDTH * HEIGHT];
        let mut wall = |c0: usize, r0: usize, c1: usize, r1: usize| {
            for row in r0..=r1 {
                for col in c0..=c1 {
                    cells[row * WIDTH + col] = CellState::Occupied;
                }
            }
        };
        wall(0, 0, WIDTH - 1, 1);
        wall(0, HEIGHT - 2, WIDTH - 1, HEIGHT - 1);
        wall(0, 0, 1, HEIGHT - 1);
        wall(WIDTH - 2, 0, WIDTH - 1, HEIGHT - 1);
        wall(60, 40, 61, 100);
        wall(60, 40, 120, 41);
        wall(170, 90, 180, 100);
        GridMap {
            yaml: MapYaml::trinary("map.pgm", RESOLUTION, [0.0, 0.0]),
            width: WIDTH,
            height: HEIGHT,
            cells,
        }
    }

    /// The ranges a 270-degree scanner at `pose` measures in `grid`, by marching each beam.
    fn scan(grid: &GridMap, pose: Pose2) -> Vec<f32> {
        (0..271)
            .map(|i| {
                let bearing = pose.yaw - 0.75 * PI + f64::from(i) * 1.5 * PI / 270.0;
                let (s, c) = bearing.sin_cos();
                let mut r = 0.0;
                while r < 20.0 {
                    r += 0.01;
                    let (col, row) = (
                        ((pose.x + r * c) / RESOLUTION).floor(),
                        ((pose.y + r * s) / RESOLUTION).floor(),
                    );
                    if col < 0.0 || row < 0.0 || col >= WIDTH as f64 || row >= HEIGHT as f64 {
                        return f32::INFINITY;
                    }
                    if grid.state(col as usize, row as usize) == CellState::Occupied {
                        return r as f32;
                    }
                }
                f32::INFINITY
            })
            .collect()
    }

    fn ranges(ranges: &[f32]) -> ScanRanges<'_> {
        ScanRanges {
            angle_min: -0.75 * PI,
            angle_increment: 1.5 * PI / 270.0,
            range_min: 0.1,
            range_max: 30.0,
            ranges,
        }
    }

    /// The true pose after `k` steps of 5 cm along a loop through the room (3 m along x,
    /// a quarter turn, and so on, from (2, 1.2)), and the step that led there.
    fn loop_pose(k: usize) -> (Pose2, Pose2) {
        let mut truth = Pose2::new(2.0, 1.2, 0.0);
        let mut increment = Pose2::IDENTITY;
        for j in 1..=k {
            increment = if j % 80 == 0 {
                Pose2::new(0.0, 0.0, 0.5 * PI)
            } else {
                Pose2::new(0.05, 0.0, 0.0)
            };
            truth = truth.compose(&increment);
        }
        (truth, increment)
    }

    /// Step `k` of the loop (0: standing at its start): the localizer's error after it
    /// and whether it said it had converged.
    fn drive_step(localizer: &mut Localizer, grid: &GridMap, k: usize) -> (f64, bool) {
        let (truth, increment) = loop_pose(k);
        let beams = scan(grid, truth);
        let motion = MeasuredMotion {
            increment,
            covariance: Matrix3::identity() * 1e-6,
            wheel_increment: None,
        };
        let located = localizer.step(&motion, Some(&ranges(&beams)));
        let mean = located.estimate.mean;
        (
            (mean.x - truth.x).hypot(mean.y - truth.y),
            located.converged,
        )
    }

    /// Drives `steps` steps of the loop, returning the final error and the first step at
    /// which the localizer said it had converged.
    fn drive(localizer: &mut Localizer, grid: &GridMap, steps: usize) -> (f64, Option<usize>) {
        let mut converged = None;
        let mut error = f64::INFINITY;
        for k in 0..steps {
            let (e, c) = drive_step(localizer, grid, k);
            if c && converged.is_none() {
                converged = Some(k);
            }
            error = e;
        }
        (error, converged)
    }

    #[test]
    fn a_known_start_is_tracked_and_corrected() {
        let grid = room();
        let config = LocalizeConfig::default();
        // Started 15 cm and 3 degrees off.
        let start = Start::Known(Pose2::new(2.1, 1.3, 0.05));
        let mut localizer = Localizer::new(config.clone(), &grid, start, 1, 0).unwrap();
        let (error, converged) = drive(&mut localizer, &grid, 200);
        assert!(error < 0.05, "{error}");
        assert!(converged.is_some());
        // Converged, KLD keeps the fewest particles allowed or near it.
        assert!(localizer.particle_poses().len() < 1000);
        // Every beam of the weighting scans, from the estimate, ends on a wall of the map.
        let fit = localizer.stats().map_fit;
        assert!(fit.beams_judged > 271 * 10, "{fit:?}");
        assert!(fit.share().is_some_and(|share| share > 0.98), "{fit:?}");
    }

    /// Times the localizer went from converged to not over `steps` of [`drive`]'s loop.
    fn losses_while_driving(config: LocalizeConfig, steps: usize) -> (usize, f64) {
        let grid = room();
        let start = Start::Known(Pose2::new(2.0, 1.2, 0.0));
        let mut localizer = Localizer::new(config, &grid, start, 5, 0).unwrap();
        let mut losses = 0;
        let mut was_converged = false;
        let mut worst: f64 = 0.0;
        for k in 1..=steps {
            let (error, converged) = drive_step(&mut localizer, &grid, k);
            if was_converged && !converged {
                losses += 1;
            }
            if was_converged {
                worst = worst.max(error);
            }
            was_converged = converged;
        }
        (losses, worst)
    }

    #[test]
    fn a_cloud_that_widens_for_a_moment_keeps_tracking() {
        // Drift eight times the default: between weightings the cloud widens past the
        // converged thresholds now and then (with the thresholds alone, without
        // `LOST_SIGMA_FACTOR`, it is lost now and then over the drive).
        let noisy = LocalizeConfig {
            xy_variance_per_metre: 0.04,
            xy_variance_per_radian: 0.04,
            yaw_variance_per_metre: 0.016,
            yaw_variance_per_radian: 0.08,
            ..LocalizeConfig::default()
        };
        let (losses, worst) = losses_while_driving(noisy, 400);
        assert_eq!(losses, 0);
        assert!(worst < 0.2, "{worst}");
    }

    #[test]
    fn a_global_start_converges_on_the_true_pose_with_fewer_particles() {
        let grid = room();
        let config = LocalizeConfig {
            max_particles: 20_000,
            ..LocalizeConfig::default()
        };
        let mut localizer = Localizer::new(config.clone(), &grid, Start::Global, 3, 0).unwrap();
        assert_eq!(localizer.particle_poses().len(), 20_000);
        let (error, converged) = drive(&mut localizer, &grid, 200);
        assert!(converged.is_some_and(|k| k < 150), "{converged:?}");
        assert!(error < 0.1, "{error}");
        assert!(localizer.particle_poses().len() < 2_000);
        assert_eq!(localizer.stats().peak_particles, 20_000);
    }

    #[test]
    fn with_the_wheels_step_the_particles_spread_between_the_two_odometers() {
        let grid = room();
        // No drift and no weighting after the first scan: the spread is the wheels' alone.
        let config = LocalizeConfig {
            xy_variance_per_metre: 0.0,
            xy_variance_per_radian: 0.0,
            yaw_variance_per_metre: 0.0,
            yaw_variance_per_radian: 0.0,
            initial_sigma_xy: 0.0,
            initial_sigma_yaw: 0.0,
            update_min_distance: 100.0,
            update_min_rotation: 100.0,
            ..LocalizeConfig::default()
        };
        let start = Pose2::new(2.0, 1.2, 0.3);
        let mut localizer = Localizer::new(config, &grid, Start::Known(start), 1, 0).unwrap();
        let beams = scan(&grid, start);
        localizer.step(&MeasuredMotion::standing_still(), Some(&ranges(&beams)));
        let fit = Pose2::new(0.035, 0.0, 0.01);
        let wheels = Pose2::new(0.05, 0.004, 0.03);
        let motion = MeasuredMotion {
            increment: fit,
            covariance: Matrix3::identity() * 1e-6,
            wheel_increment: Some(wheels),
        };
        localizer.step(&motion, Some(&ranges(&beams)));
        let shares: Vec<f64> = localizer
            .particle_poses()
            .iter()
            .map(|pose| {
                let step = start.between(pose);
                assert!((step.yaw - fit.yaw).abs() < 1e-12, "{step:?}");
                let share = (step.x - fit.x) / (wheels.x - fit.x);
                assert!((0.0..=1.0).contains(&share), "{step:?}");
                assert!((step.y - share * wheels.y).abs() < 1e-12, "{step:?}");
                share
            })
            .collect();
        let lowest = shares.iter().copied().fold(f64::INFINITY, f64::min);
        let highest = shares.iter().copied().fold(0.0, f64::max);
        assert!(lowest < 0.05 && highest > 0.95, "{lowest} {highest}");
    }

    /// The largest error over the first straight of the loop when the front end falls 30 %
    /// short over 0.6 m of it (a fit sliding along a corridor) while the wheels do not,
    /// with or without the wheels' step given.
    fn worst_error_with_a_short_front_end(wheels_given: bool) -> f64 {
        let grid = room();
        let start = Start::Known(Pose2::new(2.0, 1.2, 0.0));
        let mut localizer = Localizer::new(LocalizeConfig::default(), &grid, start, 7, 0).unwrap();
        let mut worst: f64 = 0.0;
        for k in 0..50 {
            let (truth, increment) = loop_pose(k);
            let short = (10..22).contains(&k);
            let motion = MeasuredMotion {
                increment: if short {
                    Pose2::new(0.7 * increment.x, 0.0, 0.0)
                } else {
                    increment
                },
                covariance: Matrix3::identity() * 1e-6,
                wheel_increment: wheels_given.then_some(increment),
            };
            let beams = scan(&grid, truth);
            let mean = localizer.step(&motion, Some(&ranges(&beams))).estimate.mean;
            worst = worst.max((mean.x - truth.x).hypot(mean.y - truth.y));
        }
        worst
    }

    #[test]
    fn the_wheels_step_keeps_a_front_end_that_falls_short_from_dragging_the_estimate() {
        let without = worst_error_with_a_short_front_end(false);
        let with = worst_error_with_a_short_front_end(true);
        assert!(with < 0.5 * without, "{with} against {without}");
    }

    #[test]
    fn a_grid_without_free_space_is_refused_for_a_global_start() {
        let mut grid = room();
        grid.cells.iter_mut().for_each(|c| *c = CellState::Unknown);
        let config = LocalizeConfig::default();
        assert_eq!(
            Localizer::new(config, &grid, Start::Global, 1, 0).err(),
            Some(LocalizeError::NoFreeSpace)
        );
    }
}
