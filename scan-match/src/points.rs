//! From ranges to the points the matcher uses: every valid beam, its surface normal from
//! the neighbouring beams, then thinned to one point per voxel.

use nalgebra::{Matrix2, Vector2};

use crate::bearings::Bearings;
use crate::cell_hash::{CellSet, cell_key};
use slam_geom::ScanGeometry;

/// Fewest neighbouring beams on each side that a normal is fitted over.
const NORMAL_HALF_WINDOW: usize = 3;
/// Most neighbouring beams on each side that a normal is fitted over.
const MAX_NORMAL_HALF_WINDOW: usize = 12;
/// Half the length of wall, metres, a normal is fitted over when the beams are dense.
const NORMAL_EXTENT: f64 = 0.1;

/// A scan point in the robot frame with the unit normal of its surface, pointing towards
/// the sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    pub point: Vector2<f64>,
    pub normal: Vector2<f64>,
}

/// The usable points of one scan and how many beams were valid.
#[derive(Debug, Clone, Default)]
pub struct ScanPoints {
    pub points: Vec<SurfacePoint>,
    pub valid_beams: usize,
}

/// Valid beams to points, normals fitted over their neighbours along the scan, thinned to
/// the first point of each `voxel` cell. Points on no straight-enough surface (clutter,
/// isolated returns, the edges of depth jumps) get no normal and are dropped: a
/// point-to-line residual needs one, and such points are the least repeatable.
pub fn extract(
    geometry: &ScanGeometry,
    ranges: &[f32],
    range_sigma: f64,
    voxel: f64,
) -> ScanPoints {
    Extractor::default().extract(geometry, ranges, range_sigma, voxel)
}

/// [`extract`] with its bearings and buffers kept from one scan to the next.
#[derive(Debug, Clone, Default)]
pub struct Extractor {
    bearings: Bearings,
    raw: Vec<(usize, Vector2<f64>, f64)>,
    taken: CellSet,
}

impl Extractor {
    /// See [`extract`].
    pub fn extract(
        &mut self,
        geometry: &ScanGeometry,
        ranges: &[f32],
        range_sigma: f64,
        voxel: f64,
    ) -> ScanPoints {
        let directions = self.bearings.directions(geometry, ranges.len());
        let raw = &mut self.raw;
        raw.clear();
        for (i, (&r, direction)) in ranges.iter().zip(directions).enumerate() {
            let r = f64::from(r);
            if !r.is_finite() || r < geometry.range_min || r > geometry.range_max || r <= 0.0 {
                continue;
            }
            raw.push((i, direction * r, r));
        }
        let taken = &mut self.taken;
        taken.clear();
        thin(geometry, raw, taken, range_sigma, voxel)
    }
}

/// Normals for the valid beams `raw` (beam index, point, range), one point per voxel.
fn thin(
    geometry: &ScanGeometry,
    raw: &[(usize, Vector2<f64>, f64)],
    taken: &mut CellSet,
    range_sigma: f64,
    voxel: f64,
) -> ScanPoints {
    let step = geometry.angle_increment.abs();
    let valid_beams = raw.len();
    let mut points = Vec::with_capacity(raw.len());
    for k in 0..raw.len() {
        let (_, p, r) = raw[k];
        // Only the first point of a voxel with a normal is kept: a voxel already taken
        // needs no fit.
        let voxel_key = cell_key(p.x, p.y, voxel);
        if taken.contains(&voxel_key) {
            continue;
        }
        // The window spans at least NORMAL_EXTENT of wall: over a few centimetres, range
        // noise tilts a normal by tenths of a radian, and a wall seen by a dense scanner
        // close by would seem to fix the motion along itself. (Narrow windows as a fallback
        // where the wide one is no line gave those tilted normals back at every edge.)
        let wide = ((NORMAL_EXTENT / (r * step)).ceil() as usize)
            .clamp(NORMAL_HALF_WINDOW, MAX_NORMAL_HALF_WINDOW);
        let fitted = fit_normal(raw, k, wide, step, voxel, range_sigma);
        let Some(normal) = fitted else {
            continue;
        };
        taken.insert(voxel_key);
        // Towards the sensor, so the two faces of a thin wall never pair up.
        let normal = if normal.dot(&p) > 0.0 {
            -normal
        } else {
            normal
        };
        points.push(SurfacePoint { point: p, normal });
    }
    ScanPoints {
        points,
        valid_beams,
    }
}

