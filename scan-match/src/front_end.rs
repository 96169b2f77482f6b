//! The front end: per scan, the motion prior, registration against the local map, the
//! odometry check, fusion, and the local map's upkeep.

use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Pose2, wrap_angle};

use crate::config::FrontEndConfig;
use crate::error::InputError;
use crate::fusion::{Prediction, disagreement, fuse, predict};
use crate::input::{OdometryInput, ScanInput};
use crate::local_map::LocalMap;
use crate::odometry_anchor::{Lag, MAX_CATCH_UP_NS, OdometryAnchor, is_frozen};
use crate::odometry_scale::OdometryScale;
use crate::output::{FrontEndOutput, FrontEndStats, MatchFailure, MatchStatus, OdometryStatus};
use crate::points::{Extractor, SurfacePoint};
use crate::prior::{
    MAX_EXTRAPOLATION_S, ODOMETRY_MIN_SIGMA_XY, ODOMETRY_MIN_SIGMA_YAW, OdometryRejection, Step,
    constant_velocity_step, odometry_step, positive_definite,
};
use crate::recovery::{RecoveryWindow, rank, recover};
use crate::registration::{Registration, RegistrationParams, register};
use crate::scan_clock::ScanClock;
use crate::search::{Window, score_sample, search_sample, subsample};
use crate::velocity::Velocity;
use crate::wheel_pace::{STALE_WINDOW_NS, WheelPace};
use stage_kit::SettingError;

/// The correlative search runs only when fewer of the scan's points than this (weighted
/// by closeness) lie near the map at the prior's prediction.
const SEARCH_BELOW_SCORE: f64 = 0.5;

/// A weak fit overrules the odometry only where the scan scores below this share of the
/// fit's score at the odometry's pose.
const WEAK_FIT_MARGIN: f64 = 0.7;

/// ...and only if it puts at least this share of the (closeness-weighted) points on the
/// map itself: a fit that explains little of the scan (after a gap in the data, say)
/// is no evidence against the odometry.
const WEAK_FIT_MIN_SCORE: f64 = 0.4;

/// Share of its information a degenerate direction of the fit contributes when the prior
/// is constant velocity: a tenth, since a direction this weakly constrained is easily
/// misled by a few wrong correspondences.
const WEAK_SHARE: f64 = 0.1;

/// A recovered fit replaces the one from the prior's window only if it ranks clearly
/// higher: the wide search sees many more poses, and one of them fitting a little better
/// by chance is no reason to jump.
const RECOVERY_MARGIN: f64 = 1.2;

/// A scan with fewer usable points (valid, with a surface normal) is not matched, and a fit
/// with fewer inliers does not overrule the odometry: a few dozen points can line up with a
/// map in too many ways to be evidence.
const MIN_POINTS: usize = 30;

/// Widest gate between a scan point and its map neighbour, metres. Wider than any prior's
/// plausible error between scans; matches beyond it are clutter. Registration itself
/// starts from a seed the correlative search has placed, and gates at six voxels at most
/// (the search's coarse radius).
pub const MAX_CORRESPONDENCE: f64 = 0.5;

/// The correlative search before registration spans the prior's 3-sigma window, but at
/// most this far each way, metres: a robot moves less between two scans, and the search's
/// cost grows with the window's area...
const MAX_SEARCH_TRANSLATION: f64 = 0.5;
/// ...and this far in yaw, radians.
const MAX_SEARCH_YAW: f64 = 0.6;

/// When the prior allows more than that window (a gap in the data) and the fit from it is
/// weak, a wide search spans the prior's 3-sigma window up to this far each way, metres:
/// three times the regular window, a gap's worth of motion at an indoor robot's pace, with
/// the search's cost (its area) still bounded...
const RECOVERY_TRANSLATION: f64 = 1.5;
/// ...and this far in yaw, radians: a full turn, since a turn is what a gap hides most.
const RECOVERY_YAW: f64 = std::f64::consts::PI;

/// Keyframes in the local map at most; the oldest leaves first. At the keyframe spacing
/// this is the last ten or twenty metres of path: enough to register against, and it bounds
/// the map's memory and how old the drift is that the map carries.
const MAX_KEYFRAMES: usize = 50;

