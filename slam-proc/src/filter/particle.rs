//! One particle: a pose hypothesis, its log weight and its own corner map, and the
//! per-scan update of all three from the scan's corners.

use std::ops::Range;

use nalgebra::{Vector3, Vector4};
use rand::Rng;
use rand_distr::StandardNormal;

use crate::config::SlamConfig;
use crate::filter::observation::Prepared;
use crate::map::corner_map::{CornerMap, CornerState};
use crate::math::chi2::Gates;
use crate::math::linalg::sample_information_form3;

use crate::path::particle_path::Path;
use crate::update::corner_model::{PoseTransform, WorldObservation};
use crate::update::jcbb::{Association, Jcbb, Pairing, PoseUncertainty};
use crate::update::kalman;
use slam_geom::Pose2;
use slam_geom::wrap_angle;

/// Map corners farther than this from an observation's predicted position are not
/// considered for it, metres: it must cover the gate, the pose's and the corner's
/// uncertainty at range.
pub(crate) const SEARCH_RADIUS: f64 = 1.5;
/// Search nodes JCBB may visit per particle and scan before it settles for the best
/// hypothesis found so far: bounds the time of pathological scans.
const JCBB_MAX_NODES: usize = 10_000;
/// Log density of an observation that no map corner explains (a new or spurious corner),
/// over `(x, y, heading, angle)`: roughly `-ln(visible area * 2 pi * pi)` for the few
/// hundred square metres a scanner sees indoors.
const NEW_CORNER_LOG_LIKELIHOOD: f64 = -9.0;
/// Observations after which a corner is confirmed; before that it is tentative, left out of
/// the published map and dropped when it is not seen again. Two: one sighting may be
/// clutter, a second from another viewpoint is a corner.
pub(crate) const CONFIRM_OBSERVATIONS: u32 = 2;
/// A tentative corner is dropped after this many scans in which it was in view and not
/// observed: a few, so that a corner occluded for a moment survives.
const TENTATIVE_MAX_MISSES: u32 = 3;
/// An unexplained observation within this distance of a map corner of similar heading
/// starts no new corner (it is that corner, seen badly), metres: wider than a badly seen
/// corner's error, and two real corners of one heading are seldom closer.
const DUPLICATE_RADIUS: f64 = 0.5;
/// Headings closer than this are similar for the duplicate test, radians: a corner's
/// extracted heading moves a little with the viewpoint it is seen from.
const DUPLICATE_HEADING: f64 = 30f64.to_radians();

#[derive(Debug, Clone)]
pub(crate) struct Particle {
    pub pose: Pose2,
    /// Log of the (unnormalised) importance weight since the last resampling.
    pub log_weight: f64,
    /// The particle's last step, in its frame before the step, as the constant-velocity
    /// prior will repeat it: the prediction's increment (noise included) plus the part of
    /// the observation correction within three standard deviations of the step's noise.
    /// A larger correction is the map undoing accumulated drift, not motion, and repeated
    /// as a velocity it would throw the next steps off.
    pub increment: Pose2,
    pub map: CornerMap,
    /// Every pose so far, shared with the copies of its ancestors.
    pub path: Path,
}

/// What every particle's update reads, the same for all particles of a scan.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScanContext<'a> {
    pub observations: &'a [Prepared],
    /// The uncertainty of each particle's predicted pose: its motion noise since the corners
    /// last updated it.
    pub pose: PoseUncertainty,
    pub gates: &'a Gates,
    pub config: &'a SlamConfig,
    /// Whether the update draws each particle's pose (the observation proposal) rather
    /// than keep the one the prediction drew.
    pub draw_pose: bool,
    /// `cos(view_fov / 2)`, for the field-of-view test of tentative corners.
    pub cos_half_fov: f64,
}

/// Buffers of one worker, reused across particles so the update does not allocate once
/// they have grown.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    world: Vec<WorldObservation>,
    pairings: Vec<Pairing>,
    lists: Vec<Range<usize>>,
    ids: Vec<u32>,
    /// The map corners within the search radius of each observation: `near_lists[i]`
    /// ranges over `near`.
    near: Vec<u32>,
    near_lists: Vec<Range<usize>>,
    observed: Vec<u32>,
    jcbb: Jcbb,
}

