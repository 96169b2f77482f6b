//! The prior step and the scan match combined by their information, and the test of one
//! against the other. In the map frame: the prior step's covariance is turned into it
//! with the previous pose's rotation (the previous pose itself is taken as given, as the
//! increment is all that is reported).

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Pose2, wrap_angle};

use crate::prior::Step;
use crate::registration::Registration;

/// The prior step seen from the map frame: the predicted pose and its covariance.
#[derive(Debug, Clone, Copy)]
pub struct Prediction {
    pub pose: Pose2,
    pub covariance: Matrix3<f64>,
}

/// `previous * step`, with the step's covariance rotated into the map frame.
pub fn predict(previous: &Pose2, step: &Step) -> Prediction {
    let rotation = previous.frame_jacobian();
    Prediction {
        pose: previous.compose(&step.increment),
        covariance: rotation * step.covariance * rotation.transpose(),
    }
}

/// `match - prediction` over `(x, y, yaw)`, yaw wrapped.
fn difference(prediction: &Prediction, registration: &Registration) -> Vector3<f64> {
    Vector3::new(
        registration.pose.x - prediction.pose.x,
        registration.pose.y - prediction.pose.y,
        wrap_angle(registration.pose.yaw - prediction.pose.yaw),
    )
}

/// Squared Mahalanobis distance between the prediction and the match, along the
/// directions the scan constrains.
pub fn disagreement(prediction: &Prediction, registration: &Registration) -> f64 {
    registration.constraint.mahalanobis_squared(
        &difference(prediction, registration),
        &prediction.covariance,
        registration.variance,
    )
}

/// The information-weighted combination: along the directions the scan constrains the
/// more certain of the two wins, along the degenerate ones the prediction counts with
/// `weak_share` of the scan's little information (see [`crate::constraint::Constraint::information`]).
/// Returns the pose and its covariance in the map frame.
pub fn fuse(
    prediction: &Prediction,
    registration: &Registration,
    weak_share: f64,
) -> (Pose2, Matrix3<f64>) {
    let scan_information = registration
        .constraint
        .information(registration.variance, weak_share);
    let Some(prior_information) = prediction.covariance.try_inverse() else {
        return (prediction.pose, prediction.covariance);
    };
    let Some(covariance) = (prior_information + scan_information).try_inverse() else {
        return (prediction.pose, prediction.covariance);
    };
    let correction = covariance * scan_information * difference(prediction, registration);
    let pose = Pose2::new(
        prediction.pose.x + correction.x,
        prediction.pose.y + correction.y,
        wrap_angle(prediction.pose.yaw + correction.z),
    );
    (pose, 0.5 * (covariance + covariance.transpose()))
}
