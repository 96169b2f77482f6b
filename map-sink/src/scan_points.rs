//! The valid points of one laser scan, in the sensor frame.

/// The points of the valid beams (REP 117: finite and within `[range_min, range_max]`) as
/// `r * (cos b, sin b)`, with bearing `b = angle_min + i * angle_increment`.
///
/// At most `max_points` beams are looked at, evenly strided, so a very dense scanner cannot
/// blow up memory or the picture; `0` means no limit.
pub fn scan_points(
    angle_min: f64,
    angle_increment: f64,
    range_min: f64,
    range_max: f64,
    ranges: &[f32],
    max_points: usize,
) -> Vec<[f64; 2]> {
    let stride = if max_points == 0 {
        1
    } else {
        ranges.len().div_ceil(max_points).max(1)
    };
    ranges
        .iter()
        .enumerate()
        .step_by(stride)
        .filter_map(|(i, &r)| {
            let r = f64::from(r);
            if !r.is_finite() || r < range_min || r > range_max {
                return None;
            }
            let (s, c) = (angle_min + i as f64 * angle_increment).sin_cos();
            Some([r * c, r * s])
        })
        .collect()
}