/// Without odometry, a fit that leaves a direction open adds a keyframe at least this
/// often, seconds, however little the robot seems to have moved: what the map lacks along
/// that direction (a door recess that came into view) may be in the scan, and the open
/// direction's estimate (constant velocity) may be the very reason the robot seems to stand
/// still. With odometry the wheels tell that, and keyframes by distance suffice.
const DEGENERATE_KEYFRAME_INTERVAL_S: f64 = 0.5;

/// A match is confident enough to judge the odometry only with at least this fraction of
/// its points as inliers: below that, most of the scan is not explained by the fit, which
/// may sit in a wrong basin.
const MIN_INLIER_FRACTION: f64 = 0.4;

/// A match overrules a contradicting odometry step only with at least this fraction of its
/// points as inliers; a weaker one gives way to the odometry.
const STRONG_INLIER_FRACTION: f64 = 0.6;

/// Squared Mahalanobis distance between the odometry step and the match beyond which the
/// odometry is rejected: chi-square with 3 degrees of freedom at p = 1e-6, so a consistent
/// step is almost never rejected.
const ODOMETRY_GATE: f64 = 30.7;

/// What seeded a registration, which decides how far it may look beyond its window.
#[derive(Debug, Clone, Copy)]
enum Seed {
    /// The wheels' step.
    Odometry,
    /// Constant velocity, the only prior there is.
    ConstantVelocity,
    /// Constant velocity as a second opinion beside wheels (that turned by `wheels_turn`,
    /// radians) whose seed found a poor or contradicting fit. Its wide search takes only a
    /// turn the wheels can have misjudged: by as much as they turned (wheels slip in a fast
    /// turn and undercount it), or by what the window searches anyway. A wheel does not
    /// invent or miss a larger turn, and a fit there is the wrong basin of a scan that sees
    /// little (a short-range sensor after seconds of scans too sparse to register).
    SecondOpinion { wheels_turn: f64 },
}

/// Registers every scan against a local map of recent keyframes, fused with odometry.
/// Feed it every scan in order with [`FrontEnd::process`].
#[derive(Debug, Clone)]
pub struct FrontEnd {
    config: FrontEndConfig,
    params: RegistrationParams,
    map: LocalMap,
    extractor: Extractor,
    pose: Pose2,
    last_stamp_ns: Option<u64>,
    /// The time between scans the motion model uses.
    clock: ScanClock,
    /// Stamp of the newest keyframe.
    keyframe_stamp_ns: u64,
    /// What constant velocity extrapolates.
    velocity: Velocity,
    last_odometry: Option<OdometryInput>,
    /// The last odometry reading a step was believed from.
    odometry_anchor: Option<OdometryAnchor>,
    /// Whether the wheels' readings since then were not believed, frozen while the scans
    /// moved or stale: odometry that will catch up, its steps measured from the anchor.
    lag: Lag,
    /// The wheels' pace, that a stale step breaks.
    wheel_pace: WheelPace,
    /// The wheels' distance scale, learnt from the fits.
    odometry_scale: OdometryScale,
    /// The scans since the last one registered, when the last did not register.
    unregistered: Option<Unregistered>,
    stats: FrontEndStats,
}

/// A stretch of scans that did not register: where the front end has only its prior to go
/// by, its uncertainty adds up, and so does the window the next scan is searched over.
#[derive(Debug, Clone, Copy)]
struct Unregistered {
    /// Stamp of the last scan that registered (or of the first scan).
    since_ns: u64,
    /// Scans since that did not.
    scans: u64,
    /// The covariances of their steps, added up.
    covariance: Matrix3<f64>,
}

/// Wide searches run while registering one scan, and those whose fit was taken.
#[derive(Debug, Clone, Copy, Default)]
struct WideSearches {
    run: u64,
    taken: u64,
}

