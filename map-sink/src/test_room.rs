//! A small room to test scan alignment in: its walls, the returns a robot sees in it and
//! the scan those returns make.

use slam_geom::Pose2;

use back_end::compact_scan::CompactScan;

/// The returns of a robot at `robot` in a 6 x 4 m room (x from -2 to 4, y from -2 to 2)
/// with a pillar to break its symmetry, one a degree, in the sensor frame.
pub(crate) fn room_returns(robot: Pose2) -> Vec<[f64; 2]> {
    let walls = [
        ([-2.0, -2.0], [4.0, -2.0]),
        ([4.0, -2.0], [4.0, 2.0]),
        ([4.0, 2.0], [-2.0, 2.0]),
        ([-2.0, 2.0], [-2.0, -2.0]),
        ([2.0, 0.5], [2.5, 0.5]),
        ([2.5, 0.5], [2.5, 1.0]),
    ];
    (0..360)
        .filter_map(|i| {
            let bearing = (i as f64).to_radians();
            let (s, c) = (robot.yaw + bearing).sin_cos();
            let range = walls
                .iter()
                .filter_map(|&(a, b)| ray_hit([robot.x, robot.y], [c, s], a, b))
                .fold(f64::INFINITY, f64::min);
            range
                .is_finite()
                .then(|| [range * bearing.cos(), range * bearing.sin()])
        })
        .collect()
}

fn ray_hit(o: [f64; 2], d: [f64; 2], a: [f64; 2], b: [f64; 2]) -> Option<f64> {
    let e = [b[0] - a[0], b[1] - a[1]];
    let den = d[0] * e[1] - d[1] * e[0];
    if den.abs() < 1e-12 {
        return None;
    }
    let w = [a[0] - o[0], a[1] - o[1]];
    let t = (w[0] * e[1] - w[1] * e[0]) / den;
    let u = (w[0] * d[1] - w[1] * d[0]) / den;
    (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
}

pub(crate) fn scan_of(returns: &[[f64; 2]]) -> CompactScan {
    // One beam per degree: the returns come from 0..360 degrees in order.
    let ranges: Vec<f32> = returns.iter().map(|p| p[0].hypot(p[1]) as f32).collect();
    CompactScan::new(0.0, 1_f64.to_radians(), 0.05, 30.0, &ranges, 0.0, 10.0)
}
