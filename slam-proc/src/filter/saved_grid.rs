//! The saved map's occupancy grid while mapping on top of it: each scan's beams fit the
//! particles to the grid (the converged localizer's field and beam model: by the wall faces
//! a beam can end on, see [`crate::TrackingField`]), so the new run stays in the saved
//! map's frame between corner sightings. On a field of every occupied cell a forward-looking
//! scanner fits best a little ahead of its pose, and along a corridor, where the walls fix
//! little else, fit after fit carries the run down it.

use crate::localize::cell_frame::SeenCells;
use crate::localize::hill_climb::HillClimb;
use crate::localize::localizer::{ScanRanges, sample_beam_ends};
use crate::localize::map_fit::FitField;
use crate::localize::tracking_field::{TrackingField, beam_bearings};
use crate::localize_config::LocalizeConfig;
use nalgebra::{Matrix3, Vector3};
use saved_map::GridMap;
use slam_eval::MapFit;
use slam_geom::{Pose2, wrap_angle};

/// The hill-climb from smaller first steps: a particle is at most a few centimetres and a
/// fraction of a degree off the grid after one corner update's worth of the front end's
/// drift (half a metre of path), so the search's wide steps would only risk a neighbouring
/// wall.
const TRACKING: HillClimb = HillClimb {
    xy: 0.05,
    yaw: 0.02,
    ..HillClimb::SEARCH
};

/// The particle moves this fraction of the way to the grid's best fit at each update: less
/// than all of it smooths the fit's own jitter out of the path, and half still closes most
/// of a gap within a few updates.
pub(crate) const PULL: f64 = 0.5;
/// Beams of a scan that fit the particles to the saved grid, spread evenly over its valid
/// beams: as many as the localizer weights a particle by, enough to fix a pose in a room.
pub(crate) const BEAMS: usize = 120;
/// Only the beams that end in the saved grid's seen cells count (from the best particle's
/// pose: the same beams for every particle); with fewer than this fraction of them the grid
/// is left out of the scan. High: at the saved map's edge the grid holds walls seen from
/// afar, and a climb on a few of them pulls the run off its own.
pub(crate) const MIN_KNOWN: f64 = 0.8;
/// Back on the saved grid after this much path off it, metres, the particles may have
/// drifted beyond the tracking climb's reach: they climb once from the localizer's wider
/// search steps, and take the fit if it lies within three standard deviations of what the
/// front end can have drifted over the path off the grid. Ten metres: 0.2 m of drift at the
/// rate below, more than the tracking climb's small steps are made for.
pub(crate) const SEARCH_AFTER_M: f64 = 10.0;
/// That drift: translation standard deviation per metre of path off the grid, m/m (a
/// scan-matching front end's drift is a per cent or two of the path) ...
const DRIFT_XY_PER_METRE: f64 = 0.02;
/// ... rotation standard deviation per metre, rad/m ...
const DRIFT_YAW_PER_METRE: f64 = 0.002;
/// ... up to this translation standard deviation, metres: the cap keeps a long stretch off
/// the grid from admitting any fit at all ...
const MAX_DRIFT_XY: f64 = 3.0;
/// ... and this rotation standard deviation, radians.
const MAX_DRIFT_YAW: f64 = 0.2;

/// The pose covariance the front end can have drifted by over `length` metres of path off
/// the saved grid: standard deviations that grow with the path, up to the largest
/// ([`MAX_DRIFT_XY`], [`MAX_DRIFT_YAW`]).
pub(crate) fn drift_off_grid(length: f64) -> Matrix3<f64> {
    let length = length.max(0.0);
    let xy = (DRIFT_XY_PER_METRE * length).min(MAX_DRIFT_XY);
    let yaw = (DRIFT_YAW_PER_METRE * length).min(MAX_DRIFT_YAW);
    Matrix3::from_diagonal(&Vector3::new(xy * xy, xy * xy, yaw * yaw))
}

/// The saved grid's field and this scan's beam ends that fall on it.
#[derive(Debug, Clone)]
pub(crate) struct SavedGrid {
    /// Which cells the saved map has seen.
    seen: SeenCells,
    /// What the beams are scored on: the converged localizer's field.
    tracking: TrackingField,
    /// This scan's sampled beam ends, sensor frame.
    beams: Vec<[f64; 2]>,
    /// Those of them that end in the grid's seen cells from the best particle's pose ...
    known: Vec<[f64; 2]>,
    /// ... and the bearings they left the sensor at.
    bearings: Vec<f64>,
    /// How the map's fit judges a beam ...
    fit_field: FitField,
    /// ... and the ends of this scan's beams it judges, sensor frame.
    fit_beams: Vec<[f64; 2]>,
}