impl Particle {
    pub fn new(map: CornerMap) -> Self {
        Self {
            pose: Pose2::IDENTITY,
            log_weight: 0.0,
            increment: Pose2::IDENTITY,
            map,
            path: Path::default(),
        }
    }

    /// Associates the scan's corners with this particle's map (JCBB) from its predicted
    /// pose, draws the pose from the prediction corrected by the associated corners (with
    /// the observation proposal), updates the matched corners, starts tentative ones for the
    /// unexplained, ages the tentative ones, and returns the log-likelihood of the scan
    /// for the weight.
    pub fn update(
        &mut self,
        context: &ScanContext<'_>,
        scratch: &mut Scratch,
        rng: &mut impl Rng,
    ) -> f64 {
        let config = context.config;
        scratch.world.clear();
        let mut transform = PoseTransform::new(&self.pose);
        scratch
            .world
            .extend(context.observations.iter().map(|o| transform.to_world(o)));

        // The weight is the likelihood of the scan under the predicted pose, its
        // uncertainty included.
        let association = self.associate(context, scratch);
        let unexplained = scratch.world.len() - association.pairings;
        let log_likelihood =
            association.log_likelihood + unexplained as f64 * NEW_CORNER_LOG_LIKELIHOOD;
        if context.draw_pose
            && association.pairings > 0
            && let Some(corrected) = self.corrected_pose(&context.pose, &association, rng)
        {
            let predicted = self.pose;
            self.pose = corrected;
            // The step the next constant-velocity prior repeats takes the correction only
            // up to three sigma of the step's noise (see `increment`). The correction in
            // the predicted frame: `transform` is still the predicted pose's.
            let (x, y) = transform.to_local(corrected.x, corrected.y);
            let correction = Pose2::new(x, y, wrap_angle(corrected.yaw - predicted.yaw));
            let p = &context.pose.covariance;
            let bound = |v: f64, variance: f64| {
                let limit = 3.0 * variance.sqrt();
                v.clamp(-limit, limit)
            };
            self.increment = self.increment.compose(&Pose2::new(
                bound(correction.x, p[(0, 0)]),
                bound(correction.y, p[(1, 1)]),
                bound(correction.yaw, p[(2, 2)]),
            ));
            transform = PoseTransform::new(&self.pose);
            for (world, observation) in scratch.world.iter_mut().zip(context.observations) {
                *world = transform.to_world(observation);
            }
        }

        scratch.observed.clear();
        for (i, observation) in scratch.world.iter().enumerate() {
            match scratch.jcbb.assignment()[i] {
                Some(index) => {
                    let pairing = &scratch.pairings[index];
                    scratch.observed.push(pairing.corner);
                    // The gain comes from `(P + R)^-1` at the predicted pose; after a pose
                    // correction `R` has turned by a fraction of a degree. The Joseph form
                    // gives the right covariance for any gain, so it stays consistent.
                    self.map
                        .update(pairing.corner, CONFIRM_OBSERVATIONS, |corner| {
                            kalman::update_with_inverse(
                                &corner.mean,
                                &corner.covariance,
                                &observation.z,
                                &observation.covariance,
                                &pairing.d_inverse,
                            )
                        });
                    let near = &scratch.near[scratch.near_lists[i].clone()];
                    self.drop_duplicate_of(pairing.corner, near);
                }
                // An observation that passed some corner's individual gate but fits no
                // joint hypothesis is ambiguous: it starts no corner, or the map would
                // fill with near-duplicates of corners already in it.
                None if !scratch.lists[i].is_empty() => {}
                None => {
                    if !self.has_similar_corner(observation, &mut scratch.ids) {
                        let state = CornerState {
                            mean: observation.z,
                            covariance: observation.covariance,
                            observations: 1,
                        };
                        scratch
                            .observed
                            .push(self.map.insert(state, CONFIRM_OBSERVATIONS));
                    }
                }
            }
        }

        // Within the field of view: |bearing| <= fov / 2, i.e. x >= r cos(fov / 2), which
        // spares an arctangent per tentative corner and particle.
        let (range, cos_half_fov) = (config.view_range, context.cos_half_fov);
        let in_view = |corner: &CornerState| {
            let (x, y) = transform.to_local(corner.mean.x, corner.mean.y);
            let r2 = x * x + y * y;
            r2 <= range * range && x >= r2.sqrt() * cos_half_fov
        };
        self.map
            .age_tentative(&scratch.observed, in_view, TENTATIVE_MAX_MISSES);
        log_likelihood
    }

