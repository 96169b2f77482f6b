//! The scanner model: exact ranges from the ray caster, then noise, dropouts and the
//! REP 117 invalid values.

use rand::Rng;
use rand_distr::StandardNormal;

use crate::{Pose2, RayCaster, SensorConfig, SettingError};

/// A scanner with checked settings.
#[derive(Debug, Clone)]
pub struct LidarModel {
    config: SensorConfig,
}

impl LidarModel {
    pub fn new(config: SensorConfig) -> Result<LidarModel, SettingError> {
        config.validate()?;
        Ok(LidarModel { config })
    }

    pub fn config(&self) -> &SensorConfig {
        &self.config
    }

    /// Fills `out` with one scan from the sensor at `pose` (beam `i` at bearing
    /// `angle_min + i * angle_increment` in the sensor frame).
    ///
    /// Per beam: with probability `dropout` NaN (a measurement error); no wall within reach
    /// gives +inf; otherwise the true range plus Gaussian noise, reported as +inf beyond
    /// `range_max` and -inf below `range_min`. The noisy value decides, as in a real sensor
    /// whose firmware only sees the measurement. Every beam draws the same random numbers
    /// whatever it hits, so the noise of one beam does not depend on the geometry.
    pub fn scan(&self, caster: &RayCaster, pose: Pose2, rng: &mut impl Rng, out: &mut Vec<f32>) {
        let c = &self.config;
        // A wall just beyond range_max can still read inside it.
        let reach = c.range_max + 6.0 * c.sigma_at(c.range_max);
        out.clear();
        out.reserve(c.beams);
        for i in 0..c.beams {
            let bearing = pose.yaw + c.angle_min + i as f64 * c.angle_increment;
            let truth = caster.cast([pose.x, pose.y], bearing, reach);
            let dropped = rng.random_bool(c.dropout);
            let z: f64 = rng.sample(StandardNormal);
            let range = match truth {
                _ if dropped => f32::NAN,
                None => f32::INFINITY,
                Some(t) => {
                    let r = t + c.sigma_at(t) * z;
                    if r > c.range_max {
                        f32::INFINITY
                    } else if r < c.range_min {
                        f32::NEG_INFINITY
                    } else {
                        r as f32
                    }
                }
            };
            out.push(range);
        }
    }
}