impl SavedGrid {
    /// The field of `grid` under the localizer's beam model (`localize`).
    pub fn new(grid: &GridMap, localize: &LocalizeConfig) -> Self {
        Self {
            seen: SeenCells::of(grid),
            tracking: TrackingField::new(grid, localize),
            beams: Vec::new(),
            known: Vec::new(),
            bearings: Vec::new(),
            fit_field: FitField::new(grid, slam_eval::MAP_FIT_WITHIN_M),
            fit_beams: Vec::new(),
        }
    }

    /// Takes the scan the next step brings (`None`: its beams did not arrive, the grid
    /// sits that step out).
    pub fn set_scan(&mut self, scan: Option<&ScanRanges<'_>>, beams: usize) {
        self.known.clear();
        self.bearings.clear();
        match scan {
            Some(scan) => {
                sample_beam_ends(scan, beams, &mut self.beams);
                sample_beam_ends(scan, slam_eval::MAP_FIT_BEAMS_PER_SCAN, &mut self.fit_beams);
            }
            None => {
                self.beams.clear();
                self.fit_beams.clear();
            }
        }
    }

    /// Judges the scan's beams from `pose` into `fit`: how well the saved map explains the
    /// run's scans.
    pub fn judge_fit(&self, pose: &Pose2, fit: &mut MapFit) {
        self.fit_field.judge(&self.fit_beams, pose, fit);
    }

    /// Keeps the beams that end in seen cells from `pose` (the best particle's prediction);
    /// true when at least `min_known` of them do, so that the grid can judge the scan.
    pub fn select_known(&mut self, pose: &Pose2, min_known: f64) -> bool {
        let (s, c) = pose.yaw.sin_cos();
        self.known.clear();
        self.known
            .extend(self.beams.iter().copied().filter(|[px, py]| {
                self.seen
                    .contains(pose.x + c * px - s * py, pose.y + s * px + c * py)
            }));
        beam_bearings(&self.known, &mut self.bearings);
        !self.known.is_empty() && self.known.len() as f64 >= min_known * self.beams.len() as f64
    }

    /// `pose` moved `pull` of the way uphill on the selected beams' likelihood.
    pub fn refine(&self, pose: Pose2, pull: f64) -> Pose2 {
        let fit = TRACKING.climb_on(|pose| self.log_likelihood(pose), pose);
        Pose2::new(
            pose.x + pull * (fit.x - pose.x),
            pose.y + pull * (fit.y - pose.y),
            // The fit's yaw may have wrapped past +-pi.
            pose.yaw + pull * wrap_angle(fit.yaw - pose.yaw),
        )
    }

    /// `pose` moved to the best fit uphill from it by the localizer's search steps, when
    /// that fit is within three standard deviations of what the front end can have drifted
    /// (`drift`: the x-y and yaw variances since the grid last judged a scan); else the
    /// tracking climb's `pull` of the way. The search's steps reach the basin of a
    /// neighbouring wall a metre and tens of degrees away, which a few metres of drift
    /// cannot explain, and a run taken there never comes back.
    pub fn search(&self, pose: Pose2, drift: &Matrix3<f64>, pull: f64) -> Pose2 {
        let fit = HillClimb::SEARCH.climb_on(|pose| self.log_likelihood(pose), pose);
        let within = |offset: f64, variance: f64| offset * offset <= 9.0 * variance;
        if within(
            (fit.x - pose.x).hypot(fit.y - pose.y),
            drift[(0, 0)].max(drift[(1, 1)]),
        ) && within(wrap_angle(fit.yaw - pose.yaw), drift[(2, 2)])
        {
            fit
        } else {
            self.refine(pose, pull)
        }
    }

    /// The selected beams' log-likelihood from `pose`.
    pub fn log_likelihood(&self, pose: &Pose2) -> f64 {
        self.tracking.scan_score(&self.known, &self.bearings, pose)
    }

