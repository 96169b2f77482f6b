//! One particle: a pose hypothesis, its log weight and its own corner map, and the
//! per-scan update of all three from the scan's corners.

use std::ops::Range;

use crate::angle::wrap_angle;
use crate::chi2::Gates;
use crate::config::SlamConfig;
use crate::corner_model::{Frame, WorldObservation};
use crate::jcbb::{Jcbb, Pairing, PoseUncertainty};
use crate::kalman;
use crate::map::{CornerMap, CornerState};
use crate::observation::Prepared;
use crate::pose::Pose2;

#[derive(Debug, Clone)]
pub(crate) struct Particle {
    pub pose: Pose2,
    /// Log of the (unnormalised) importance weight since the last resampling.
    pub log_weight: f64,
    /// The increment of the last prediction, noise included, in the particle's frame.
    pub increment: Pose2,
    pub map: CornerMap,
}

/// What every particle's update reads, the same for all particles of a scan.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScanContext<'a> {
    pub observations: &'a [Prepared],
    /// The uncertainty of each particle's predicted pose: its motion noise.
    pub pose: PoseUncertainty,
    pub gates: &'a Gates,
    pub config: &'a SlamConfig,
}

/// Buffers of one worker, reused across particles so the update does not allocate once
/// they have grown.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    world: Vec<WorldObservation>,
    pairings: Vec<Pairing>,
    lists: Vec<Range<usize>>,
    ids: Vec<u32>,
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
        }
    }

    /// Associates the scan's corners with this particle's map (JCBB), updates the matched
    /// corners, starts tentative ones for the unexplained, ages the tentative ones, and
    /// returns the log-likelihood of the scan for the weight.
    pub fn update(&mut self, context: &ScanContext<'_>, scratch: &mut Scratch) -> f64 {
        let config = context.config;
        let gate = context.gates.individual();
        scratch.world.clear();
        let frame = Frame::new(&self.pose);
        scratch
            .world
            .extend(context.observations.iter().map(|o| frame.to_world(o)));

        scratch.pairings.clear();
        scratch.lists.clear();
        let radius_squared = config.search_radius * config.search_radius;
        for observation in &scratch.world {
            let start = scratch.pairings.len();
            scratch.ids.clear();
            self.map.near(
                observation.z.x,
                observation.z.y,
                config.search_radius,
                &mut scratch.ids,
            );
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
                scratch
                    .pairings
                    .extend(Pairing::new(observation, id, corner, &context.pose, gate));
            }
            // Ties broken by id: the grid's order must not decide anything.
            scratch.pairings[start..].sort_by(|a, b| {
                a.distance
                    .total_cmp(&b.distance)
                    .then(a.corner.cmp(&b.corner))
            });
            scratch.lists.push(start..scratch.pairings.len());
        }

        let association = scratch.jcbb.solve(
            &scratch.pairings,
            &scratch.lists,
            &context.pose,
            context.gates.joint(),
            config.jcbb_max_nodes,
        );
        let unexplained = scratch.world.len() - association.pairings;
        let log_likelihood =
            association.log_likelihood + unexplained as f64 * config.new_corner_log_likelihood;

        scratch.observed.clear();
        for (i, observation) in scratch.world.iter().enumerate() {
            match scratch.jcbb.assignment()[i] {
                Some(index) => {
                    let pairing = &scratch.pairings[index];
                    scratch.observed.push(pairing.corner);
                    self.map
                        .update(pairing.corner, config.confirm_observations, |corner| {
                            kalman::update_with_inverse(
                                &corner.mean,
                                &corner.covariance,
                                &observation.z,
                                &observation.covariance,
                                &pairing.d_inverse,
                            )
                        });
                }
                // An observation that passed some corner's individual gate but fits no
                // joint hypothesis is ambiguous: it starts no corner, or the map would
                // fill with near-duplicates of corners already in it.
                None if !scratch.lists[i].is_empty() => {}
                None => {
                    if !self.has_similar_corner(observation, config, &mut scratch.ids) {
                        let state = CornerState {
                            mean: observation.z,
                            covariance: observation.covariance,
                            observations: 1,
                        };
                        scratch
                            .observed
                            .push(self.map.insert(state, config.confirm_observations));
                    }
                }
            }
        }

        // Within the field of view: |bearing| <= fov / 2, i.e. x >= r cos(fov / 2), which
        // spares an arctangent per tentative corner and particle.
        let (range, cos_half_fov) = (config.view_range, (0.5 * config.view_fov).cos());
        let in_view = |corner: &CornerState| {
            let (x, y) = frame.to_local(corner.mean.x, corner.mean.y);
            let r2 = x * x + y * y;
            r2 <= range * range && x >= r2.sqrt() * cos_half_fov
        };
        self.map
            .age_tentative(&scratch.observed, in_view, config.tentative_max_misses);
        log_likelihood
    }

    /// Whether the map has a corner within the duplicate radius with a similar heading.
    fn has_similar_corner(
        &self,
        observation: &WorldObservation,
        config: &SlamConfig,
        ids: &mut Vec<u32>,
    ) -> bool {
        let (x, y) = (observation.z.x, observation.z.y);
        ids.clear();
        self.map.near(x, y, config.duplicate_radius, ids);
        let radius_squared = config.duplicate_radius * config.duplicate_radius;
        ids.iter().filter_map(|&id| self.map.get(id)).any(|corner| {
            (corner.mean.x - x).powi(2) + (corner.mean.y - y).powi(2) <= radius_squared
                && wrap_angle(corner.mean.z - observation.z.z).abs() <= config.duplicate_heading
        })
    }
}
