//! Logs written by the tests: a robot in a room with a pillar, its scans ray-cast, as
//! `FLASER` and `ODOM` lines.

use std::f64::consts::PI;

/// Ranges of a 181-beam scan over 180 degrees from `(x, y, yaw)` inside a 10 x 6 m room
/// with a 2 x 1 m pillar, so the walls' directions turn with the robot.
pub(crate) fn ranges(x: f64, y: f64, yaw: f64) -> Vec<String> {
    let boxes = [(-5.0, -3.0, 5.0, 3.0, true), (1.0, 0.5, 3.0, 1.5, false)];
    (0..181)
        .map(|i| {
            let bearing = yaw - PI / 2.0 + f64::from(i).to_radians();
            let (dx, dy) = (bearing.cos(), bearing.sin());
            let mut nearest = 50.0_f64;
            for &(x0, y0, x1, y1, inside) in &boxes {
                for (t0, t1) in [
                    ((x0 - x) / dx, (x1 - x) / dx),
                    ((y0 - y) / dy, (y1 - y) / dy),
                ] {
                    for t in [t0, t1] {
                        let (px, py) = (x + t * dx, y + t * dy);
                        let on = px >= x0 - 1e-9
                            && px <= x1 + 1e-9
                            && py >= y0 - 1e-9
                            && py <= y1 + 1e-9;
                        if t > 1e-6 && t.is_finite() && on && (inside || t < nearest) {
                            nearest = nearest.min(t);
                        }
                    }
                }
            }
            format!("{nearest:.3}")
        })
        .collect()
}

/// The robot's pose at `t` seconds: a slow circle, turning faster and slower.
pub(crate) fn pose(t: f64) -> (f64, f64, f64) {
    let yaw = 0.5 * t + 0.6 * (0.7 * t).sin();
    (
        1.5 * (0.2 * t).cos() - 1.0,
        1.0 * (0.2 * t).sin() - 0.5,
        yaw,
    )
}

pub(crate) fn flaser(stamp: f64, odometry: (f64, f64, f64), truth: (f64, f64, f64)) -> String {
    let (x, y, yaw) = odometry;
    let r = ranges(truth.0, truth.1, truth.2).join(" ");
    format!("FLASER 181 {r} {x} {y} {yaw} {x} {y} {yaw} {stamp:.6} host {stamp:.6}\n")
}

pub(crate) fn odom(stamp: f64, (x, y, yaw): (f64, f64, f64)) -> String {
    format!("ODOM {x} {y} {yaw} 0 0 0 {stamp:.6} host {stamp:.6}\n")
}
