//! `office`: a 48 m x 30 m floor with a ring corridor between an outer band of rooms and an
//! inner block, door niches every few metres on both sides, and a 104.8 m loop around the
//! ring that ends where it starts.

use crate::World;
use crate::outline::{Paint, outline};

use super::{door_niche, square};

/// Splits of the south and north bands along x (the corner rooms first and last).
const BAND_X: [[f64; 2]; 8] = [
    [0.2, 5.0],
    [5.2, 11.3],
    [11.5, 17.6],
    [17.8, 23.9],
    [24.1, 30.2],
    [30.4, 36.5],
    [36.7, 42.8],
    [43.0, 47.8],
];
/// Splits of the west and east bands along y.
const BAND_Y: [[f64; 2]; 3] = [[5.2, 11.6], [11.8, 18.2], [18.4, 24.8]];

pub(crate) fn office() -> World {
    let mut plan = vec![
        // The ring corridor, 2.4 m wide.
        Paint::Free([5.2, 5.2, 42.8, 7.6]),
        Paint::Free([5.2, 22.4, 42.8, 24.8]),
        Paint::Free([5.2, 5.2, 7.6, 24.8]),
        Paint::Free([40.4, 5.2, 42.8, 24.8]),
        // The inner block: four rooms and an open area with two pillars.
        Paint::Free([7.8, 7.8, 15.75, 14.9]),
        Paint::Free([7.8, 15.1, 15.75, 22.2]),
        Paint::Free([15.95, 7.8, 32.05, 22.2]),
        Paint::Free([32.25, 7.8, 40.2, 14.9]),
        Paint::Free([32.25, 15.1, 40.2, 22.2]),
        Paint::Solid(square(21.0, 15.0, 0.6)),
        Paint::Solid(square(27.0, 15.0, 0.6)),
        // Wide openings from the corridor into the open area.
        Paint::Free([18.0, 7.55, 20.0, 7.85]),
        Paint::Free([28.0, 7.55, 30.0, 7.85]),
        Paint::Free([19.0, 22.15, 21.0, 22.45]),
        Paint::Free([27.0, 22.15, 29.0, 22.45]),
    ];
    for [x0, x1] in BAND_X {
        plan.push(Paint::Free([x0, 0.2, x1, 5.0]));
        plan.push(Paint::Free([x0, 25.0, x1, 29.8]));
    }
    for [y0, y1] in BAND_Y {
        plan.push(Paint::Free([0.2, y0, 5.0, y1]));
        plan.push(Paint::Free([43.0, y0, 47.8, y1]));
    }
    // Cabinets in two rooms, seen through their doors.
    plan.push(Paint::Solid([12.0, 0.6, 13.2, 1.2]));
    plan.push(Paint::Solid([33.0, 28.8, 34.2, 29.4]));
    // Door niches off the corridor: outer band, then inner block.
    for (s, n) in [9.0, 14.5, 21.5, 27.0, 33.0, 39.5]
        .into_iter()
        .zip([8.5, 14.0, 20.5, 27.5, 33.5, 39.0])
    {
        door_niche(&mut plan, false, s, 5.2, -1.0);
        door_niche(&mut plan, false, n, 24.8, 1.0);
    }
    for (w, e) in [(9.0, 8.5), (15.0, 15.0), (21.0, 21.5)] {
        door_niche(&mut plan, true, w, 5.2, -1.0);
        door_niche(&mut plan, true, e, 42.8, 1.0);
    }
    for (x, y) in [(11.5, 7.6), (24.0, 7.6), (36.5, 7.6)] {
        door_niche(&mut plan, false, x, y, 1.0);
    }
    for (x, y) in [(11.5, 22.4), (24.0, 22.4), (36.5, 22.4)] {
        door_niche(&mut plan, false, x, y, -1.0);
    }
    for (y, x) in [(11.5, 7.6), (18.5, 7.6)] {
        door_niche(&mut plan, true, y, x, 1.0);
    }
    for (y, x) in [(11.0, 40.4), (19.0, 40.4)] {
        door_niche(&mut plan, true, y, x, -1.0);
    }
    // The corner rooms open into their neighbours.
    plan.push(Paint::Free([4.95, 2.0, 5.25, 2.9]));
    plan.push(Paint::Free([42.75, 2.0, 43.05, 2.9]));
    plan.push(Paint::Free([4.95, 27.1, 5.25, 28.0]));
    plan.push(Paint::Free([42.75, 27.1, 43.05, 28.0]));
    World {
        walls: outline(&plan),
        waypoints: vec![
            [10.0, 6.4],
            [41.6, 6.4],
            [41.6, 23.6],
            [6.4, 23.6],
            [6.4, 6.4],
            [10.0, 6.4],
        ],
        speed: 1.2,
    }
}
