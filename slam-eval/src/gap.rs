//! How far one trajectory is from another in the same frame, pose by pose: a localization
//! on a saved map against the mapping run's path, or against the truth moved into the map's
//! frame. No alignment: the map fixes the frame, and an offset is an error.

use nalgebra::Vector3;

use crate::pose::Pose;
use crate::stats::ErrorStats;
use crate::trajectory::Trajectory;

/// Position gaps of the poses matched by stamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gaps {
    /// Estimate poses at or after the start that have a reference pose within the tolerance.
    pub matched: usize,
    /// Estimate poses at or after the start without one.
    pub unmatched: usize,
    /// Root mean square of the gaps, metres.
    pub rmse_m: f64,
    /// Mean, spread and largest gap, metres.
    pub stats: ErrorStats,
    /// Mean of the gaps' components along the reference's heading, metres: positive when
    /// the estimate runs ahead of the reference (a likelihood field that rewards beams
    /// sinking into the walls ahead draws a localizer forward), 0 without gaps.
    pub along_track_m: f64,
}

/// The position gap of every `estimate` pose stamped at or after `from_ns` to the
/// `reference` pose nearest its stamp (within `tolerance_ns`), the reference first moved by
/// `frame_from_reference` into the estimate's frame.
pub fn position_gaps(
    estimate: &Trajectory,
    reference: &Trajectory,
    frame_from_reference: &Pose,
    from_ns: u64,
    tolerance_ns: u64,
) -> Gaps {
    let mut gaps = Vec::new();
    let mut along_track = 0.0;
    let mut unmatched = 0;
    for (stamp_ns, pose) in estimate.iter().filter(|(stamp, _)| *stamp >= from_ns) {
        match reference.pose_at(stamp_ns, tolerance_ns) {
            Some(truth) => {
                let moved = frame_from_reference * truth;
                let gap = pose.translation.vector - moved.translation.vector;
                gaps.push(gap.norm());
                along_track += gap.dot(&(moved.rotation * Vector3::x()));
            }
            None => unmatched += 1,
        }
    }
    let stats = ErrorStats::of(&gaps);
    Gaps {
        matched: gaps.len(),
        unmatched,
        rmse_m: stats.squared_mean.sqrt(),
        stats,
        along_track_m: if gaps.is_empty() {
            0.0
        } else {
            along_track / gaps.len() as f64
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::from_tum;

    fn at(x: f64, y: f64) -> Pose {
        from_tum([x, y, 0.0], [0.0, 0.0, 0.0, 1.0]).unwrap()
    }

    #[test]
    fn gaps_are_taken_from_the_start_in_the_given_frame() {
        let estimate = Trajectory::new(vec![
            (0, at(5.0, 5.0)),
            (10, at(1.0, 0.0)),
            (20, at(2.0, 0.3)),
        ])
        .unwrap();
        let reference = Trajectory::new(vec![
            (0, at(0.0, 0.0)),
            (10, at(0.0, 0.0)),
            (20, at(1.0, 0.0)),
        ])
        .unwrap();
        let shift = at(1.0, 0.0);
        let gaps = position_gaps(&estimate, &reference, &shift, 10, 0);
        assert_eq!((gaps.matched, gaps.unmatched), (2, 0));
        assert!((gaps.stats.max - 0.3).abs() < 1e-12);
        assert!((gaps.rmse_m - (0.09f64 / 2.0).sqrt()).abs() < 1e-12);
        // The gaps are across the reference's heading (x): none along it.
        assert!(gaps.along_track_m.abs() < 1e-12);
        let none = position_gaps(&estimate, &reference, &shift, 30, 0);
        assert_eq!((none.matched, none.unmatched), (0, 0));
        assert_eq!(none.along_track_m, 0.0);
    }

    #[test]
    fn an_estimate_ahead_of_the_reference_has_a_positive_along_track_gap() {
        // The reference heads along +y; the estimate is 5 cm further along it and 2 cm
        // to its side.
        let heading_y = |x: f64, y: f64| {
            let half = std::f64::consts::FRAC_PI_4;
            from_tum([x, y, 0.0], [0.0, 0.0, half.sin(), half.cos()]).unwrap()
        };
        let reference =
            Trajectory::new(vec![(0, heading_y(0.0, 0.0)), (10, heading_y(0.0, 1.0))]).unwrap();
        let estimate = Trajectory::new(vec![
            (0, heading_y(0.02, 0.05)),
            (10, heading_y(0.02, 1.05)),
        ])
        .unwrap();
        let gaps = position_gaps(&estimate, &reference, &Pose::identity(), 0, 0);
        assert!((gaps.along_track_m - 0.05).abs() < 1e-12, "{gaps:?}");
        let behind = position_gaps(&reference, &estimate, &Pose::identity(), 0, 0);
        assert!((behind.along_track_m + 0.05).abs() < 1e-12, "{behind:?}");
    }
}
