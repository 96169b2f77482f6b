//! `hall`: a 41 m x 29 m hall with a grid of pillars, pilasters and alcoves in the outer
//! walls, and a three-quarter circuit through it, like the real recording.

use crate::World;
use crate::outline::{Paint, outline};

use super::square;

/// Pillar grid, metres: columns every 7.5 m, rows every 7.5 m.
const COLUMNS: [f64; 5] = [7.0, 14.5, 22.0, 29.5, 37.0];
const ROWS: [f64; 3] = [7.0, 14.5, 22.0];

pub(crate) fn hall() -> World {
    let mut plan = vec![
        Paint::Free([0.0, 0.0, 41.0, 29.0]),
        // Alcoves (1.2 m deep) in each outer wall.
        Paint::Free([8.0, -1.2, 11.0, 0.0]),
        Paint::Free([25.5, -1.2, 28.5, 0.0]),
        Paint::Free([41.0, 10.0, 42.2, 13.0]),
        Paint::Free([16.5, 29.0, 19.5, 30.2]),
        Paint::Free([31.0, 29.0, 34.0, 30.2]),
        Paint::Free([-1.2, 16.0, 0.0, 19.0]),
    ];
    for &x in &COLUMNS {
        for &y in &ROWS {
            plan.push(Paint::Solid(square(x, y, 0.7)));
        }
        // Pilasters where the pillar rows meet the outer walls, 0.4 m proud of them.
        plan.push(Paint::Solid([x - 0.35, -0.5, x + 0.35, 0.4]));
        plan.push(Paint::Solid([x - 0.35, 28.6, x + 0.35, 29.5]));
    }
    for &y in &ROWS {
        plan.push(Paint::Solid([-0.5, y - 0.35, 0.4, y + 0.35]));
        plan.push(Paint::Solid([40.6, y - 0.35, 41.5, y + 0.35]));
    }
    World {
        walls: outline(&plan),
        // Along the aisles midway between pillar rows and columns.
        waypoints: vec![[4.0, 10.75], [33.25, 10.75], [33.25, 18.25], [10.75, 18.25]],
        speed: 1.0,
    }
}
