//! `corridor`: 70 m of 2.5 m wide corridor with five shallow door recesses, the hard case
//! for a corner-feature SLAM: for long stretches no corner is in view.

use crate::World;
use crate::outline::{Paint, outline};

pub(crate) fn corridor() -> World {
    let mut plan = vec![Paint::Free([0.0, 0.0, 70.0, 2.5])];
    for x in [12.0, 31.0, 47.0] {
        plan.push(Paint::Free([x, 2.5, x + 1.2, 2.9]));
    }
    for x in [22.0, 58.0] {
        plan.push(Paint::Free([x, -0.4, x + 1.2, 0.0]));
    }
    World {
        walls: outline(&plan),
        waypoints: vec![[2.0, 1.25], [68.0, 1.25]],
        speed: 1.0,
    }
}
