//! The route for the vehicle's follower: the waypoint polyline by arc length, driven one lap
//! or several in a row.
//!
//! A closed route (its last waypoint on its first) carries on round from lap to lap without
//! stopping. An open route is driven back the way it came on every other lap: the vehicle
//! stops at its end and turns on the spot, since a straight line back to the start could
//! cross walls. The laps are not stored: arc lengths run over all of them and are mapped onto
//! the one polyline. A stretch driven from rest to rest is a leg: all the laps of a closed
//! route make one leg, each lap of an open route is a leg of its own.

use std::ops::RangeInclusive;

use crate::{Laps, Point2};

/// A route whose last waypoint lies this close to its first is closed, metres: as close as
/// the vehicle comes to a goal.
const CLOSED_WITHIN: f64 = 1e-3;

#[derive(Debug, Clone)]
pub(crate) struct Path {
    points: Vec<Point2>,
    /// Arc length at each waypoint, within a lap.
    s: Vec<f64>,
    laps: u32,
    closed: bool,
}

/// A segment as driven: from `a` to `b`, over arc lengths `sa..sb` of the whole drive.
struct Stretch {
    a: Point2,
    b: Point2,
    sa: f64,
    sb: f64,
}

impl Path {
    /// Needs at least two distinct consecutive points ([`crate::World::validate`]).
    pub(crate) fn new(waypoints: &[[f64; 2]], laps: Laps) -> Path {
        let points: Vec<Point2> = waypoints.iter().map(|p| Point2::new(p[0], p[1])).collect();
        let mut s = vec![0.0];
        for w in points.windows(2) {
            s.push(s[s.len() - 1] + (w[1] - w[0]).norm());
        }
        let closed = (points[points.len() - 1] - points[0]).norm() <= CLOSED_WITHIN;
        Path {
            points,
            s,
            laps: laps.get(),
            closed,
        }
    }

    pub(crate) fn start_heading(&self) -> f64 {
        let d = self.points[1] - self.points[0];
        d.y.atan2(d.x)
    }

    pub(crate) fn start(&self) -> Point2 {
        self.points[0]
    }

    /// Legs of the drive: see the module's documentation.
    pub(crate) fn legs(&self) -> u32 {
        if self.closed { 1 } else { self.laps }
    }

    /// Arc length at which leg `leg` ends, at rest.
    pub(crate) fn leg_end(&self, leg: u32) -> f64 {
        self.lap_start(self.leg_laps(leg).end() + 1)
    }

    /// The point of leg `leg` at arc length `s`; beyond the leg's end, on the extension of
    /// its last segment, so that a carrot past a goal still points the way the leg ends.
    pub(crate) fn point_at(&self, leg: u32, s: f64) -> Point2 {
        let s = s.max(self.lap_start(*self.leg_laps(leg).start()));
        let lap = self.lap_at(leg, s);
        let local = s - self.lap_start(lap);
        if self.backwards(lap) {
            self.on_polyline(self.lap_length() - local)
        } else {
            self.on_polyline(local)
        }
    }

    /// Arc length of the point of leg `leg` nearest to `p` within `[from, from + window]`.
    /// The window keeps the progress monotonic and local, so a loop that passes its start
    /// again is not taken for finished; the leg, so an open route's way back is not taken
    /// for the way there.
    pub(crate) fn project(&self, leg: u32, p: Point2, from: f64, window: f64) -> f64 {
        let to = (from + window).min(self.leg_end(leg));
        let mut best = (f64::INFINITY, from);
        for lap in self.lap_at(leg, from)..=self.lap_at(leg, to) {
            for Stretch { a, b, sa, sb } in self.stretches(lap) {
                let (s0, s1) = (sa.max(from), sb.min(to));
                if s0 > s1 {
                    continue;
                }
                let len = sb - sa;
                let u = ((p - a).dot(&(b - a)) / (len * len)).clamp(0.0, 1.0);
                let s = (sa + u * len).clamp(s0, s1);
                let d = (self.point_at(leg, s) - p).norm();
                if d < best.0 {
                    best = (d, s);
                }
            }
        }
        best.1
    }