    /// Forgets the scan once a step has used it.
    pub fn clear_scan(&mut self) {
        self.beams.clear();
        self.fit_beams.clear();
        self.known.clear();
        self.bearings.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::{BEAMS, MIN_KNOWN, PULL, SavedGrid, drift_off_grid};
    use crate::config::SlamConfig;
    use crate::filter::fast_slam::{FastSlam, FilterStats};
    use crate::filter::observation::MeasuredMotion;
    use crate::localize::localizer::ScanRanges;
    use crate::localize::tracking_field::{TrackingField, beam_bearings};
    use nalgebra::{Matrix3, Matrix4};
    use saved_map::{CellState, GridMap, MapYaml};
    use slam_eval::{FitVerdict, MAP_FIT_BEAMS_PER_SCAN, MAP_FIT_MIN_BEAMS};
    use slam_geom::{MapCorner, Pose2};

    /// A room's walls, x in [-1, 9], y in [-3, 3].
    const ROOM: [f64; 4] = [-1.0, 9.0, -3.0, 3.0];
    const RESOLUTION: f64 = 0.05;
    const ORIGIN: [f64; 2] = [-2.0, -4.0];

    /// The room as a saved grid: its walls occupied, inside free, outside unknown.
    fn room_grid() -> GridMap {
        grid_of(ROOM)
    }

    /// The grid of a room with walls at `[x0, x1, y0, y1]`, as [`room_grid`]'s.
    fn grid_of(room: [f64; 4]) -> GridMap {
        let (width, height) = (240, 160);
        let mut cells = Vec::with_capacity(width * height);
        for row in 0..height {
            for col in 0..width {
                let x = ORIGIN[0] + (col as f64 + 0.5) * RESOLUTION;
                let y = ORIGIN[1] + (row as f64 + 0.5) * RESOLUTION;
                let [x0, x1, y0, y1] = room;
                // Walls 0.1 m thick, their inner face on the room's edge: a beam that a
                // drifted pose carries past the face still ends in a seen cell.
                let thick = |v: f64, wall: f64, outward: f64| {
                    let d = (v - wall) * outward;
                    (-0.5 * RESOLUTION..=0.1).contains(&d)
                };
                let inside = x > x0 && x < x1 && y > y0 && y < y1;
                let along_x = x >= x0 - 0.1 && x <= x1 + 0.1;
                let along_y = y >= y0 - 0.1 && y <= y1 + 0.1;
                let on_wall = (thick(x, x0, -1.0) || thick(x, x1, 1.0)) && along_y
                    || (thick(y, y0, -1.0) || thick(y, y1, 1.0)) && along_x;
                cells.push(if on_wall {
                    CellState::Occupied
                } else if inside {
                    CellState::Free
                } else {
                    CellState::Unknown
                });
            }
        }
        GridMap {
            yaml: MapYaml::trinary("map.pgm", RESOLUTION, ORIGIN),
            width,
            height,
            cells,
        }
    }

    /// A 360-beam scan of the room from `pose` (inside it).
    fn scan_from(pose: &Pose2) -> Vec<f32> {
        let [x0, x1, y0, y1] = ROOM;
        (0..360)
            .map(|i| {
                let bearing = pose.yaw - std::f64::consts::PI + f64::from(i).to_radians();
                let (s, c) = bearing.sin_cos();
                let tx = if c > 0.0 {
                    (x1 - pose.x) / c
                } else {
                    (x0 - pose.x) / c
                };
                let ty = if s > 0.0 {
                    (y1 - pose.y) / s
                } else {
                    (y0 - pose.y) / s
                };
                tx.min(ty) as f32
            })
            .collect()
    }

    /// The ranges of [`scan_from`] as the scan they are.
    fn room_scan(ranges: &[f32]) -> ScanRanges<'_> {
        ScanRanges {
            angle_min: -std::f64::consts::PI,
            angle_increment: 1f64.to_radians(),
            range_min: 0.1,
            range_max: 30.0,
            ranges,
        }
    }

