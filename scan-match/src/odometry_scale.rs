//! The wheels' distance scale, learnt online: wheel odometry is off by a few per cent in
//! distance (tyre wear and pressure, load, floor), the same way for hours. Where a scan
//! fixes its pose in every direction the fit measures the true advance; the ratio of that
//! to the wheels' advance, over the last tens of metres, corrects the odometry step where
//! the scan cannot: along a corridor, whose length the prior alone decides.

use nalgebra::Matrix3;
use slam_geom::Pose2;

use crate::prior::Step;

/// What the estimator needs to know.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryScaleConfig {
    /// The estimate forgets with this distance travelled, metres: long enough to average
    /// out the fits' noise, short enough to follow a change of floor.
    pub memory_m: f64,
    /// Distance the fits must have measured before the scale is used, metres.
    pub min_evidence_m: f64,
    /// The scale is kept within `1 +- max_correction`: beyond that the wheels or the fits
    /// are broken, not off in scale.
    pub max_correction: f64,
}

/// The scale's estimate forgets with this distance travelled, metres: long enough to
/// average out the fits' noise, short enough to follow a change of floor.
pub const ODOMETRY_SCALE_MEMORY_M: f64 = 50.0;

/// Distance the fits must have measured before the scale is used, metres: a few metres of
/// fits average their noise below a per cent.
pub const ODOMETRY_SCALE_MIN_EVIDENCE_M: f64 = 5.0;

/// Wheel steps shorter than this teach nothing about the scale, metres: the fit's noise
/// would swamp them.
const MIN_STEP_M: f64 = 0.01;

/// The running ratio of the fitted advance to the wheels' advance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryScale {
    config: OdometryScaleConfig,
    /// Fitted advance along the wheels' direction, summed with forgetting, metres.
    fitted_m: f64,
    /// The wheels' advance, summed with the same forgetting, metres.
    wheels_m: f64,
    /// Distance observed in all, metres (no forgetting): the evidence so far.
    observed_m: f64,
}

impl OdometryScale {
    pub fn new(config: OdometryScaleConfig) -> Self {
        Self {
            config,
            fitted_m: 0.0,
            wheels_m: 0.0,
            observed_m: 0.0,
        }
    }

    /// Learns from one step the scan fixed in every direction: `wheels` the odometry's
    /// increment (unscaled), `fitted` the scan's, both in the previous robot frame.
    pub fn observe(&mut self, wheels: &Pose2, fitted: &Pose2) {
        let advance = wheels.translation_norm();
        if !(advance >= MIN_STEP_M && advance.is_finite()) {
            return;
        }
        let along = (fitted.x * wheels.x + fitted.y * wheels.y) / advance;
        if !along.is_finite() {
            return;
        }
        let keep = (-advance / self.config.memory_m).exp();
        self.fitted_m = keep * self.fitted_m + along;
        self.wheels_m = keep * self.wheels_m + advance;
        self.observed_m += advance;
    }

    /// The scale the wheels' distances are multiplied by: 1 until there is evidence.
    pub fn scale(&self) -> f64 {
        if self.observed_m < self.config.min_evidence_m || self.wheels_m <= 0.0 {
            return 1.0;
        }
        let limit = self.config.max_correction;
        (self.fitted_m / self.wheels_m).clamp(1.0 - limit, 1.0 + limit)
    }

    /// `step` with its translation (and the translation's uncertainty) scaled.
    pub fn apply(&self, step: Step) -> Step {
        let k = self.scale();
        if k == 1.0 {
            return step;
        }
        let scaling = Matrix3::from_diagonal(&nalgebra::Vector3::new(k, k, 1.0));
        let covariance = scaling * step.covariance * scaling;
        Step {
            increment: Pose2::new(
                k * step.increment.x,
                k * step.increment.y,
                step.increment.yaw,
            ),
            covariance: 0.5 * (covariance + covariance.transpose()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> OdometryScaleConfig {
        OdometryScaleConfig {
            memory_m: 30.0,
            min_evidence_m: 5.0,
            max_correction: 0.2,
        }
    }

    #[test]
    fn wheels_that_overcount_by_three_per_cent_are_scaled_down() {
        let mut scale = OdometryScale::new(config());
        // 20 m in 5 cm steps, the wheels counting 3 % too far, the fit noisy across.
        for i in 0..400 {
            let wheels = Pose2::new(0.05 * 1.03, 0.0, 0.0);
            let side = if i % 2 == 0 { 0.002 } else { -0.002 };
            scale.observe(&wheels, &Pose2::new(0.05, side, 0.0));
        }
        assert!(
            (scale.scale() - 1.0 / 1.03).abs() < 1e-3,
            "{}",
            scale.scale()
        );
        let step = Step {
            increment: Pose2::new(1.03, 0.0, 0.1),
            covariance: Matrix3::identity(),
        };
        let scaled = scale.apply(step);
        assert!((scaled.increment.x - 1.0).abs() < 2e-3, "{scaled:?}");
        assert_eq!(scaled.increment.yaw, 0.1);
        assert!(scaled.covariance[(0, 0)] < 1.0 && scaled.covariance[(2, 2)] == 1.0);
    }

    /// `steps` straight steps the wheels count `wheels` metres long and the fit `fitted`.
    fn drive(scale: &mut OdometryScale, steps: usize, wheels: f64, fitted: f64) {
        for _ in 0..steps {
            scale.observe(&Pose2::new(wheels, 0.0, 0.0), &Pose2::new(fitted, 0.0, 0.0));
        }
    }

    #[test]
    fn no_scale_before_enough_evidence_nor_from_standing_still() {
        let mut scale = OdometryScale::new(config());
        // Standing still: the fit jitters, the wheels do not move.
        drive(&mut scale, 1000, 0.0, 0.003);
        assert_eq!(scale.scale(), 1.0);
        // 4 m observed: not yet.
        drive(&mut scale, 40, 0.1, 0.11);
        assert_eq!(scale.scale(), 1.0);
    }

    #[test]
    fn the_scale_is_kept_within_its_limit_and_follows_a_change() {
        let mut scale = OdometryScale::new(config());
        drive(&mut scale, 200, 0.1, 0.2);
        assert_eq!(scale.scale(), 1.2);
        // A new floor where the wheels are right: after 200 m (over six memories) the old
        // floor is forgotten.
        drive(&mut scale, 2000, 0.1, 0.1);
        assert!((scale.scale() - 1.0).abs() < 0.01, "{}", scale.scale());
    }
}
