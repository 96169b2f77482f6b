//! Which true corners a sensor could observe from a position, for statistics and scoring.

use crate::geometry::cross;
use crate::{Point2, RayCaster, TrueCorner};

/// A wall seen at a shallower angle than this (about 5 degrees) is not counted as seen.
const MIN_INCIDENCE_SIN: f64 = 0.087;

/// Indices of the `corners` observable from `position`: the tip within `max_range`, in line
/// of sight, and both arms facing the sensor — seen from inside the opening angle (a room
/// corner) or from the opposite side (a pillar corner), not from where one arm hides the
/// other. The field of view is not considered.
pub fn visible_corners(
    caster: &RayCaster,
    corners: &[TrueCorner],
    position: [f64; 2],
    max_range: f64,
) -> Vec<usize> {
    let p = Point2::new(position[0], position[1]);
    let mut seen = Vec::new();
    for (k, c) in corners.iter().enumerate() {
        let v = p - Point2::new(c.x, c.y);
        let dist = v.norm();
        if dist > max_range || dist < 1e-9 {
            continue;
        }
        let [d1, d2] = c.arms();
        let (s1, s2) = (cross(d1, v) / dist, cross(d2, v) / dist);
        let between = cross(d1, d2);
        // Same signs: inside the opening; both opposite: the outside of both arms.
        let (f1, f2) = (s1 * between.signum(), -s2 * between.signum());
        let facing = (f1 > 0.0) == (f2 > 0.0);
        if !facing || f1.abs() < MIN_INCIDENCE_SIN || f2.abs() < MIN_INCIDENCE_SIN {
            continue;
        }
        let back = -v;
        let hit = caster.cast(position, back.y.atan2(back.x), dist + 1.0);
        if hit.is_none_or(|t| t >= dist * (1.0 - 1e-6) - 1e-9) {
            seen.push(k);
        }
    }
    seen
}