impl FrontEnd {
    pub fn new(config: FrontEndConfig) -> Result<Self, SettingError> {
        config.validate()?;
        let odometry_scale = OdometryScale::new(config.odometry_scale());
        Ok(Self {
            params: RegistrationParams {
                range_sigma: config.range_sigma,
                voxel: config.voxel_size,
                weak_steps: false,
            },
            map: LocalMap::new(config.voxel_size, MAX_KEYFRAMES),
            config,
            extractor: Extractor::default(),
            pose: Pose2::IDENTITY,
            last_stamp_ns: None,
            clock: ScanClock::default(),
            keyframe_stamp_ns: 0,
            velocity: Velocity::default(),
            last_odometry: None,
            odometry_anchor: None,
            lag: Lag::OnTime,
            wheel_pace: WheelPace::default(),
            odometry_scale,
            unregistered: None,
            stats: FrontEndStats::default(),
        })
    }

    pub fn config(&self) -> &FrontEndConfig {
        &self.config
    }

    /// The latest pose, `odom_from_robot` in the front end's frame.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// The scale the wheels' distances are multiplied by, learnt from the fits so far (1
    /// until there is evidence).
    pub fn odometry_scale(&self) -> f64 {
        self.odometry_scale.scale()
    }

    /// Counts over the run so far.
    pub fn stats(&self) -> FrontEndStats {
        self.stats
    }

    /// Points in the local map.
    pub fn map_points(&self) -> usize {
        self.map.len()
    }