    /// `(arc length, turn angle)` of the waypoints where leg `leg` turns without stopping,
    /// from the lap that holds arc length `from` to the next one: the same turn a lap later
    /// limits the speed less, being further off.
    pub(crate) fn turns(&self, leg: u32, from: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let first = self.lap_at(leg, from);
        let last = (first + 1).min(*self.leg_laps(leg).end());
        (first..=last).flat_map(move |lap| self.lap_turns(lap))
    }

    fn lap_length(&self) -> f64 {
        self.s[self.s.len() - 1]
    }

    /// Arc length at which lap `lap` (from 0) starts.
    fn lap_start(&self, lap: u32) -> f64 {
        self.lap_length() * f64::from(lap)
    }

    fn leg_laps(&self, leg: u32) -> RangeInclusive<u32> {
        if self.closed {
            0..=self.laps - 1
        } else {
            leg..=leg
        }
    }

    /// The lap of leg `leg` that holds arc length `s`: its first or last one beyond its ends.
    fn lap_at(&self, leg: u32, s: f64) -> u32 {
        let laps = self.leg_laps(leg);
        let lap = (s / self.lap_length()).floor();
        // `as` saturates: far below the first lap is 0, far past the last is u32::MAX.
        (lap.max(0.0) as u32).clamp(*laps.start(), *laps.end())
    }

    /// Whether lap `lap` drives the polyline from its last waypoint to its first.
    fn backwards(&self, lap: u32) -> bool {
        !self.closed && lap % 2 == 1
    }

    /// The polyline's point at arc length `s`, on the extension of its first or last segment
    /// beyond its ends.
    fn on_polyline(&self, s: f64) -> Point2 {
        let k = self
            .s
            .partition_point(|&v| v <= s)
            .clamp(1, self.points.len() - 1);
        let (a, b) = (self.points[k - 1], self.points[k]);
        let u = (s - self.s[k - 1]) / (self.s[k] - self.s[k - 1]);
        a + (b - a) * u
    }

    /// Lap `lap`'s segments in the order driven.
    fn stretches(&self, lap: u32) -> impl Iterator<Item = Stretch> + '_ {
        let (start, n, length) = (self.lap_start(lap), self.points.len(), self.lap_length());
        let backwards = self.backwards(lap);
        (1..n).map(move |k| {
            if backwards {
                let (i, j) = (n - k, n - k - 1);
                Stretch {
                    a: self.points[i],
                    b: self.points[j],
                    sa: start + (length - self.s[i]),
                    sb: start + (length - self.s[j]),
                }
            } else {
                Stretch {
                    a: self.points[k - 1],
                    b: self.points[k],
                    sa: start + self.s[k - 1],
                    sb: start + self.s[k],
                }
            }
        })
    }

    /// Lap `lap`'s turns in the order driven: at its inner waypoints, and at its end when
    /// the next lap carries on round from there.
    fn lap_turns(&self, lap: u32) -> impl Iterator<Item = (f64, f64)> + '_ {
        let (start, n, length) = (self.lap_start(lap), self.points.len(), self.lap_length());
        let backwards = self.backwards(lap);
        let p = &self.points;
        let inner = (1..n - 1).map(move |i| {
            if backwards {
                let k = n - 1 - i;
                let turn = turn_angle(p[k] - p[k + 1], p[k - 1] - p[k]);
                (start + (length - self.s[k]), turn)
            } else {
                (
                    start + self.s[i],
                    turn_angle(p[i] - p[i - 1], p[i + 1] - p[i]),
                )
            }
        });
        let carries_on = self.closed && lap + 1 < self.laps;
        let end = carries_on.then(|| {
            let turn = turn_angle(p[n - 1] - p[n - 2], p[1] - p[0]);
            (start + length, turn)
        });
        inner.chain(end)
    }
}

