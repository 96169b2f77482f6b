//! The map's corners carried along when the final path differs from the filter's (the back
//! end's): the filter placed each corner from the poses that saw it, so where the final
//! path moved those poses the corner moves with them.
//! `landmarks.json` and `map_corners.csv` then lie in the frame of the grid, which is laid
//! along the final path; a run mapping on the saved map starts from corners and walls that
//! agree.
//!
//! A corner is placed when first seen; seen again on a later pass, it is the filter's pose
//! that is fitted to it, not the corner to the pose. So the poses of the first pass near
//! it decide: a later pass may have been moved by a quite different correction.

use nalgebra::Matrix4;
use slam_geom::{MapCorner, Point2, StampedPose, wrap_angle};

/// Poses of the path within this distance of a corner decide how it moves, metres: about
/// the range at which the front end finds corners, so mostly the poses that saw it.
const NEAR_POSES_M: f64 = 3.0;

/// `corners` (in the frame of `filter`, the filter's path) moved as the final path moved
/// the filter's to `last` (the same stamps, in the same order). Each corner moves as the
/// poses of the first pass within [`NEAR_POSES_M`] of it moved, on average (the nearest
/// pose when none is that near): its position and heading by their rigid motions, its
/// covariance turned with them.
/// `None` when the two paths do not hold the same stamps.
pub(crate) fn follow_final_path(
    corners: &[MapCorner],
    filter: &[StampedPose],
    last: &[StampedPose],
) -> Option<Vec<MapCorner>> {
    if filter.len() != last.len()
        || filter
            .iter()
            .zip(last)
            .any(|(a, b)| a.stamp_ns != b.stamp_ns)
    {
        return None;
    }
    Some(
        corners
            .iter()
            .map(|corner| follow(corner, filter, last))
            .collect(),
    )
}