    /// Processes the next scan. `Err` only for a scan whose geometry makes no sense; a
    /// scan that cannot be matched is reported in the output's status.
    pub fn process(&mut self, scan: &ScanInput<'_>) -> Result<FrontEndOutput, InputError> {
        let start = Instant::now();
        scan.geometry.check().map_err(InputError::Geometry)?;
        let extracted = self.extractor.extract(
            &scan.geometry,
            scan.ranges,
            self.config.range_sigma,
            self.config.voxel_size,
        );
        let points = &extracted.points;
        let floor = self.floor_covariance();
        let mut output = FrontEndOutput {
            stamp_ns: scan.stamp_ns,
            odom_from_robot: self.pose,
            increment: Pose2::IDENTITY,
            increment_covariance: floor,
            status: MatchStatus::First,
            odometry: OdometryStatus::Absent,
            wheel_increment: None,
            valid_beams: extracted.valid_beams,
            points: points.len(),
            inliers: 0,
            iterations: 0,
            keyframe: false,
            elapsed: Default::default(),
        };
        let Some(last_stamp_ns) = self.last_stamp_ns else {
            if let Some(odometry) = scan.odometry {
                output.odometry = OdometryStatus::Started;
                self.last_odometry = Some(odometry);
            }
            if points.len() >= MIN_POINTS {
                self.map.insert(self.pose, points);
                self.keyframe_stamp_ns = scan.stamp_ns;
                output.keyframe = true;
            }
            self.last_stamp_ns = Some(scan.stamp_ns);
            return Ok(self.finish(output, start));
        };
        let elapsed_s = scan.stamp_ns.saturating_sub(last_stamp_ns) as f64 * 1e-9;
        let dt = self.clock.interval(elapsed_s);

        // Constant velocity carries the robot on over a stretch of scans that do not register
        // for as long as it carries it over a gap, then holds it: the output stays bounded,
        // its covariance growing as it would.
        let adrift = self.unregistered.is_some_and(|u| {
            scan.stamp_ns.saturating_sub(u.since_ns) as f64 * 1e-9 > MAX_EXTRAPOLATION_S
        });
        let velocity = if adrift {
            Vector3::zeros()
        } else {
            self.velocity.get()
        };
        let cv = constant_velocity_step(&velocity, dt, &self.config);
        // Across a gap (or a stretch as long of scans that did not register) the velocity
        // says nothing and a weak fit may be in the wrong basin.
        let gap = elapsed_s > MAX_EXTRAPOLATION_S || adrift;
        let mut wheels_moved = None;
        let mut caught_up = false;
        let mut odometry = match (scan.odometry, self.last_odometry) {
            (None, _) => Err(OdometryStatus::Absent),
            (Some(_), None) => Err(OdometryStatus::Started),
            (Some(current), Some(previous)) => odometry_step(&previous, &current, dt, &self.config)
                .and_then(|step| {
                    wheels_moved = Some(step.increment);
                    let (step, from_anchor) =
                        self.wheel_step(&current, scan.stamp_ns, step, dt, gap)?;
                    caught_up = from_anchor;
                    Ok(step)
                })
                .map_err(OdometryStatus::Rejected),
        };
        // The next step starts from this reading even if this step was rejected: a reset
        // odometry frame then costs one rejection, not all the following steps.
        match scan.odometry {
            None => self.last_odometry = None,
            Some(current) if is_finite(&current) => self.last_odometry = Some(current),
            Some(_) => {}
        }

        // After scans that did not register, the prior is as uncertain as their steps added
        // up: the search looks that much wider (a recovery, once wider than its window).
        let stretch = self.stretch_covariance();
        let widened = |step: Step| Step {
            covariance: step.covariance + stretch,
            ..step
        };
        let cv = widened(cv);
        odometry = odometry.map(widened);
        let mut wide = WideSearches::default();
        let mut prior = odometry.unwrap_or(cv);
        let seeded_by = if odometry.is_ok() {
            Seed::Odometry
        } else {
            Seed::ConstantVelocity
        };
        let mut registration = self.register(points, &prior, gap, seeded_by, &mut wide);
        // The wheels' step as judged against the scan, even if the scan overrules it.
        let judged = odometry.ok();
        if let Ok(step) = odometry {
            let second_opinion = Seed::SecondOpinion {
                wheels_turn: step.increment.yaw,
            };
            // Whether `registration` is already the second opinion's.
            let asked = registration.is_err();
            if asked {
                // The odometry may have put the scan where it finds no map: try the
                // other prior before believing it.
                if let Ok(other) = self.register(points, &cv, gap, second_opinion, &mut wide) {
                    registration = Ok(other);
                }
            }
            if let Ok(found) = &registration {
                let distance = disagreement(&predict(&self.pose, &step), found);
                if distance.is_nan() || distance > ODOMETRY_GATE {
                    // The odometry's seed may have led the fit astray: the scan gets a
                    // second chance from constant velocity, and the better of the two fits
                    // is compared with the odometry.
                    if !asked
                        && let Ok(other) =
                            self.register(points, &cv, gap, second_opinion, &mut wide)
                        && rank(&other, &self.params) > rank(found, &self.params)
                    {
                        registration = Ok(other);
                    }
                    let distance = registration
                        .as_ref()
                        .map_or(f64::NAN, |r| disagreement(&predict(&self.pose, &step), r));
                    if distance <= ODOMETRY_GATE {
                        // The second fit agrees with the wheels.
                    } else if registration
                        .as_ref()
                        .is_ok_and(|r| self.overrules(r, &step, points))
                    {
                        // A clear fit overrules the wheels.
                        odometry = Err(OdometryStatus::Rejected(OdometryRejection::Inconsistent {
                            mahalanobis_squared: distance,
                        }));
                        prior = cv;
                    } else {
                        // A weak one that explains the scan no better than the odometry does
                        // not: it is more likely wrong than the wheels.
                        registration = Err(MatchFailure::Contradicted);
                    }
                }
            }
        }

        let prediction = predict(&self.pose, &prior);
        let (pose, covariance) = match &registration {
            Ok(found) => {
                output.inliers = found.inliers;
                output.iterations = found.iterations;
                let mut open = found.constraint.degenerate_directions();
                output.status = match open.next() {
                    None => {
                        // The scan measured the whole step: what the wheels' distance
                        // is worth.
                        if let (Ok(_), Some(moved), false) =
                            (odometry, wheels_moved, self.lag != Lag::OnTime)
                        {
                            self.odometry_scale
                                .observe(&moved, &self.pose.between(&found.pose));
                        }
                        MatchStatus::Matched
                    }
                    Some(weakest) => MatchStatus::Degenerate {
                        direction: robot_direction(&found.pose, &weakest),
                        count: 1 + open.count() as u8,
                    },
                };
                // Without odometry the velocity guess is all there is along a corridor: the
                // scan's weak evidence there (a door frame, the far end) is better than
                // none, and tells a robot that stopped from one that goes on.
                let weak_share = if odometry.is_ok() { 0.0 } else { WEAK_SHARE };
                fuse(&prediction, found, weak_share)
            }
            Err(failure) => {
                output.status = MatchStatus::Failed(*failure);
                // The step's own uncertainty: what the scans before it that did not
                // register added is in their own steps already.
                let own = Step {
                    covariance: prior.covariance - self.stretch_covariance(),
                    ..prior
                };
                let own = predict(&self.pose, &own);
                (own.pose, own.covariance)
            }
        };
        output.odometry = match odometry {
            Ok(_) => OdometryStatus::Used,
            Err(status) => status,
        };
        output.wheel_increment = match (output.odometry, judged) {
            (
                OdometryStatus::Used
                | OdometryStatus::Rejected(OdometryRejection::Inconsistent { .. }),
                Some(step),
            ) => Some(step.increment),
            _ => None,
        };
        let believed = matches!(
            output.odometry,
            OdometryStatus::Used | OdometryStatus::Started
        );
        match scan.odometry {
            Some(reading) if believed => {
                self.odometry_anchor = Some(OdometryAnchor {
                    reading,
                    pose,
                    stamp_ns: scan.stamp_ns,
                });
            }
            None => self.odometry_anchor = None,
            Some(_) => {}
        }
        match (output.odometry, wheels_moved) {
            (OdometryStatus::Used, _) => {
                match odometry {
                    Ok(step) if !caught_up => self.wheel_pace.believe(&step.increment, dt),
                    // A catch-up is no pace: the next step is not judged.
                    _ => self.wheel_pace.forget(),
                }
                self.lag = Lag::OnTime;
            }
            (OdometryStatus::Absent | OdometryStatus::Started, _) => {
                self.lag = Lag::OnTime;
                self.wheel_pace.forget();
            }
            (OdometryStatus::Rejected(OdometryRejection::Stale { .. }), _) => {
                self.lag = Lag::Stale;
            }
            (OdometryStatus::Rejected(OdometryRejection::Inconsistent { .. }), Some(moved)) => {
                self.lag = if is_frozen(&moved) {
                    Lag::Frozen
                } else {
                    Lag::OnTime
                }
            }
            (OdometryStatus::Rejected(_), _) => {}
        }

        let to_map = self.pose.frame_jacobian();
        let increment = self.pose.between(&pose);
        output.increment = increment;
        output.increment_covariance = positive_definite(
            &(to_map.transpose() * covariance * to_map),
            &floor.diagonal(),
        );
        // With wheels, a step they did not measure (stale, contradicted) lies between steps
        // they did; without any, constant velocity is the prior of every step.
        self.velocity
            .update(&increment, dt, scan.odometry.is_some());
        self.pose = pose;
        self.last_stamp_ns = Some(scan.stamp_ns);
        output.odom_from_robot = pose;

        self.stats.wide_searches += wide.run;
        self.stats.recovered += wide.taken;
        if let MatchStatus::Failed(_) = output.status {
            let stretch = self.unregistered.get_or_insert(Unregistered {
                since_ns: last_stamp_ns,
                scans: 0,
                covariance: Matrix3::zeros(),
            });
            stretch.scans += 1;
            // A step constant velocity guessed adds its uncertainty: its prior, widened by the
            // stretch so far, is the stretch's now. One the wheels measured bridges the scan
            // as any other wheel step does.
            if !matches!(output.odometry, OdometryStatus::Used) {
                stretch.covariance = prior.covariance;
            }
            self.stats.longest_unregistered = self.stats.longest_unregistered.max(stretch.scans);
        } else {
            self.unregistered = None;
        }

        let lost = matches!(
            output.status,
            MatchStatus::Failed(MatchFailure::TooFewInliers)
        );
        // Only without odometry: the wheels tell a robot that moves from one that stands.
        let open = matches!(output.status, MatchStatus::Degenerate { .. })
            && !matches!(output.odometry, OdometryStatus::Used);
        if points.len() >= MIN_POINTS && (lost || self.keyframe_due(scan.stamp_ns, open)) {
            self.map.insert(pose, points);
            self.keyframe_stamp_ns = scan.stamp_ns;
            output.keyframe = true;
        }
        Ok(self.finish(output, start))
    }

