//! The waypoint polyline by arc length, for the vehicle's follower.

use crate::Point2;

#[derive(Debug, Clone)]
pub(crate) struct Path {
    points: Vec<Point2>,
    /// Arc length at each waypoint.
    s: Vec<f64>,
}

impl Path {
    /// Needs at least two distinct consecutive points ([`crate::World::validate`]).
    pub(crate) fn new(waypoints: &[[f64; 2]]) -> Path {
        let points: Vec<Point2> = waypoints.iter().map(|p| Point2::new(p[0], p[1])).collect();
        let mut s = vec![0.0];
        for w in points.windows(2) {
            s.push(s[s.len() - 1] + (w[1] - w[0]).norm());
        }
        Path { points, s }
    }

    pub(crate) fn length(&self) -> f64 {
        self.s[self.s.len() - 1]
    }

    pub(crate) fn start_heading(&self) -> f64 {
        let d = self.points[1] - self.points[0];
        d.y.atan2(d.x)
    }

    pub(crate) fn start(&self) -> Point2 {
        self.points[0]
    }

    /// The point at arc length `s`; beyond the end, on the extension of the last segment,
    /// so that a carrot past the goal still points the way the path ends.
    pub(crate) fn point_at(&self, s: f64) -> Point2 {
        let s = s.max(0.0);
        let k = self
            .s
            .partition_point(|&v| v <= s)
            .clamp(1, self.points.len() - 1);
        let (a, b) = (self.points[k - 1], self.points[k]);
        let u = (s - self.s[k - 1]) / (self.s[k] - self.s[k - 1]);
        a + (b - a) * u
    }

    /// Arc length of the point nearest to `p` within `[from, from + window]`. The window
    /// keeps the progress monotonic and local, so a loop that passes its start again is not
    /// taken for finished.
    pub(crate) fn project(&self, p: Point2, from: f64, window: f64) -> f64 {
        let to = (from + window).min(self.length());
        let mut best = (f64::INFINITY, from);
        for k in 1..self.points.len() {
            let (s0, s1) = (self.s[k - 1].max(from), self.s[k].min(to));
            if s0 > s1 {
                continue;
            }
            let (a, b) = (self.points[k - 1], self.points[k]);
            let len = self.s[k] - self.s[k - 1];
            let u = ((p - a).dot(&(b - a)) / (len * len)).clamp(0.0, 1.0);
            let s = (self.s[k - 1] + u * len).clamp(s0, s1);
            let d = (self.point_at(s) - p).norm();
            if d < best.0 {
                best = (d, s);
            }
        }
        best.1
    }

    /// `(arc length, turn angle)` of every inner waypoint.
    pub(crate) fn turns(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (1..self.points.len() - 1).map(|k| {
            let (d0, d1) = (
                self.points[k] - self.points[k - 1],
                self.points[k + 1] - self.points[k],
            );
            let turn = crate::geometry::cross(d0, d1).atan2(d0.dot(&d1)).abs();
            (self.s[k], turn)
        })
    }
}