/// The normal at point `k` of `raw` from the beams within `half_window` of it on one
/// surface, if they lie on a line.
fn fit_normal(
    raw: &[(usize, Vector2<f64>, f64)],
    k: usize,
    half_window: usize,
    step: f64,
    voxel: f64,
    range_sigma: f64,
) -> Option<Vector2<f64>> {
    let (beam, p, r) = raw[k];
    // Neighbours on one surface are a few beam spacings apart at this range (more on an
    // oblique wall); a larger gap is a depth jump to another surface.
    let radius = (4.0 * half_window as f64 * r * step).clamp(2.0 * voxel, 1.0);
    let lo = k.saturating_sub(half_window);
    let hi = (k + half_window).min(raw.len() - 1);
    let mut n = 0.0;
    let mut sum = Vector2::zeros();
    let mut sum_sq = Matrix2::zeros();
    for &(other_beam, q, _) in &raw[lo..=hi] {
        if other_beam.abs_diff(beam) > half_window || (q - p).norm_squared() > radius * radius {
            continue;
        }
        n += 1.0;
        sum += q;
        sum_sq += q * q.transpose();
    }
    if n < 3.0 {
        return None;
    }
    let mean = sum / n;
    let cov = sum_sq / n - mean * mean.transpose();
    line_normal(&cov, range_sigma)
}

/// The unit normal of the line through points of scatter `cov`, if they lie on one: the
/// spread across it within a few range sigmas (plus a little for a gently curved surface).
fn line_normal(cov: &Matrix2<f64>, range_sigma: f64) -> Option<Vector2<f64>> {
    let (a, b, c) = (cov[(0, 0)], cov[(0, 1)], cov[(1, 1)]);
    let half_trace = 0.5 * (a + c);
    let root = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let small = half_trace - root;
    let large = half_trace + root;
    if large.is_nan() || large <= 0.0 || small > 9.0 * range_sigma * range_sigma + 0.01 * large {
        return None;
    }
    // The eigenvector of the larger eigenvalue runs along the line; the normal is across.
    let along = if b.abs() > 1e-15 {
        Vector2::new(large - c, b)
    } else if a >= c {
        Vector2::new(1.0, 0.0)
    } else {
        Vector2::new(0.0, 1.0)
    };
    let norm = along.norm();
    if norm.is_nan() || norm <= 0.0 {
        return None;
    }
    Some(Vector2::new(-along.y, along.x) / norm)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn a_wall_gives_points_with_normals_towards_the_sensor() {
        // A wall at x = 2, seen over +-40 degrees.
        let geometry = ScanGeometry {
            angle_min: -0.7,
            angle_increment: PI / 360.0,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.1,
            range_max: 30.0,
        };
        let n = (1.4 / geometry.angle_increment) as usize;
        let mut ranges: Vec<f32> = (0..n)
            .map(|i| {
                (2.0 / (geometry.angle_min + i as f64 * geometry.angle_increment).cos()) as f32
            })
            .collect();
        ranges[5] = f32::NAN;
        ranges[6] = f32::INFINITY;
        ranges[7] = 0.05;
        let scan = extract(&geometry, &ranges, 0.01, 0.05);
        assert_eq!(scan.valid_beams, n - 3);
        assert!(scan.points.len() > 20 && scan.points.len() < n);
        for p in &scan.points {
            assert!((p.point.x - 2.0).abs() < 1e-5);
            assert!((p.normal - Vector2::new(-1.0, 0.0)).norm() < 1e-4);
        }
    }

    #[test]
    fn a_dense_scan_of_a_near_wall_gives_normals_that_do_not_tilt() {
        // A UTM-30LX (0.25 degree steps) 1.25 m from a corridor wall along x, with 1 cm of
        // range noise from a fixed sequence: over the few centimetres seven beams span, the
        // noise would tilt the normals by tenths of a radian, and the wall would seem to fix
        // the motion along itself.
        let geometry = ScanGeometry {
            angle_min: 0.3,
            angle_increment: PI / 720.0,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.1,
            range_max: 30.0,
        };
        let n = ((PI - 0.6) / geometry.angle_increment) as usize;
        let mut state = 12345_u64;
        let ranges: Vec<f32> = (0..n)
            .map(|i| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.035;
                let bearing = geometry.angle_min + i as f64 * geometry.angle_increment;
                (1.25 / bearing.sin() + noise) as f32
            })
            .collect();
        let scan = extract(&geometry, &ranges, 0.01, 0.05);
        assert!(scan.points.len() > 50);
        // What the normals say about motion along the wall, against across it.
        let along: f64 = scan.points.iter().map(|p| p.normal.x * p.normal.x).sum();
        let across: f64 = scan.points.iter().map(|p| p.normal.y * p.normal.y).sum();
        assert!(along < 0.01 * across, "along {along}, across {across}");
    }
}