    /// Registration seeded by `step` (from what `seeded_by` says), judged: enough points,
    /// enough of them matched, at least one direction constrained. After a `gap` in the
    /// data, or when the fit fails outright, a prior wider than the search window gets a
    /// wide search as well.
    fn register(
        &self,
        points: &[SurfacePoint],
        step: &Step,
        gap: bool,
        seeded_by: Seed,
        wide_searches: &mut WideSearches,
    ) -> Result<Registration, MatchFailure> {
        let params = RegistrationParams {
            weak_steps: !matches!(seeded_by, Seed::Odometry),
            ..self.params
        };
        if points.len() < MIN_POINTS {
            return Err(MatchFailure::TooFewPoints);
        }
        if self.map.is_empty() {
            return Err(MatchFailure::TooFewInliers);
        }
        let prediction: Prediction = predict(&self.pose, step);
        let spread = (points.iter().map(|p| p.point.norm_squared()).sum::<f64>()
            / points.len() as f64)
            .sqrt();
        let c = &prediction.covariance;
        let gate = (3.0 * (c[(0, 0)] + c[(1, 1)]).sqrt() + 3.0 * c[(2, 2)].sqrt() * spread)
            .min(MAX_CORRESPONDENCE);
        // Where the prior is less certain than the scoring distance, a correlative search
        // picks the basin first (coarse, then fine around the best), so that a fast turn
        // or a no-odometry guess does not leave Gauss-Newton in the wrong one.
        let radius = 2.0 * self.config.voxel_size;
        let prior_window = Window {
            translation: 3.0 * (c[(0, 0)] + c[(1, 1)]).sqrt(),
            yaw: 3.0 * c[(2, 2)].sqrt(),
        };
        let window = Window {
            translation: prior_window.translation.min(MAX_SEARCH_TRANSLATION),
            yaw: prior_window.yaw.min(MAX_SEARCH_YAW),
        };
        let mut seed = prediction.pose;
        let sample = subsample(points);
        let uncertain = window.translation > radius || window.yaw * spread > radius;
        // A seed where most points already sit on the map is in the right basin.
        if uncertain && score_sample(&self.map, &sample, &seed, radius) < SEARCH_BELOW_SCORE {
            if window.translation > 3.0 * radius || window.yaw * spread > 3.0 * radius {
                seed = search_sample(&self.map, &sample, &seed, window, 3.0 * radius).0;
            }
            let fine = Window {
                translation: window.translation.min(3.0 * radius),
                yaw: window.yaw.min(3.0 * radius / spread.max(1.0)),
            };
            seed = search_sample(&self.map, &sample, &seed, fine, radius).0;
        }
        // The seed is now within the search's resolution of the basin (or had most points
        // on the map already): a gate of the coarse search's radius is wide enough, and
        // keeps every query within the map's lookup raster.
        let gate = gate.min(3.0 * radius);
        let mut found = register(&self.map, points, seed, gate, &params);
        let clipped =
            prior_window.translation > window.translation || prior_window.yaw > window.yaw;
        let n = points.len() as f64;
        let weak = (found.inliers as f64) < STRONG_INLIER_FRACTION * n;
        let failed = (found.inliers as f64) < MIN_INLIER_FRACTION * n;
        // Look wider where the prior allowed more than the window searched and the fit is
        // poor (a gap in the data, a fast turn without odometry), over the prior's reach.
        // Not for a merely weak fit between regular scans: a corridor's repeating doors
        // would tempt the wide search along it. Except over turns: without odometry a weak
        // fit whose constant-velocity prior allowed a wider turn than the window searched
        // may be a wrong basin of a turn that reversed, and the wide search over turns
        // only, at the window's reach in translation, keeps the doors out. `wide` is the
        // search's reach in translation and, searching over turns, the turn the window
        // already searched.
        let turned_past =
            matches!(seeded_by, Seed::ConstantVelocity) && prior_window.yaw > window.yaw;
        let wide = if clipped && (failed || (gap && weak)) {
            Some((prior_window.translation.min(RECOVERY_TRANSLATION), None))
        } else if turned_past && weak {
            Some((window.translation, Some(window.yaw)))
        } else {
            None
        };
        if let Some((translation, searched_yaw)) = wide {
            let how = RecoveryWindow {
                seed: prediction.pose,
                window: Window {
                    translation,
                    yaw: prior_window.yaw.min(RECOVERY_YAW),
                },
                coarse_radius: 3.0 * radius,
                fine_radius: radius,
            };
            // Over turns, only a turn beyond what the window searched is news: a better
            // fit within it would be the window's own search second-guessed.
            let beyond = |other: &Registration| {
                searched_yaw
                    .is_none_or(|yaw| wrap_angle(other.pose.yaw - prediction.pose.yaw).abs() > yaw)
            };
            let plausible = |other: &Registration| match seeded_by {
                Seed::SecondOpinion { wheels_turn } => {
                    let turn = wrap_angle(other.pose.yaw - self.pose.yaw);
                    wrap_angle(turn - wheels_turn).abs() <= wheels_turn.abs().max(MAX_SEARCH_YAW)
                }
                Seed::Odometry | Seed::ConstantVelocity => true,
            };
            wide_searches.run += 1;
            if let Some(other) = recover(&self.map, points, &sample, &how, &params)
                && beyond(&other)
                && plausible(&other)
                && rank(&other, &params) > rank(&found, &params) * RECOVERY_MARGIN
            {
                wide_searches.taken += 1;
                found = other;
            }
        }
        if (found.inliers as f64) < MIN_INLIER_FRACTION * points.len() as f64 {
            return Err(MatchFailure::TooFewInliers);
        }
        if found.constraint.is_void() {
            return Err(MatchFailure::Unconstrained);
        }
        Ok(found)
    }