    /// Pairs the scan's observations (already in `scratch.world`) with the map corners
    /// within the search radius that pass the individual gate under the predicted pose's
    /// uncertainty, and solves for the joint hypothesis (JCBB). Leaves the candidate lists
    /// in `scratch` for the update.
    fn associate(&self, context: &ScanContext<'_>, scratch: &mut Scratch) -> Association {
        let (gate, pose, radius) = (context.gates.individual(), &context.pose, SEARCH_RADIUS);
        scratch.pairings.clear();
        scratch.lists.clear();
        scratch.near.clear();
        scratch.near_lists.clear();
        let radius_squared = radius * radius;
        for observation in &scratch.world {
            let start = scratch.pairings.len();
            let near_start = scratch.near.len();
            scratch.ids.clear();
            self.map
                .near(observation.z.x, observation.z.y, radius, &mut scratch.ids);
            for &id in &scratch.ids {
                let Some(corner) = self.map.get(id) else {
                    continue;
                };
                let (dx, dy) = (
                    corner.mean.x - observation.z.x,
                    corner.mean.y - observation.z.y,
                );
                if dx * dx + dy * dy > radius_squared {
                    continue;
                }
                scratch.near.push(id);
                if let Some(pairing) = Pairing::new(observation, id, corner, pose, gate) {
                    scratch.pairings.push(pairing);
                }
            }
            // Ties broken by id: the grid's order must not decide anything.
            scratch.pairings[start..].sort_by(|a, b| {
                a.distance
                    .total_cmp(&b.distance)
                    .then(a.corner.cmp(&b.corner))
            });
            scratch.lists.push(start..scratch.pairings.len());
            scratch.near_lists.push(near_start..scratch.near.len());
        }
        scratch.jcbb.solve(
            &scratch.pairings,
            &scratch.lists,
            pose,
            context.gates.joint(),
            JCBB_MAX_NODES,
        )
    }

    /// A draw from the pose posterior given the associated corners: the Gaussian with
    /// information `P^-1 + A` and mean `predicted - (P^-1 + A)^-1 b` (one Gauss-Newton step
    /// of the linearised observations from the predicted pose). `None` when the
    /// information is not positive definite, which leaves the prediction in place.
    fn corrected_pose(
        &self,
        pose: &PoseUncertainty,
        association: &Association,
        rng: &mut impl Rng,
    ) -> Option<Pose2> {
        let normal = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
        let evidence = &association.evidence;
        let information = pose.information + evidence.information;
        let step = sample_information_form3(&information, &evidence.gradient, &normal)?;
        let pose = Pose2::new(
            self.pose.x + step.x,
            self.pose.y + step.y,
            wrap_angle(self.pose.yaw + step.z),
        );
        [pose.x, pose.y, pose.yaw]
            .iter()
            .all(|v| v.is_finite())
            .then_some(pose)
    }

    /// Whether the map has a corner within the duplicate radius with a similar heading.
    fn has_similar_corner(&self, observation: &WorldObservation, ids: &mut Vec<u32>) -> bool {
        ids.clear();
        self.map
            .near(observation.z.x, observation.z.y, DUPLICATE_RADIUS, ids);
        ids.iter()
            .filter_map(|&id| self.map.get(id))
            .any(|corner| similar(&corner.mean, &observation.z))
    }

