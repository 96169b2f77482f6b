//! Wheels that freeze and catch up: some odometry stops updating for a few scans while the
//! robot moves, then reports the whole motion in one step. The scans contradict the frozen
//! steps (rightly rejected), and the catch-up, taken from the last frozen reading, is a jump
//! the scan contradicts too, or worse, drags the fit with it. Measured instead from the
//! last reading a step was believed from, and from the front end's pose then, it is the
//! motion the scans saw.

use slam_geom::Pose2;

use crate::config::FrontEndConfig;
use crate::input::OdometryInput;
use crate::odometry_scale::OdometryScale;
use crate::prior::{OdometryRejection, Step, odometry_step};
use crate::scan_clock::MIN_DT;

/// A step is measured from the last odometry reading believed for at most this long,
/// nanoseconds: longer, and the odometry's frame was reset rather than frozen.
pub(crate) const MAX_CATCH_UP_NS: u64 = 2_000_000_000;

/// How the wheels' readings since the anchor stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Lag {
    /// Believed: the anchor is the last reading.
    OnTime,
    /// Standing still while the scans moved: measured from the anchor once they move again.
    Frozen,
    /// Stale (see [`crate::wheel_pace`]): measured from the anchor until believed again.
    Stale,
}

/// A contradicted wheel step shorter than this (metres, radians) is wheels that froze.
const FROZEN_M: f64 = 1e-3;
const FROZEN_RAD: f64 = 1e-3;

/// Whether a wheel step is the wheels standing still.
pub(crate) fn is_frozen(step: &Pose2) -> bool {
    step.translation_norm() < FROZEN_M && step.yaw.abs() < FROZEN_RAD
}

/// The last odometry reading a step was believed from, with the front end's pose and the
/// stamp of its scan.
#[derive(Debug, Clone, Copy)]
pub(crate) struct OdometryAnchor {
    pub reading: OdometryInput,
    pub pose: Pose2,
    pub stamp_ns: u64,
}

impl OdometryAnchor {
    /// The wheels' step from the anchor to `current` (at `stamp_ns`), scaled, as a step
    /// from `previous_pose`: where the anchor's pose and the wheels' motion since put the
    /// robot, its uncertainty the wheels' over the whole span.
    pub fn step_to(
        &self,
        current: &OdometryInput,
        stamp_ns: u64,
        previous_pose: &Pose2,
        scale: &OdometryScale,
        config: &FrontEndConfig,
    ) -> Result<Step, OdometryRejection> {
        let span_s = (stamp_ns.saturating_sub(self.stamp_ns) as f64 * 1e-9).max(MIN_DT);
        let span = scale.apply(odometry_step(&self.reading, current, span_s, config)?);
        let increment = previous_pose.between(&self.pose.compose(&span.increment));
        // The span's covariance is in the anchor's frame; the step's in the previous one.
        let turn = Pose2::new(0.0, 0.0, self.pose.yaw - previous_pose.yaw);
        let rotation = turn.frame_jacobian();
        let covariance = rotation * span.covariance * rotation.transpose();
        Ok(Step {
            increment,
            covariance: 0.5 * (covariance + covariance.transpose()),
        })
    }
}
