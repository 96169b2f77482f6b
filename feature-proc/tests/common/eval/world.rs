//! A world of straight walls: exact ray casting, its true corners, and which of them a
//! sensor at a pose could be expected to detect.

use feature_proc::FeatureConfig;
use lidar_sim::RayCaster;
use lidar_sim::geometry::Segment;
use slam_geom::MeasuredCorner;
use slam_geom::wrap_angle;

use super::score::{CornerScore, score_corners};

pub use slam_geom::TrueCorner;

/// The beam pattern of a simulated scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanGeometry {
    pub angle_min: f64,
    pub angle_increment: f64,
    pub beams: usize,
    /// Rays that hit nothing closer read `+inf` (no return, REP 117).
    pub range_max: f64,
}

impl ScanGeometry {
    /// Whether a bearing in the sensor frame falls within the beams' span.
    fn covers(&self, bearing: f64) -> bool {
        let step = self.angle_increment.abs();
        let from_first = (bearing - self.angle_min) * self.angle_increment.signum();
        from_first.rem_euclid(std::f64::consts::TAU) / step <= (self.beams - 1) as f64 + 1e-9
    }
}

/// What makes a true corner one the extractor should find from a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    pub geometry: ScanGeometry,
    /// The corner and both arms within this range.
    pub max_range: f64,
    /// Length of each wall next to the corner that must be in sight, metres.
    pub min_arm_length: f64,
    /// Beams that must fall on the stretch of each wall in sight from the corner (its
    /// angular width over the beam step; probed up to 2 m from the corner).
    pub min_arm_beams: f64,
    /// Opening angles of the corners looked for, radians.
    pub min_angle: f64,
    pub max_angle: f64,
}

impl View {
    /// The corners `config` is meant to find with `geometry`, no farther than `max_range`.
    pub fn for_config(geometry: ScanGeometry, config: &FeatureConfig, max_range: f64) -> Self {
        Self {
            geometry,
            max_range: max_range.min(config.max_range),
            min_arm_length: feature_proc::MIN_LINE_LENGTH,
            min_arm_beams: config.min_line_points as f64,
            min_angle: feature_proc::CORNER_MIN_ANGLE,
            max_angle: feature_proc::CORNER_MAX_ANGLE,
        }
    }
}

/// Straight walls and the corners where they meet.
#[derive(Debug, Clone)]
pub struct World {
    walls: Vec<[[f64; 2]; 2]>,
    corners: Vec<TrueCorner>,
    /// The two walls of each corner.
    corner_walls: Vec<[usize; 2]>,
    /// The simulator's ray caster over `walls`.
    caster: RayCaster,
}

impl Default for World {
    fn default() -> Self {
        Self::new()
    }
}

impl World {
    pub fn new() -> Self {
        Self {
            walls: Vec::new(),
            corners: Vec::new(),
            corner_walls: Vec::new(),
            caster: RayCaster::from_segments(Vec::new()),
        }
    }

    /// Adds walls along `vertices`; with `closed` the last vertex joins the first. Every
    /// vertex where two of these walls meet becomes a true corner.
    pub fn add_polyline(&mut self, vertices: &[[f64; 2]], closed: bool) {
        let n = vertices.len();
        if n < 2 {
            return;
        }
        let first_wall = self.walls.len();
        let wall_count = if closed { n } else { n - 1 };
        for i in 0..wall_count {
            self.walls.push([vertices[i], vertices[(i + 1) % n]]);
        }
        for i in 0..n {
            if !closed && (i == 0 || i == n - 1) {
                continue;
            }
            let (before, after) = ((i + n - 1) % n, (i + 1) % n);
            let d1 = unit(vertices[before], vertices[i]);
            let d2 = unit(vertices[after], vertices[i]);
            let v = vertices[i];
            self.corners.push(TrueCorner {
                x: v[0],
                y: v[1],
                heading: wrap_angle((-(d1[1] + d2[1])).atan2(-(d1[0] + d2[0]))),
                angle: (d1[0] * d2[0] + d1[1] * d2[1]).clamp(-1.0, 1.0).acos(),
            });
            let wall_before = first_wall + (i + wall_count - 1) % wall_count;
            self.corner_walls
                .push([wall_before, first_wall + i % wall_count]);
        }
        self.caster = RayCaster::from_segments(
            self.walls
                .iter()
                .map(|[a, b]| Segment::new(*a, *b))
                .collect(),
        );
    }

