//! Exact planar primitives: ray against segment, distances between segments.

use crate::Point2;

/// Tolerance on the segment parameter, so that a beam aimed exactly at a vertex hits it
/// whichever of the two segments' rounding it meets.
const VERTEX_SLACK: f64 = 1e-9;

/// `a x b`, the z of the 3D cross product.
pub fn cross(a: Point2, b: Point2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// A wall segment from `a` to `a + e`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub a: Point2,
    pub e: Point2,
}

impl Segment {
    pub fn new(start: [f64; 2], end: [f64; 2]) -> Segment {
        let a = Point2::new(start[0], start[1]);
        Segment {
            a,
            e: Point2::new(end[0], end[1]) - a,
        }
    }

    /// Distance `t >= 0` along the ray `o + t d` (`|d| = 1`) to this segment.
    ///
    /// A ray running along the segment's own line meets its nearer end (the end face of a
    /// thin wall), or the origin itself when that lies on the segment.
    pub fn hit(&self, o: Point2, d: Point2) -> Option<f64> {
        let w = self.a - o;
        let denom = cross(d, self.e);
        if denom * denom <= 1e-24 * self.e.norm_squared() {
            if cross(w, d).abs() > 1e-9 {
                return None;
            }
            let (ta, tb) = (w.dot(&d), (w + self.e).dot(&d));
            return (ta.max(tb) >= 0.0).then(|| ta.min(tb).max(0.0));
        }
        // t = cross(w, e) / denom and u = cross(w, d) / denom; the range checks are made
        // on the numerators so that a miss (most tests) costs no division.
        let (t, u) = (cross(w, self.e), cross(w, d));
        let (t, u, den) = if denom > 0.0 {
            (t, u, denom)
        } else {
            (-t, -u, -denom)
        };
        (t >= 0.0 && u >= -VERTEX_SLACK * den && u <= (1.0 + VERTEX_SLACK) * den).then(|| t / den)
    }

    /// Shortest distance from `p` to this segment.
    pub fn distance_to_point(&self, p: Point2) -> f64 {
        let len2 = self.e.norm_squared();
        let u = ((p - self.a).dot(&self.e) / len2).clamp(0.0, 1.0);
        (self.a + u * self.e - p).norm()
    }

    /// Shortest distance between two segments (0 when they cross or touch).
    pub fn distance_to_segment(&self, other: &Segment) -> f64 {
        let d = other.a - self.a;
        let denom = cross(self.e, other.e);
        if denom != 0.0 {
            let u = cross(d, other.e) / denom;
            let v = cross(d, self.e) / denom;
            if (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v) {
                return 0.0;
            }
        }
        [
            self.distance_to_point(other.a),
            self.distance_to_point(other.a + other.e),
            other.distance_to_point(self.a),
            other.distance_to_point(self.a + self.e),
        ]
        .into_iter()
        .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_crossing_segment_and_misses_parallel_one() {
        let s = Segment::new([2.0, -1.0], [2.0, 1.0]);
        let o = Point2::zeros();
        assert_eq!(s.hit(o, Point2::new(1.0, 0.0)), Some(2.0));
        assert_eq!(s.hit(o, Point2::new(-1.0, 0.0)), None);
        assert_eq!(s.hit(o, Point2::new(0.0, 1.0)), None);
        // Along its own line: the near end.
        let along = Segment::new([3.0, 0.0], [5.0, 0.0]);
        assert_eq!(along.hit(o, Point2::new(1.0, 0.0)), Some(3.0));
    }

    #[test]
    fn segment_distances() {
        let s = Segment::new([0.0, 0.0], [2.0, 0.0]);
        assert_eq!(
            s.distance_to_segment(&Segment::new([1.0, -1.0], [1.0, 1.0])),
            0.0
        );
        assert_eq!(
            s.distance_to_segment(&Segment::new([3.0, 1.0], [3.0, 2.0])),
            2f64.sqrt()
        );
        assert_eq!(
            s.distance_to_segment(&Segment::new([0.5, 0.5], [1.5, 0.5])),
            0.5
        );
    }
}