    /// Drives 7 m along the room with a front end that overstates every step by 5 % and
    /// turns 0.004 rad a step that the robot does not; returns the best particle's last
    /// pose and the truth.
    fn drive(saved_grid: Option<&GridMap>) -> (Pose2, Pose2) {
        let config = SlamConfig {
            particles: 20,
            ..SlamConfig::default()
        };
        let mut slam = FastSlam::new(config, 7).unwrap();
        if let Some(grid) = saved_grid {
            slam = slam.with_saved_grid(grid);
        }
        let drifting = MeasuredMotion {
            increment: Pose2::new(0.105, 0.0, 0.004),
            covariance: Matrix3::identity() * 1e-6,
            wheel_increment: None,
        };
        let standing = MeasuredMotion {
            increment: Pose2::IDENTITY,
            ..drifting
        };
        let mut truth = Pose2::IDENTITY;
        let mut last = Pose2::IDENTITY;
        for k in 0..71u32 {
            if k > 0 {
                truth = truth.compose(&Pose2::new(0.1, 0.0, 0.0));
            }
            let ranges = scan_from(&truth);
            let scan = room_scan(&ranges);
            slam.set_scan(Some(&scan));
            let motion = if k == 0 { &standing } else { &drifting };
            last = slam
                .process_measured(u64::from(k) * 25_000_000, &[], &[], motion)
                .best;
        }
        (last, truth)
    }

    #[test]
    fn the_drift_off_the_grid_grows_with_the_path_up_to_its_cap() {
        // 0.02 m and 0.002 rad per metre, up to 3 m and 0.2 rad.
        let p = drift_off_grid(50.0);
        assert!((p[(0, 0)].sqrt() - 1.0).abs() < 1e-12);
        assert_eq!(p[(0, 0)], p[(1, 1)]);
        assert!((p[(2, 2)].sqrt() - 0.1).abs() < 1e-12);
        let far = drift_off_grid(1000.0);
        assert!((far[(0, 0)].sqrt() - 3.0).abs() < 1e-12);
        assert!((far[(2, 2)].sqrt() - 0.2).abs() < 1e-12);
        assert_eq!(drift_off_grid(-1.0), Matrix3::zeros());
    }

    #[test]
    fn the_search_moves_a_particle_only_as_far_as_the_drift_allows() {
        // A particle 0.3 m and 0.25 rad off the pose the scan was taken from: the search's
        // climb finds the true pose, which takes it after 50 m off the grid (a metre and
        // 0.1 rad of drift allowed) and not after 10 m (0.2 m and 0.02 rad).
        let config = SlamConfig::default();
        let mut grid = SavedGrid::new(&room_grid(), &config.localize);
        let truth = Pose2::new(4.0, 0.5, 0.0);
        let ranges = scan_from(&truth);
        let scan = room_scan(&ranges);
        grid.set_scan(Some(&scan), BEAMS);
        assert!(grid.select_known(&truth, MIN_KNOWN));
        let off = Pose2::new(4.2, 0.72, 0.25);
        let pull = PULL;

        let found = grid.search(off, &drift_off_grid(50.0), pull);
        assert!(
            (found.x - truth.x).hypot(found.y - truth.y) < 0.05,
            "{found:?}"
        );
        assert!(found.yaw.abs() < 0.02, "{found:?}");

        let kept = grid.search(off, &drift_off_grid(10.0), pull);
        assert_eq!(kept, grid.refine(off, pull));
        assert!(kept.yaw > 0.15, "{kept:?}");
    }

    #[test]
    fn the_beams_are_scored_as_the_converged_localizer_scores_them() {
        // By the wall faces a beam can end on: the climb then does not carry a forward-looking
        // scanner ahead along a corridor, where ends sunk into a wall would score as well.
        let config = SlamConfig::default();
        let saved = room_grid();
        let mut grid = SavedGrid::new(&saved, &config.localize);
        let truth = Pose2::new(4.0, 0.5, 0.3);
        let ranges = scan_from(&truth);
        grid.set_scan(Some(&room_scan(&ranges)), BEAMS);
        assert!(grid.select_known(&truth, MIN_KNOWN));
        let localizer = TrackingField::new(&saved, &config.localize);
        let mut bearings = Vec::new();
        beam_bearings(&grid.known, &mut bearings);
        for pose in [
            truth,
            Pose2::new(4.05, 0.48, 0.31),
            Pose2::new(3.9, 0.6, 0.28),
        ] {
            let expected = localizer.scan_score(&grid.known, &bearings, &pose);
            assert_eq!(grid.log_likelihood(&pose), expected, "{pose:?}");
        }
        // And the climb from near the truth comes back to it, to within a cell (the faces
        // are the cells' edges).
        let fit = grid.refine(Pose2::new(4.04, 0.47, 0.31), 1.0);
        assert!(
            (fit.x - truth.x).hypot(fit.y - truth.y) < RESOLUTION,
            "{fit:?}"
        );
        assert!((fit.yaw - truth.yaw).abs() < 0.01, "{fit:?}");
    }