fn follow(corner: &MapCorner, filter: &[StampedPose], last: &[StampedPose]) -> MapCorner {
    let at = Point2::new(corner.x, corner.y);
    let distance2 = |p: &StampedPose| (p.pose.position() - at).norm_squared();
    let is_near = |i: &usize| distance2(&filter[*i]) <= NEAR_POSES_M * NEAR_POSES_M;
    let near: Vec<usize> = (0..filter.len())
        .skip_while(|i| !is_near(i))
        .take_while(is_near)
        .collect();
    let near = if near.is_empty() {
        (0..filter.len())
            .min_by(|&a, &b| distance2(&filter[a]).total_cmp(&distance2(&filter[b])))
            .into_iter()
            .collect()
    } else {
        near
    };
    if near.is_empty() {
        return *corner;
    }
    let (mut moved, mut turn) = (Point2::zeros(), 0.0);
    for &i in &near {
        let (before, after) = (&filter[i].pose, &last[i].pose);
        // Where the corner is in the frame of the pose, put back at the pose's new place.
        moved += after.transform(before.inverse().transform(at));
        turn += wrap_angle(after.yaw - before.yaw);
    }
    let n = near.len() as f64;
    let turn = turn / n;
    let (s, c) = turn.sin_cos();
    // Position turns with the path; the heading's and opening's variances do not change.
    let rotation = Matrix4::new(
        c, -s, 0.0, 0.0, //
        s, c, 0.0, 0.0, //
        0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    );
    let covariance = rotation * corner.covariance * rotation.transpose();
    MapCorner {
        x: moved.x / n,
        y: moved.y / n,
        heading: wrap_angle(corner.heading + turn),
        covariance: 0.5 * (covariance + covariance.transpose()),
        ..*corner
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slam_geom::Pose2;

    fn corner(x: f64, y: f64) -> MapCorner {
        MapCorner {
            x,
            y,
            heading: 0.3,
            angle: 1.5,
            covariance: Matrix4::from_diagonal(&nalgebra::Vector4::new(0.04, 0.01, 0.02, 0.03)),
            observations: 5,
        }
    }

    /// A straight path along x, 0.1 m a pose, from x = 0 to 20.
    fn path() -> Vec<StampedPose> {
        (0..=200)
            .map(|i| StampedPose {
                stamp_ns: i,
                pose: Pose2::new(0.1 * i as f64, 0.0, 0.0),
            })
            .collect()
    }

    /// `path` with each pose moved by `move_pose`, stamps kept.
    fn moved(path: &[StampedPose], move_pose: impl Fn(Pose2) -> Pose2) -> Vec<StampedPose> {
        path.iter()
            .map(|p| StampedPose {
                stamp_ns: p.stamp_ns,
                pose: move_pose(p.pose),
            })
            .collect()
    }

    #[test]
    fn corners_move_as_the_poses_near_them_moved() {
        let filter = path();
        // The first half stays, the second half is moved 0.2 m sideways.
        let last = moved(&filter, |p| {
            if p.x < 10.0 {
                p
            } else {
                Pose2::new(p.x, 0.2, 0.0)
            }
        });
        let corners = [corner(2.0, 1.0), corner(18.0, 1.0)];
        let after = follow_final_path(&corners, &filter, &last).unwrap();
        assert!((after[0].x - 2.0).abs() < 1e-12 && (after[0].y - 1.0).abs() < 1e-12);
        assert_eq!(after[0].covariance, corners[0].covariance);
        assert!((after[1].x - 18.0).abs() < 1e-9, "{:?}", after[1]);
        assert!((after[1].y - 1.2).abs() < 1e-9, "{:?}", after[1]);
        assert!((after[1].heading - 0.3).abs() < 1e-9);
    }

    #[test]
    fn a_corner_passed_twice_moves_as_the_first_pass_moved() {
        // Out along x to 20 m and back: the way back was corrected by 0.5 m sideways.
        let out = path();
        let back: Vec<StampedPose> = out
            .iter()
            .rev()
            .enumerate()
            .map(|(k, p)| StampedPose {
                stamp_ns: 1000 + k as u64,
                pose: Pose2::new(p.pose.x, 0.0, std::f64::consts::PI),
            })
            .collect();
        let filter: Vec<StampedPose> = out.iter().chain(&back).copied().collect();
        let last = moved(&filter, |p| match p.yaw.abs() > 1.0 {
            true => Pose2::new(p.x, 0.5, p.yaw),
            false => Pose2::new(p.x, 0.1, p.yaw),
        });
        let after = follow_final_path(&[corner(5.0, 1.0)], &filter, &last).unwrap()[0];
        assert!((after.y - 1.1).abs() < 1e-9, "{after:?}");
    }

    #[test]
    fn a_turned_path_turns_its_corners_and_their_covariance() {
        let filter = path();
        // The whole path turned 0.1 rad about the origin.
        let turn = Pose2::new(0.0, 0.0, 0.1);
        let last = moved(&filter, |p| turn.compose(&p));
        let c = corner(5.0, 1.0);
        let after = follow_final_path(&[c], &filter, &last).unwrap()[0];
        let expected = turn.transform(Point2::new(5.0, 1.0));
        assert!((after.x - expected.x).abs() < 1e-9 && (after.y - expected.y).abs() < 1e-9);
        assert!((after.heading - 0.4).abs() < 1e-9);
        // The x-y block turned: its trace is kept and it gains a cross term.
        let xy = after.covariance.fixed_view::<2, 2>(0, 0);
        assert!((xy.trace() - 0.05).abs() < 1e-12);
        assert!(xy[(0, 1)].abs() > 1e-4);
        assert_eq!(after.covariance[(2, 2)], 0.02);
        assert_eq!(after.covariance[(3, 3)], 0.03);
        assert_eq!(after.covariance, after.covariance.transpose());
    }

    #[test]
    fn a_corner_far_from_the_path_follows_the_nearest_pose() {
        let filter = path();
        let last = moved(&filter, |p| Pose2::new(1.01 * p.x, 0.0, 0.0));
        let after = follow_final_path(&[corner(30.0, 0.0)], &filter, &last).unwrap()[0];
        // The last pose, at x = 20, moved 0.2 m along x.
        assert!((after.x - 30.2).abs() < 1e-9, "{after:?}");
    }

    #[test]
    fn paths_of_other_stamps_are_refused() {
        let filter = path();
        let last = &filter[1..];
        assert!(follow_final_path(&[corner(1.0, 1.0)], &filter, last).is_none());
    }
}
