//! The built-in worlds, painted as rectilinear floor plans (see `crate::outline`).

mod corridor;
mod hall;
mod office;

pub(crate) use corridor::corridor;
pub(crate) use hall::hall;
pub(crate) use office::office;

use crate::outline::{Paint, Rect};

/// A door niche in a wall whose corridor-side face lies at `face` across the wall, centred
/// at `c` along it; the niche goes towards `sign` (+1 or -1) across the wall, and
/// `along_y` says the wall runs along y. A niche (1.6 m wide, 0.5 m deep) with a 0.9 m door
/// at its back gives four corners seen from the corridor whose arms are all long enough
/// (>= 0.35 m) for a line fit, which the jambs of a door in a thin wall are not.
fn door_niche(plan: &mut Vec<Paint>, along_y: bool, c: f64, face: f64, sign: f64) {
    let rect = |a0: f64, a1: f64, d0: f64, d1: f64| -> Rect {
        let (b0, b1) = (face + sign * d0, face + sign * d1);
        let (b0, b1) = (b0.min(b1), b0.max(b1));
        if along_y {
            [b0, a0, b1, a1]
        } else {
            [a0, b0, a1, b1]
        }
    };
    plan.push(Paint::Solid(rect(c - 1.0, c + 1.0, 0.0, 0.7)));
    plan.push(Paint::Free(rect(c - 0.8, c + 0.8, 0.0, 0.5)));
    plan.push(Paint::Free(rect(c - 0.45, c + 0.45, 0.45, 0.8)));
}

/// A square of side `size` centred at `(x, y)`.
fn square(x: f64, y: f64, size: f64) -> Rect {
    let h = 0.5 * size;
    [x - h, y - h, x + h, y + h]
}