    pub fn walls(&self) -> &[[[f64; 2]; 2]] {
        &self.walls
    }

    pub fn corners(&self) -> &[TrueCorner] {
        &self.corners
    }

    /// Distance along the ray from `origin` in direction `bearing` to the first wall.
    pub fn ray_cast(&self, origin: [f64; 2], bearing: f64) -> Option<f64> {
        self.caster.cast(origin, bearing, f64::INFINITY)
    }

    /// Exact ranges from a sensor at `pose` (`[x, y, yaw]`, world from sensor).
    pub fn scan(&self, pose: [f64; 3], geometry: &ScanGeometry) -> Vec<f32> {
        (0..geometry.beams)
            .map(|i| {
                let bearing = pose[2] + geometry.angle_min + i as f64 * geometry.angle_increment;
                match self.ray_cast([pose[0], pose[1]], bearing) {
                    Some(r) if r <= geometry.range_max => r as f32,
                    _ => f32::INFINITY,
                }
            })
            .collect()
    }

    /// The true corners the extractor should detect from `pose`: opening angle within the
    /// view's limits, and from the corner along both its walls an unbroken stretch of at
    /// least `min_arm_length` in line of sight, in range and in the field of view, wide
    /// enough for `min_arm_beams` beams.
    pub fn corners_in_view(&self, pose: [f64; 3], view: &View) -> Vec<TrueCorner> {
        let origin = [pose[0], pose[1]];
        let mut found = Vec::new();
        for (corner, walls) in self.corners.iter().zip(&self.corner_walls) {
            if corner.angle < view.min_angle || corner.angle > view.max_angle {
                continue;
            }
            let tip = [corner.x, corner.y];
            let arms_seen = walls.iter().all(|&wall| {
                let [a, b] = self.walls[wall];
                let far = if same(a, tip) { b } else { a };
                let along = unit(far, tip);
                let at = |s: f64| [tip[0] + s * along[0], tip[1] + s * along[1]];
                // The run of the wall in sight from the tip, probed every 2 cm up to 2 m:
                // enough to decide whether the arm is long enough and gets enough beams.
                let probe = distance(tip, far).min(view.min_arm_length.max(2.0));
                let steps = (probe / 0.02).ceil() as usize;
                let mut seen = 0.0;
                for k in 0..=steps {
                    let s = (k as f64 * 0.02).min(probe);
                    if !self.sees(pose, at(s), view) {
                        break;
                    }
                    seen = s;
                }
                let width = wrap_angle(bearing(origin, at(seen)) - bearing(origin, tip));
                seen > view.min_arm_length
                    && width.abs() / view.geometry.angle_increment.abs() >= view.min_arm_beams
            });
            if arms_seen {
                found.push(*corner);
            }
        }
        found
    }

    /// Scores corners `detected` from `pose` against this world: precision over every true
    /// corner, recall over those in `view`, each within `tolerance` metres.
    pub fn score(
        &self,
        detected: &[MeasuredCorner],
        pose: [f64; 3],
        view: &View,
        tolerance: f64,
    ) -> CornerScore {
        let in_view = self.corners_in_view(pose, view);
        score_corners(detected, pose, &self.corners, &in_view, tolerance)
    }

    /// Whether a point on a wall is in range, in the field of view and not hidden.
    fn sees(&self, pose: [f64; 3], point: [f64; 2], view: &View) -> bool {
        let origin = [pose[0], pose[1]];
        let range = distance(origin, point);
        let direction = bearing(origin, point);
        range <= view.max_range
            && view.geometry.covers(direction - pose[2])
            && self
                .ray_cast(origin, direction)
                .is_none_or(|hit| hit >= range - 1e-6)
    }
}

fn unit(to: [f64; 2], from: [f64; 2]) -> [f64; 2] {
    let d = distance(to, from);
    [(to[0] - from[0]) / d, (to[1] - from[1]) / d]
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn bearing(from: [f64; 2], to: [f64; 2]) -> f64 {
    (to[1] - from[1]).atan2(to[0] - from[0])
}

fn same(a: [f64; 2], b: [f64; 2]) -> bool {
    distance(a, b) < 1e-12
}
