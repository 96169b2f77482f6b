//! Constructed scans: a 2D world of wall segments ray-cast from a pose.

#![allow(dead_code)]

use slam_geom::Pose2;
use slam_geom::ScanGeometry;

pub type Segment = ((f64, f64), (f64, f64));

/// A SICK-like sensor: 361 beams over 180 degrees, 30 m.
pub const SICK: ScanGeometry = ScanGeometry {
    angle_min: -std::f64::consts::FRAC_PI_2,
    angle_increment: std::f64::consts::PI / 360.0,
    time_increment: 0.0,
    scan_time: 0.0,
    range_min: 0.05,
    range_max: 30.0,
};

/// A Hokuyo-like sensor: 1081 beams over 270 degrees.
pub const HOKUYO: ScanGeometry = ScanGeometry {
    angle_min: -0.75 * std::f64::consts::PI,
    angle_increment: std::f64::consts::PI / 720.0,
    time_increment: 0.0,
    scan_time: 0.0,
    range_min: 0.05,
    range_max: 30.0,
};

/// A 12 x 8 m room with a pillar, a box and a recess: every direction constrained.
pub fn room() -> Vec<Segment> {
    let mut walls = vec![
        ((-4.0, -3.0), (8.0, -3.0)),
        ((8.0, -3.0), (8.0, 5.0)),
        ((8.0, 5.0), (2.0, 5.0)),
        ((2.0, 5.0), (2.0, 4.0)),
        ((2.0, 4.0), (0.0, 4.0)),
        ((0.0, 4.0), (0.0, 5.0)),
        ((0.0, 5.0), (-4.0, 5.0)),
        ((-4.0, 5.0), (-4.0, -3.0)),
    ];
    walls.extend(square(3.0, 1.5, 0.4));
    walls.extend(square(-2.0, -1.0, 0.6));
    walls
}

/// A straight corridor 2 m wide along x, far longer than the sensor's range.
pub fn corridor() -> Vec<Segment> {
    vec![
        ((-100.0, -1.0), (100.0, -1.0)),
        ((-100.0, 1.0), (100.0, 1.0)),
    ]
}

/// [`corridor`] with a recess `depth` metres deep into its left wall between `from` and
/// `to` along x: the one feature along its length.
pub fn corridor_with_recess(from: f64, to: f64, depth: f64) -> Vec<Segment> {
    vec![
        ((-100.0, -1.0), (100.0, -1.0)),
        ((-100.0, 1.0), (from, 1.0)),
        ((from, 1.0), (from, 1.0 + depth)),
        ((from, 1.0 + depth), (to, 1.0 + depth)),
        ((to, 1.0 + depth), (to, 1.0)),
        ((to, 1.0), (100.0, 1.0)),
    ]
}

fn square(cx: f64, cy: f64, half: f64) -> Vec<Segment> {
    let c = [
        (cx - half, cy - half),
        (cx + half, cy - half),
        (cx + half, cy + half),
        (cx - half, cy + half),
    ];
    (0..4).map(|i| (c[i], c[(i + 1) % 4])).collect()
}

/// Ranges seen from `pose` (+inf where nothing is hit within range), with a deterministic
/// pseudo-random noise of standard deviation about `noise` metres.
pub fn raycast(
    walls: &[Segment],
    pose: &Pose2,
    geometry: &ScanGeometry,
    beams: usize,
    noise: f64,
) -> Vec<f32> {
    let mut state: u64 =
        0x9e37_79b9_7f4a_7c15 ^ (pose.x.to_bits() ^ pose.yaw.to_bits().rotate_left(17));
    (0..beams)
        .map(|i| {
            let bearing = pose.yaw + geometry.angle_min + i as f64 * geometry.angle_increment;
            let (dy, dx) = bearing.sin_cos();
            let mut best = f64::INFINITY;
            for &((x1, y1), (x2, y2)) in walls {
                let (ex, ey) = (x2 - x1, y2 - y1);
                let det = dx * -ey + ex * dy;
                if det.abs() < 1e-12 {
                    continue;
                }
                let (wx, wy) = (x1 - pose.x, y1 - pose.y);
                let t = (wx * -ey + ex * wy) / det;
                let u = (dx * wy - dy * wx) / det;
                if t > 0.0 && (0.0..=1.0).contains(&u) && t < best {
                    best = t;
                }
            }
            if best > geometry.range_max {
                return f32::INFINITY;
            }
            // Sum of uniforms: roughly Gaussian, reproducible without a dependency.
            let mut sum = 0.0;
            for _ in 0..4 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                sum += (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            }
            (best + noise * sum * 3.0_f64.sqrt()) as f32
        })
        .collect()
}