    /// Whether a fit that contradicts the odometry step overrules it. Never one with fewer
    /// inliers than a scan needs points to be registered at all ([`MIN_POINTS`]): a few dozen
    /// points (a short-range sensor's scan, most of its beams no-returns) can line up with
    /// the map tens of degrees from where the wheels put the robot, and a strong share of
    /// a small scan is still small evidence against the wheels. Otherwise a clear fit
    /// always; a weak one only if the scan lies on the map clearly better at the fit's pose
    /// than at the odometry's (a stale odometry catching up, say), since a weak fit is the
    /// more likely of the two to be wrong.
    fn overrules(&self, found: &Registration, step: &Step, points: &[SurfacePoint]) -> bool {
        if found.inliers < MIN_POINTS {
            return false;
        }
        if found.inliers as f64 >= STRONG_INLIER_FRACTION * points.len() as f64 {
            return true;
        }
        let sample = subsample(points);
        let radius = 2.0 * self.config.voxel_size;
        let at_odometry = score_sample(&self.map, &sample, &predict(&self.pose, step).pose, radius);
        let at_fit = score_sample(&self.map, &sample, &found.pose, radius);
        at_fit >= WEAK_FIT_MIN_SCORE && at_odometry < WEAK_FIT_MARGIN * at_fit
    }