    #[test]
    fn mapping_on_a_saved_grid_keeps_a_drifting_run_on_the_grid() {
        let grid = room_grid();
        let (alone, truth) = drive(None);
        let off = (alone.x - truth.x).hypot(alone.y - truth.y);
        // The drift alone: 0.35 m along the room and 0.28 rad of turn, about a metre off.
        assert!(off > 0.5, "without the grid {alone:?} vs {truth:?}");
        let (on_grid, truth) = drive(Some(&grid));
        let off = (on_grid.x - truth.x).hypot(on_grid.y - truth.y);
        // The last update was under half a metre of drift ago: a few centimetres.
        assert!(off < 0.06, "on the grid {on_grid:?} vs {truth:?}");
        assert!(on_grid.yaw.abs() < 0.03, "on the grid {on_grid:?}");
    }

    /// Maps the room on `grid` with `saved` as the saved map's corners, from its origin 7 m
    /// along it (an update every step, so that the saved map's fit has its verdict on the
    /// way); the filter's summary and its map.
    fn map_the_room_on(grid: &GridMap, saved: &[MapCorner]) -> (FilterStats, Vec<MapCorner>) {
        let config = SlamConfig {
            particles: 20,
            update_min_distance: 0.1,
            ..SlamConfig::default()
        };
        let mut slam = FastSlam::with_prior_map_from(config, 7, saved, Pose2::IDENTITY)
            .unwrap()
            .with_saved_grid(grid);
        let mut truth = Pose2::IDENTITY;
        for k in 0..71u32 {
            let step = if k == 0 { 0.0 } else { 0.1 };
            truth = truth.compose(&Pose2::new(step, 0.0, 0.0));
            let ranges = scan_from(&truth);
            slam.set_scan(Some(&room_scan(&ranges)));
            let motion = MeasuredMotion {
                increment: Pose2::new(step, 0.0, 0.0),
                covariance: Matrix3::identity() * 1e-6,
                wheel_increment: None,
            };
            slam.process_measured(u64::from(k) * 25_000_000, &[], &[], &motion);
        }
        (slam.stats(), slam.best_map())
    }

    #[test]
    fn a_saved_map_of_another_room_is_set_aside_and_its_corners_leave_the_map() {
        // The saved map's corners: the room's four.
        let [x0, x1, y0, y1] = ROOM;
        let corners: Vec<MapCorner> = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
            .iter()
            .map(|&(x, y)| MapCorner {
                x,
                y,
                heading: (-y).atan2(-(x - 4.0)),
                angle: std::f64::consts::FRAC_PI_2,
                covariance: Matrix4::identity() * 1e-4,
                observations: 5,
            })
            .collect();
        // On the room's own map: every beam ends on its walls, and the map stays.
        let (stats, map) = map_the_room_on(&room_grid(), &corners);
        assert_eq!(stats.map_fit.verdict(), FitVerdict::Fits, "{stats:?}");
        assert!(stats.map_fit.share().unwrap() > 0.95, "{stats:?}");
        assert_eq!(stats.saved_map_set_aside_at, None);
        assert_eq!(map.len(), corners.len());
        // On the map of a smaller room that shares the start: the beams pass through its
        // walls or end in its free space. Set aside once enough beams are judged, the
        // saved corners gone and the counts stopped where the verdict was.
        let (stats, map) = map_the_room_on(&grid_of([-1.0, 3.0, -1.5, 4.5]), &corners);
        assert_eq!(stats.map_fit.verdict(), FitVerdict::DoesNotFit, "{stats:?}");
        assert!(stats.map_fit.share().unwrap() < 0.3, "{stats:?}");
        let at = stats.saved_map_set_aside_at.expect("set aside");
        assert!(at < 71, "{stats:?}");
        assert!(stats.map_fit.beams_judged < MAP_FIT_MIN_BEAMS + MAP_FIT_BEAMS_PER_SCAN as u64);
        assert!(map.is_empty(), "{map:?}");
    }
}
