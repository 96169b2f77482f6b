//! Segmentation with the adaptive breakpoint detector (Borges & Aldon 2004): the largest
//! distance between neighbouring points of one surface grows with their range and the beam
//! spacing, so far walls are not shattered and near objects are not joined.

use std::ops::Range;

use crate::config::FeatureConfig;
use crate::scan::{BeamPattern, ScanPoint};

/// Cuts `points` (valid readings in beam order) into segments, ranges of `points` with at
/// least `min_line_points` points each.
///
/// A 360-degree scan is first rotated to begin just after a break, so no surface is cut at
/// the seam; with no break at all it begins at the point farthest from the first one, which
/// is a vertex of the scanned outline (the farthest point of a polygon from any point is).
pub(crate) fn segment(
    points: &mut [ScanPoint],
    geometry: BeamPattern,
    config: &FeatureConfig,
    segments: &mut Vec<Range<usize>>,
) {
    segments.clear();
    let breakpoints = Breakpoints::new(geometry, config);
    if geometry.cyclic {
        let start = cyclic_start(points, geometry.count, &breakpoints);
        points.rotate_left(start);
    }
    let mut segment_start = 0;
    for i in 1..points.len() {
        let (a, b) = (&points[i - 1], &points[i]);
        if breakpoints.is_break(a, b, steps(a, b, geometry.count)) {
            close(segment_start, i, config, segments);
            segment_start = i;
        }
    }
    close(segment_start, points.len(), config, segments);
}

fn close(start: usize, end: usize, config: &FeatureConfig, segments: &mut Vec<Range<usize>>) {
    if end - start >= config.min_line_points {
        segments.push(start..end);
    }
}

/// Beams from `a` to the next point `b`, across the seam of a rotated 360-degree scan too
/// (a single point is its own neighbour a full turn away).
fn steps(a: &ScanPoint, b: &ScanPoint, count: usize) -> usize {
    if b.beam > a.beam {
        b.beam - a.beam
    } else {
        b.beam + count - a.beam
    }
}

/// Where to begin a 360-degree scan: at the first point after a break.
fn cyclic_start(points: &[ScanPoint], count: usize, breakpoints: &Breakpoints) -> usize {
    let Some(origin) = points.first() else {
        return 0;
    };
    for (i, b) in points.iter().enumerate() {
        let a = &points[if i == 0 { points.len() - 1 } else { i - 1 }];
        if breakpoints.is_break(a, b, steps(a, b, count)) {
            return i;
        }
    }
    let mut farthest = (0, 0.0);
    for (i, p) in points.iter().enumerate() {
        let distance = p.distance(origin);
        if distance > farthest.1 {
            farthest = (i, distance);
        }
    }
    farthest.0
}

/// The breakpoint distance of the adaptive breakpoint detector for neighbours `steps`
/// beams apart, per metre of range: `sin(dphi) / sin(lambda - dphi)`, or `None` where
/// `dphi >= lambda` and no surface can be followed. Indexed by `steps`, a handful of
/// entries, so the hot loop needs no trigonometry.
/// The shallowest angle between a beam and a surface that is still followed as one segment,
/// radians: below Borges & Aldon's 10 degrees, so walls seen at a grazing angle (pillar sides
/// far away) stay whole, while split-and-merge still cuts real jumps. Neighbouring points
/// further apart than `r * sin(dphi) / sin(lambda - dphi) + 3 * wall sigma` start a new
/// segment.
const BREAKPOINT_LAMBDA: f64 = 0.1;
/// Invalid beams bridged inside a segment: a dark patch on a wall should not cut it, and
/// more than two missing beams in a row is more likely a gap between two surfaces.
const MAX_INVALID_GAP: usize = 2;

#[derive(Debug, Clone, Copy)]
pub(crate) struct Breakpoints {
    factors: [Option<f64>; Self::MAX_STEPS + 1],
    margin: f64,
}

impl Breakpoints {
    /// Room for [`MAX_INVALID_GAP`] beams bridged, and the beam after them.
    const MAX_STEPS: usize = MAX_INVALID_GAP + 1;

    pub fn new(geometry: BeamPattern, config: &FeatureConfig) -> Self {
        let mut factors = [None; Self::MAX_STEPS + 1];
        for (steps, factor) in factors.iter_mut().enumerate().skip(1) {
            let dphi = geometry.spacing * steps as f64;
            if dphi < BREAKPOINT_LAMBDA {
                *factor = Some(dphi.sin() / (BREAKPOINT_LAMBDA - dphi).sin());
            }
        }
        Self {
            factors,
            margin: 3.0 * config.wall_sigma(),
        }
    }

    /// Whether two valid points `steps` beams apart belong to different surfaces.
    fn is_break(&self, a: &ScanPoint, b: &ScanPoint, steps: usize) -> bool {
        let Some(&Some(factor)) = self.factors.get(steps) else {
            return true;
        };
        // The nearer range: a surface at the shallowest angle lambda to the beam puts its
        // next point this far away, whichever way the range changes.
        let nearer = if a.range < b.range { a.range } else { b.range };
        let limit = nearer * factor + self.margin;
        let (dx, dy) = (a.x - b.x, a.y - b.y);
        dx * dx + dy * dy > limit * limit
    }
}
