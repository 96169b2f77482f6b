//! The true corners of a world, defined as in docs/CONVENTIONS.md.

use crate::{Point2, TrueCorner, World};

/// Opening angles outside this range are not corners: nearly collinear segments are one
/// wall, and spikes sharper than this do not give two fittable lines.
const MIN_ANGLE_DEG: f64 = 20.0;
const MAX_ANGLE_DEG: f64 = 160.0;

impl World {
    /// Every wall vertex where two segments of one polyline meet at an opening angle
    /// between 20 and 160 degrees (the first vertex of a closed polygon included). A vertex
    /// is listed once though a thin wall is seen from both sides: the definition does not
    /// depend on the side. Walls of different polylines that merely touch are not joined.
    pub fn true_corners(&self) -> Vec<TrueCorner> {
        let (lo, hi) = (MIN_ANGLE_DEG.to_radians(), MAX_ANGLE_DEG.to_radians());
        let mut corners = Vec::new();
        for wall in &self.walls {
            let p: Vec<Point2> = wall.iter().map(|q| Point2::new(q[0], q[1])).collect();
            let n = p.len();
            let closed = n >= 4 && p[0] == p[n - 1];
            // Inner vertices, plus vertex 0 of a closed polygon, whose neighbours are n-2
            // and 1 (n-1 repeats it).
            let tips = (1..n.saturating_sub(1)).map(|i| (i - 1, i, i + 1));
            let first = closed.then_some((n - 2, 0, 1));
            for (a, i, b) in tips.chain(first) {
                let d1 = (p[a] - p[i]).normalize();
                let d2 = (p[b] - p[i]).normalize();
                let corner = TrueCorner::from_arms(p[i], d1, d2);
                if (lo..=hi).contains(&corner.angle) {
                    corners.push(corner);
                }
            }
        }
        corners
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn square_room() -> World {
        World {
            walls: vec![vec![
                [0.0, 0.0],
                [4.0, 0.0],
                [4.0, 4.0],
                [0.0, 4.0],
                [0.0, 0.0],
            ]],
            waypoints: vec![[1.0, 1.0], [3.0, 3.0]],
            speed: 1.0,
        }
    }

    #[test]
    fn square_room_has_four_right_corners_pointing_away_from_the_centre() {
        let corners = square_room().true_corners();
        assert_eq!(corners.len(), 4);
        for c in &corners {
            assert!((c.angle - FRAC_PI_2).abs() < 1e-12);
            // From the centre (2, 2) towards the tip.
            let expected = (c.y - 2.0).atan2(c.x - 2.0);
            assert!(
                crate::wrap_angle(c.heading - expected).abs() < 1e-12,
                "{c:?}"
            );
        }
    }

    #[test]
    fn pillar_corner_heading_points_out_of_the_pillar() {
        let mut world = square_room();
        world.walls = vec![vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.0, 0.0],
        ]];
        let corners = world.true_corners();
        let c = corners.iter().find(|c| c.x == 1.0 && c.y == 1.0);
        // Same rule, so the tip (1, 1) of a pillar centred at (0.5, 0.5) points away from it.
        assert!(c.is_some_and(|c| (c.heading - PI / 4.0).abs() < 1e-12));
    }

    #[test]
    fn straight_and_open_ends_are_not_corners_and_arms_round_trip() {
        let mut world = square_room();
        world.walls = vec![vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.01], [2.0, 1.0]]];
        let corners = world.true_corners();
        assert_eq!(corners.len(), 1);
        let [a1, a2] = corners[0].arms();
        let back = TrueCorner::from_arms(Point2::new(2.0, 0.01), a1, a2);
        assert!((back.heading - corners[0].heading).abs() < 1e-12);
        assert!((back.angle - corners[0].angle).abs() < 1e-12);
    }
}