/// The angle between two consecutive directions, from 0 (straight on) to pi.
fn turn_angle(d0: Point2, d1: Point2) -> f64 {
    crate::geometry::cross(d0, d1).atan2(d0.dot(&d1)).abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn laps(n: i64) -> Laps {
        Laps::new(n).unwrap()
    }

    fn near(p: Point2, x: f64, y: f64) -> bool {
        (p - Point2::new(x, y)).norm() < 1e-9
    }

    /// A 4 m square driven anticlockwise from the origin, back to it: 16 m a lap.
    const SQUARE: [[f64; 2]; 5] = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [0.0, 0.0]];
    /// An L: 4 m east, then 3 m north; 7 m a lap.
    const ELL: [[f64; 2]; 3] = [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]];

    #[test]
    fn a_closed_route_carries_on_round_as_one_leg() {
        let path = Path::new(&SQUARE, laps(3));
        assert_eq!((path.legs(), path.leg_end(0)), (1, 48.0));
        // Lap 2 starts where lap 1 ended and goes the same way round.
        assert!(near(path.point_at(0, 16.0), 0.0, 0.0));
        assert!(near(path.point_at(0, 17.0), 1.0, 0.0));
        assert!(near(path.point_at(0, 16.0 + 9.0), 3.0, 4.0));
        // Past the last lap's end, along its last segment (south).
        assert!(near(path.point_at(0, 49.0), 0.0, -1.0));
        // Progress passes from one lap into the next.
        assert_eq!(path.project(0, Point2::new(0.5, 0.1), 15.0, 3.0), 16.5);
        // The corner where a lap meets the next is a turn; the laps after the next are
        // not listed.
        let turns: Vec<(f64, f64)> = path.turns(0, 13.0).collect();
        let at: Vec<f64> = turns.iter().map(|&(s, _)| s).collect();
        assert_eq!(at, [4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 28.0, 32.0]);
        assert!(turns.iter().all(|&(_, a)| (a - FRAC_PI_2).abs() < 1e-12));
        // From the last lap on, no turn at its end: the vehicle stops there.
        let last: Vec<f64> = path.turns(0, 40.0).map(|(s, _)| s).collect();
        assert_eq!(last, [36.0, 40.0, 44.0]);
    }

    #[test]
    fn an_open_route_is_driven_back_on_every_other_lap_each_a_leg() {
        let path = Path::new(&ELL, laps(3));
        assert_eq!(path.legs(), 3);
        assert_eq!([0, 1, 2].map(|leg| path.leg_end(leg)), [7.0, 14.0, 21.0]);
        // There, back, and there again.
        assert!(near(path.point_at(0, 5.0), 4.0, 1.0));
        assert!(near(path.point_at(1, 8.0), 4.0, 2.0));
        assert!(near(path.point_at(1, 12.0), 2.0, 0.0));
        assert!(near(path.point_at(2, 16.0), 2.0, 0.0));
        // Past a leg's end the carrot runs on the way the leg ends, not onto the next leg.
        assert!(near(path.point_at(0, 7.5), 4.0, 3.5));
        assert!(near(path.point_at(1, 14.5), -0.5, 0.0));
        // The way back is not taken for the way there, nor the other way round.
        let p = Point2::new(4.0, 2.0);
        assert_eq!(path.project(0, p, 5.0, 5.0), 6.0);
        assert_eq!(path.project(1, p, 7.0, 5.0), 8.0);
        // The corner is a turn on either way; the ends, where the vehicle stops, are not.
        let back: Vec<(f64, f64)> = path.turns(1, 6.5).collect();
        assert_eq!(back.len(), 1);
        assert_eq!(back[0].0, 10.0);
        assert!((back[0].1 - FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn one_lap_is_the_polyline_alone() {
        for waypoints in [&SQUARE[..], &ELL[..]] {
            let path = Path::new(waypoints, Laps::ONE);
            let length = path.s[path.s.len() - 1];
            assert_eq!((path.legs(), path.leg_end(0)), (1, length));
            let turns: Vec<f64> = path.turns(0, -1.0).map(|(s, _)| s).collect();
            assert_eq!(turns, path.s[1..path.s.len() - 1]);
        }
    }

    use std::f64::consts::FRAC_PI_2;
}