    /// Keeps the map free of duplicates after corner `id` moved: a similar corner among
    /// `near` (the corners near the observation that moved it, which covers the duplicate
    /// radius around it) is one place mapped twice, e.g. a corner whose extracted heading
    /// depends on the viewpoint, or one remapped before a loop closed. The one seen fewer
    /// times goes (the younger among equals).
    fn drop_duplicate_of(&mut self, id: u32, near: &[u32]) {
        let Some((mean, observations)) = self.map.get(id).map(|c| (c.mean, c.observations)) else {
            return;
        };
        for &other in near {
            let Some(neighbour) = self.map.get(other) else {
                continue;
            };
            if other == id || !similar(&mean, &neighbour.mean) {
                continue;
            }
            let neighbour_weaker = neighbour.observations < observations
                || (neighbour.observations == observations && other > id);
            let weaker = if neighbour_weaker { other } else { id };
            self.map.remove(weaker, CONFIRM_OBSERVATIONS);
            if weaker == id {
                return;
            }
        }
    }
}

/// Whether two corners `(x, y, heading, angle)` are one for the map: within the duplicate
/// radius, headings within the duplicate angle.
fn similar(a: &Vector4<f64>, b: &Vector4<f64>) -> bool {
    let radius = DUPLICATE_RADIUS;
    (a.x - b.x).powi(2) + (a.y - b.y).powi(2) <= radius * radius
        && wrap_angle(a.z - b.z).abs() <= DUPLICATE_HEADING
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix4, Vector2};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The step the prediction made.
    const STEP: Pose2 = Pose2 {
        x: 0.1,
        y: 0.01,
        yaw: 0.02,
    };

    /// Four well-known corners around the origin, and what a robot at `pose` sees of them.
    fn scene(pose: &Pose2) -> (CornerMap, Vec<Prepared>) {
        let corners = [
            (3.0, 1.0, 0.5),
            (-2.0, 4.0, 2.0),
            (1.0, -3.0, -1.0),
            (5.0, -2.0, 2.8),
        ];
        let mut map = CornerMap::new(3.0);
        let inverse = pose.inverse();
        let mut observations = Vec::new();
        for (x, y, heading) in corners {
            map.insert(
                CornerState {
                    mean: Vector4::new(x, y, heading, 1.5),
                    covariance: Matrix4::identity() * 1e-6,
                    observations: 10,
                },
                2,
            );
            let local = inverse.transform(Vector2::new(x, y));
            observations.push(Prepared {
                z: Vector4::new(local.x, local.y, wrap_angle(heading - pose.yaw), 1.5),
                covariance: Matrix4::identity() * 1e-6,
            });
        }
        (map, observations)
    }

    /// The prediction is uncertain by 5 cm and 0.02 rad.
    const PREDICTION: (f64, f64) = (0.05, 0.02);

    fn update(draw_pose: bool, predicted: Pose2, truth: &Pose2) -> Particle {
        let (map, observations) = scene(truth);
        update_in(map, &observations, draw_pose, predicted, PREDICTION)
    }

    fn update_in(
        map: CornerMap,
        observations: &[Prepared],
        draw_pose: bool,
        predicted: Pose2,
        (sigma_xy, sigma_yaw): (f64, f64),
    ) -> Particle {
        let config = &SlamConfig::default();
        let mut gates = Gates::new(crate::filter::fast_slam::ASSOCIATION_PROBABILITY);
        gates.ensure(observations.len());
        let context = ScanContext {
            observations,
            pose: PoseUncertainty::from_variances(
                sigma_xy * sigma_xy,
                sigma_xy * sigma_xy,
                sigma_yaw * sigma_yaw,
            ),
            gates: &gates,
            config,
            draw_pose,
            cos_half_fov: (0.5 * config.view_fov).cos(),
        };
        let mut particle = Particle {
            pose: predicted,
            increment: STEP,
            ..Particle::new(map)
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        particle.update(&context, &mut Scratch::default(), &mut rng);
        particle
    }

    #[test]
    fn the_observation_proposal_pulls_the_pose_onto_the_map() {
        let truth = Pose2::new(0.5, 0.2, 0.3);
        let predicted = Pose2::new(0.55, 0.17, 0.31);
        // Without it the particle keeps its prediction (and its error).
        let kept = update(false, predicted, &truth);
        assert_eq!(kept.pose, predicted);
        // With it the particle lands on the pose its well-known map implies, within the
        // posterior's spread (about 1 mm: four corners known to 1 mm).
        let drawn = update(true, predicted, &truth);
        let error = (drawn.pose.x - truth.x).hypot(drawn.pose.y - truth.y);
        assert!(error < 5e-3, "{:?}", drawn.pose);
        assert!(wrap_angle(drawn.pose.yaw - truth.yaw).abs() < 2e-3);
        // The increment follows the correction: the previous pose composed with it is the
        // drawn pose.
        let previous = predicted.compose(&STEP.inverse());
        let reached = previous.compose(&drawn.increment);
        assert!((reached.x - drawn.pose.x).abs() < 1e-12);
        assert!((reached.y - drawn.pose.y).abs() < 1e-12);
        assert!(wrap_angle(reached.yaw - drawn.pose.yaw).abs() < 1e-12);
        // The corners were updated from the corrected pose: they stay where they were.
        let corner = drawn.map.get(0).map(|c| c.mean).unwrap_or_default();
        assert!(
            (corner.x - 3.0).abs() < 2e-3 && (corner.y - 1.0).abs() < 2e-3,
            "{corner}"
        );
        let moved = kept.map.get(0).map(|c| c.mean).unwrap_or_default();
        assert!((moved.x - 3.0).abs() > (corner.x - 3.0).abs());
    }

    #[test]
    fn a_prediction_far_off_its_map_stays_where_it_is() {
        // 0.6 m and 3 degrees off four well-known corners, far outside this step's noise:
        // no pairing passes the gate, and the particle keeps its prediction (closing such
        // a loop is the back end's).
        let truth = Pose2::new(0.5, 0.2, 0.3);
        let predicted = Pose2::new(1.0, -0.15, 0.35);
        let kept = update(true, predicted, &truth);
        assert_eq!(kept.pose, predicted);
    }

    #[test]
    fn a_correction_beyond_the_step_noise_is_not_taken_for_motion() {
        // The prediction is 3.8 sigma off (1 cm noise): the pose is corrected all the way,
        // but only three sigma of it count as the step's motion.
        let truth = Pose2::new(0.5, 0.2, 0.3);
        let (map, observations) = scene(&truth);
        let predicted = Pose2::new(truth.x + 0.038, truth.y, truth.yaw);
        let drawn = update_in(map, &observations, true, predicted, (0.01, 0.002));
        assert!((drawn.pose.x - truth.x).abs() < 3e-3, "{:?}", drawn.pose);
        let previous = predicted.compose(&STEP.inverse());
        let reached = previous.compose(&drawn.increment);
        assert!(
            (reached.x - (predicted.x - 0.03)).abs() < 3e-3,
            "{reached:?}"
        );
    }

    #[test]
    fn a_corner_mapped_twice_keeps_the_better_copy() {
        let truth = Pose2::new(0.5, 0.2, 0.3);
        let (mut map, observations) = scene(&truth);
        // Corner 0 again, 0.25 m off and 0.2 rad turned, seen only three times: the same
        // place mapped twice (as a viewpoint-dependent extraction would).
        let copy = map.insert(
            CornerState {
                mean: Vector4::new(3.2, 1.15, 0.7, 1.5),
                covariance: Matrix4::identity() * 1e-6,
                observations: 3,
            },
            2,
        );
        assert_eq!(map.confirmed_count(), 5);
        let particle = update_in(map, &observations, false, truth, PREDICTION);
        // Observing corner 0 moved it; its weaker copy went.
        assert!(particle.map.get(copy).is_none());
        assert!(particle.map.get(0).is_some());
        assert_eq!(particle.map.confirmed_count(), 4);
    }
}
