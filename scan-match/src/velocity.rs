//! The velocity that constant velocity extrapolates. With wheels, constant velocity is a
//! second opinion or bridges a step they got wrong, and a step's own velocity is the next
//! step's. Without any, every step's prior is constant velocity and every step is the fit's,
//! and along a direction the scan leaves open (a corridor) the fit mostly follows the prior:
//! when a scan that fixes every direction comes again, its fit corrects the pose by what the
//! stretch before drifted, and that correction, taken for a speed, would be extrapolated on
//! and on (a robot turning on the spot sent down the corridor at a metre a second). So
//! without wheels the speed is the median of the last [`STEPS`] steps' speeds: one step's
//! correction does not move it, a real change of speed does after a step.

use std::collections::VecDeque;

use nalgebra::Vector3;
use slam_geom::Pose2;

/// Steps the median is taken over.
const STEPS: usize = 3;

#[derive(Debug, Clone, Default)]
pub(crate) struct Velocity {
    /// `(vx, vy)` of the last steps without wheels, each in its own robot frame.
    unmeasured: VecDeque<[f64; 2]>,
    /// `(vx, vy, yaw rate)` in the robot frame.
    current: Vector3<f64>,
}

impl Velocity {
    /// `(vx, vy, yaw rate)` in the robot frame.
    pub fn get(&self) -> Vector3<f64> {
        self.current
    }

    /// After a step of `increment` over `dt` seconds, with wheels or without.
    pub fn update(&mut self, increment: &Pose2, dt: f64, wheels: bool) {
        let speed = [increment.x / dt, increment.y / dt];
        if wheels {
            self.unmeasured.clear();
            self.current = Vector3::new(speed[0], speed[1], increment.yaw / dt);
            return;
        }
        if self.unmeasured.len() == STEPS {
            self.unmeasured.pop_front();
        }
        self.unmeasured.push_back(speed);
        let median = |k: usize| {
            let mut values: Vec<f64> = self.unmeasured.iter().map(|s| s[k]).collect();
            values.sort_by(f64::total_cmp);
            values.get(values.len() / 2).copied().unwrap_or(speed[k])
        };
        // The turn rate is the last step's: a turn that reverses must be followed at once,
        // and a wrong one is the search's to catch (it searches turns wider).
        self.current = Vector3::new(median(0), median(1), increment.yaw / dt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_correction_is_not_taken_for_a_speed() {
        let mut velocity = Velocity::default();
        for _ in 0..5 {
            velocity.update(&Pose2::new(0.0, 0.0, 0.1), 0.2, false);
        }
        // A fit puts the robot 0.2 m back in one step: the speed stays.
        velocity.update(&Pose2::new(-0.2, 0.0, 0.1), 0.2, false);
        assert_eq!(velocity.get().x, 0.0);
        assert!((velocity.get().z - 0.5).abs() < 1e-12);
        // Two steps of a new speed are a new speed.
        velocity.update(&Pose2::new(0.1, 0.0, 0.0), 0.2, false);
        velocity.update(&Pose2::new(0.1, 0.0, 0.0), 0.2, false);
        assert!((velocity.get().x - 0.5).abs() < 1e-12);
    }

    #[test]
    fn with_wheels_a_step_is_its_own_velocity() {
        let mut velocity = Velocity::default();
        velocity.update(&Pose2::new(0.1, 0.0, 0.0), 0.2, false);
        velocity.update(&Pose2::new(0.1, 0.0, 0.0), 0.2, false);
        velocity.update(&Pose2::new(-0.2, 0.02, 0.1), 0.2, true);
        assert!((velocity.get() - Vector3::new(-1.0, 0.1, 0.5)).norm() < 1e-12);
    }
}