    /// The wheels' step to the `current` reading at `stamp_ns` (`step` from the last
    /// reading, `dt` seconds before), scaled, unless it breaks the wheels' pace; and
    /// whether it is a catch-up, measured from the anchor.
    fn wheel_step(
        &self,
        current: &OdometryInput,
        stamp_ns: u64,
        step: Step,
        dt: f64,
        gap: bool,
    ) -> Result<(Step, bool), OdometryRejection> {
        let paced = |step: Step| match self.pace_change(stamp_ns, &step, dt, gap) {
            Some(acceleration) => Err(OdometryRejection::Stale { acceleration }),
            None => Ok(step),
        };
        let plain = self.odometry_scale.apply(step);
        let Some(anchor) = self.catch_up(stamp_ns, &step) else {
            return paced(plain).map(|step| (step, false));
        };
        // Wheels that lag the scans (stale, or frozen and moving again): their step is the
        // motion since the last reading believed ...
        anchor
            .step_to(
                current,
                stamp_ns,
                &self.pose,
                &self.odometry_scale,
                &self.config,
            )
            .and_then(paced)
            .map(|step| (step, true))
            .or_else(|rejection| match rejection {
                // ... unless that breaks the pace where this reading's own step does not:
                // the wheels go on at the robot's pace, and what they missed stays missed.
                OdometryRejection::Stale { .. } => paced(plain)
                    .map(|step| (step, false))
                    .map_err(|_| rejection),
                other => Err(other),
            })
    }

    /// The acceleration, m/s^2, the wheels' `step` over `dt` seconds would take from their
    /// pace, when more than `max_linear_acceleration` allows: a stale reading. Not across a
    /// `gap`, and only within [`STALE_WINDOW_NS`] of the last believed reading.
    fn pace_change(&self, stamp_ns: u64, step: &Step, dt: f64, gap: bool) -> Option<f64> {
        let recent = self
            .odometry_anchor
            .is_some_and(|anchor| stamp_ns.saturating_sub(anchor.stamp_ns) <= STALE_WINDOW_NS);
        if gap || !recent {
            return None;
        }
        self.wheel_pace.broken_by(
            &step.increment,
            dt,
            self.config.max_linear_acceleration,
            ODOMETRY_MIN_SIGMA_XY,
        )
    }

    /// The reading to measure the wheels' `step` to the scan at `stamp_ns` from instead of
    /// the last one, when the wheels lag since it (recently): stale, or frozen and moving
    /// again.
    fn catch_up(&self, stamp_ns: u64, step: &Step) -> Option<OdometryAnchor> {
        let anchor = self.odometry_anchor?;
        let due = match self.lag {
            Lag::OnTime => false,
            Lag::Frozen => !is_frozen(&step.increment),
            Lag::Stale => true,
        };
        (due && stamp_ns.saturating_sub(anchor.stamp_ns) <= MAX_CATCH_UP_NS).then_some(anchor)
    }

    /// Whether the scan just registered at `stamp_ns` joins the map: after enough motion,
    /// or, for a fit that left a direction `open`, after enough time.
    fn keyframe_due(&self, stamp_ns: u64, open: bool) -> bool {
        match self.map.last_keyframe() {
            None => true,
            Some(keyframe) => {
                let moved = keyframe.between(&self.pose);
                let since = stamp_ns.saturating_sub(self.keyframe_stamp_ns) as f64 * 1e-9;
                moved.translation_norm() > self.config.keyframe_distance
                    || moved.yaw.abs() > self.config.keyframe_angle
                    || (open && since >= DEGENERATE_KEYFRAME_INTERVAL_S)
            }
        }
    }

    /// What the scans since the last one registered added to the uncertainty.
    fn stretch_covariance(&self) -> Matrix3<f64> {
        self.unregistered
            .map_or_else(Matrix3::zeros, |stretch| stretch.covariance)
    }

    fn floor_covariance(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(
            ODOMETRY_MIN_SIGMA_XY.powi(2),
            ODOMETRY_MIN_SIGMA_XY.powi(2),
            ODOMETRY_MIN_SIGMA_YAW.powi(2),
        ))
    }

    fn finish(&mut self, mut output: FrontEndOutput, start: Instant) -> FrontEndOutput {
        output.elapsed = start.elapsed();
        let stats = &mut self.stats;
        stats.scans += 1;
        stats.busy_ns += u64::try_from(output.elapsed.as_nanos()).unwrap_or(u64::MAX);
        match output.status {
            MatchStatus::First => {}
            MatchStatus::Matched => stats.matched += 1,
            MatchStatus::Degenerate { .. } => stats.degenerate += 1,
            MatchStatus::Failed(_) => stats.failed_matches += 1,
        }
        match output.odometry {
            OdometryStatus::Used => stats.odometry_used += 1,
            OdometryStatus::Rejected(why) => stats.odometry_rejected.add(&why),
            OdometryStatus::Absent | OdometryStatus::Started => {}
        }
        if output.keyframe {
            stats.keyframes += 1;
        }
        output
    }
}

fn is_finite(odometry: &OdometryInput) -> bool {
    let p = odometry.odom_from_robot;
    p.x.is_finite()
        && p.y.is_finite()
        && p.yaw.is_finite()
        && odometry.covariance.iter().all(|v| v.is_finite())
}

/// A direction over `(x, y, yaw)` in the map frame, turned into the robot frame at `pose`
/// and normalised.
fn robot_direction(pose: &Pose2, direction: &Vector3<f64>) -> Vector3<f64> {
    let turned = pose.frame_jacobian().transpose() * direction;
    let norm = turned.norm();
    if norm > 0.0 { turned / norm } else { turned }
}
