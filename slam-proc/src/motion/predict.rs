//! The prediction step: each particle moves by the motion estimate composed in its own
//! frame, perturbed by noise that has a floor and grows with the step.

use nalgebra::{Matrix3, Vector3};
use rand::Rng;
use rand_distr::StandardNormal;

use crate::config::SlamConfig;
use crate::motion::estimator::{Motion, MotionSource};
use slam_geom::Pose2;

/// Particle translation noise per step at most (the course's model, which bounds a fitted
/// step's noise): `sigma = base + per_metre * |t| + per_radian * |dyaw|`, metres. The base
/// keeps the particles diverse when the robot stands; the terms grow with the step as
/// wheel slip and a fit's error do.
const NOISE_XY_BASE: f64 = 0.01;
const NOISE_XY_PER_METRE: f64 = 0.05;
const NOISE_XY_PER_RADIAN: f64 = 0.02;
/// Particle rotation noise per step at most: `sigma = base + per_radian * |dyaw| +
/// per_metre * |t|`, radians (the same model, for the heading).
const NOISE_YAW_BASE: f64 = 0.004;
const NOISE_YAW_PER_RADIAN: f64 = 0.05;
const NOISE_YAW_PER_METRE: f64 = 0.01;
/// A corner-fitted step spreads the particles by this multiple of the fit's own standard
/// deviations (within the model above): the fit knows how well it did, but its covariance
/// takes the corners for independent, which they are not quite.
const NOISE_FIT_SCALE: f64 = 2.0;
/// Smallest translation noise of a fitted step, metres: the particles must stay diverse
/// however sure the fit is.
const NOISE_XY_FLOOR: f64 = 0.002;
/// Smallest rotation noise of a fitted step, radians.
const NOISE_YAW_FLOOR: f64 = 0.0005;
/// Noise multiplier for a step at constant velocity (no fit, no odometry): the motion is a
/// guess, so the particles must spread wider than the model says for a measured step.
const FALLBACK_NOISE_SCALE: f64 = 3.0;

/// Standard deviations of one step's noise, in the particle's frame before the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MotionNoise {
    pub sigma_xy: f64,
    pub sigma_yaw: f64,
}

impl MotionNoise {
    /// The noise of a step. The course model (a floor plus terms proportional to the
    /// translation and rotation) bounds it; within that, a corner fit spreads the
    /// particles by its own uncertainty (times [`NOISE_FIT_SCALE`], floored), a line fit
    /// likewise in heading; odometry alone by the odometry's reported uncertainty (floored
    /// by the motion estimate), since the model's per-step floor would random-walk the
    /// particles far faster than good odometry drifts; constant velocity, which only
    /// guesses, by the model times [`FALLBACK_NOISE_SCALE`].
    pub fn for_step(motion: &Motion, config: &SlamConfig) -> Self {
        let (t, r) = (motion.delta.translation_norm(), motion.delta.yaw.abs());
        let model = Self {
            sigma_xy: NOISE_XY_BASE + NOISE_XY_PER_METRE * t + NOISE_XY_PER_RADIAN * r,
            sigma_yaw: NOISE_YAW_BASE + NOISE_YAW_PER_RADIAN * r + NOISE_YAW_PER_METRE * t,
        };
        match motion.source {
            // A fit knows how well it did: the particles spread by a multiple of its own
            // standard deviations, no tighter than the floors (diversity) and no wider
            // than the model (a fit's covariance can be pessimistic at long range).
            MotionSource::Corners => {
                let (xy, yaw) = fit_sigmas(&motion.covariance);
                Self {
                    sigma_xy: fitted(xy, NOISE_XY_FLOOR, model.sigma_xy),
                    sigma_yaw: fitted(yaw, NOISE_YAW_FLOOR, model.sigma_yaw),
                }
            }
            // Walls fix a line step's heading as well as the fit says (scaled and floored
            // like a corner fit's, the particles spread too narrowly along the walls). The
            // advance along them is the prior's: as good as the fit says on odometry, a
            // guess at constant velocity, where the fit's tighter figure would be too sure.
            MotionSource::Lines { on_odometry } => {
                let (xy, yaw) = fit_sigmas(&motion.covariance);
                Self {
                    sigma_xy: if on_odometry {
                        fitted(xy, NOISE_XY_FLOOR, model.sigma_xy)
                    } else {
                        model.sigma_xy
                    },
                    sigma_yaw: yaw.min(model.sigma_yaw),
                }
            }
            MotionSource::Odometry => {
                let (sigma_xy, sigma_yaw) = fit_sigmas(&motion.covariance);
                Self {
                    sigma_xy,
                    sigma_yaw,
                }
            }
            // A front end registers each scan against keyframes: its error grows with the
            // path, not with the scan count, and its covariance (that of independent beams)
            // says little about it. The particles spread by that drift.
            MotionSource::Measured => Self {
                sigma_xy: (config.measured_xy_variance_per_metre * t
                    + config.measured_xy_variance_per_radian * r)
                    .sqrt(),
                sigma_yaw: (config.measured_yaw_variance_per_metre * t
                    + config.measured_yaw_variance_per_radian * r)
                    .sqrt(),
            },
            MotionSource::ConstantVelocity => Self {
                sigma_xy: FALLBACK_NOISE_SCALE * model.sigma_xy,
                sigma_yaw: FALLBACK_NOISE_SCALE * model.sigma_yaw,
            },
        }
    }

    /// No noise at all (the first scan: the first pose is the map frame by definition).
    pub const NONE: Self = Self {
        sigma_xy: 0.0,
        sigma_yaw: 0.0,
    };

    /// Covariance of the noise in the world frame. The translation noise is isotropic, so
    /// it is the same in every frame.
    pub fn covariance(&self) -> Matrix3<f64> {
        let (t, r) = (
            self.sigma_xy * self.sigma_xy,
            self.sigma_yaw * self.sigma_yaw,
        );
        Matrix3::from_diagonal(&Vector3::new(t, t, r))
    }
}

/// The standard deviations of a step's translation (the larger axis: the noise is
/// isotropic) and rotation, from its covariance.
fn fit_sigmas(covariance: &Matrix3<f64>) -> (f64, f64) {
    let xy = covariance[(0, 0)].max(covariance[(1, 1)]).max(0.0).sqrt();
    (xy, covariance[(2, 2)].max(0.0).sqrt())
}

/// [`NOISE_FIT_SCALE`] times a fit's standard deviation, between `floor` and `model`.
fn fitted(sigma: f64, floor: f64, model: f64) -> f64 {
    (NOISE_FIT_SCALE * sigma).max(floor).min(model.max(floor))
}

/// The noisy increment `delta + noise` a particle moves by, in its own frame.
pub(crate) fn sample(delta: &Pose2, noise: &MotionNoise, rng: &mut impl Rng) -> Pose2 {
    let nx: f64 = rng.sample(StandardNormal);
    let ny: f64 = rng.sample(StandardNormal);
    let nr: f64 = rng.sample(StandardNormal);
    // The increment's yaw is not wrapped here: composing it with the pose wraps the sum.
    Pose2::new(
        delta.x + noise.sigma_xy * nx,
        delta.y + noise.sigma_xy * ny,
        delta.yaw + noise.sigma_yaw * nr,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn noise_grows_with_the_step_and_follows_the_source() {
        let config = SlamConfig::default();
        let motion = |x: f64, yaw: f64, source: MotionSource, variance: f64| Motion {
            delta: Pose2::new(x, 0.0, yaw),
            covariance: Matrix3::identity() * variance,
            source,
            inliers: 0,
        };
        let noise = |m: Motion| MotionNoise::for_step(&m, &config);
        // A poor fit spreads the particles as the model says, which grows with the step.
        let small = noise(motion(0.01, 0.0, MotionSource::Corners, 1.0));
        let large = noise(motion(0.3, 0.2, MotionSource::Corners, 1.0));
        assert!(small.sigma_xy < large.sigma_xy && small.sigma_yaw < large.sigma_yaw);
        // A good fit by its own uncertainty, scaled, but no tighter than the floors.
        let good = noise(motion(0.3, 0.2, MotionSource::Corners, 1e-6));
        assert!((good.sigma_xy - NOISE_FIT_SCALE * 1e-3).abs() < 1e-15);
        let perfect = noise(motion(0.3, 0.2, MotionSource::Corners, 0.0));
        assert_eq!(perfect.sigma_xy, NOISE_XY_FLOOR);
        assert_eq!(perfect.sigma_yaw, NOISE_YAW_FLOOR);
        // Lines: heading from the fit as it is; translation from the model at constant
        // velocity, from the fit (odometry along the walls) on odometry.
        let walls =
            |on_odometry| noise(motion(0.3, 0.2, MotionSource::Lines { on_odometry }, 1e-6));
        assert_eq!(walls(false).sigma_xy, large.sigma_xy);
        assert!((walls(false).sigma_yaw - 1e-3).abs() < 1e-15);
        assert_eq!(walls(true).sigma_xy, good.sigma_xy);
        let guess = noise(motion(0.3, 0.2, MotionSource::ConstantVelocity, 0.0));
        assert!((guess.sigma_xy - FALLBACK_NOISE_SCALE * large.sigma_xy).abs() < 1e-15);
        // Odometry spreads the particles as widely as it says it errs (the motion estimate
        // has already floored that), however tight.
        let odometry = noise(motion(0.3, 0.2, MotionSource::Odometry, 1e-6));
        assert!((odometry.sigma_xy - 1e-3).abs() < 1e-15);
        assert!((odometry.sigma_yaw - 1e-3).abs() < 1e-15);
    }

    #[test]
    fn samples_spread_around_the_composed_pose_in_the_particle_frame() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let pose = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
        let delta = Pose2::new(1.0, 0.0, 0.1);
        let noise = MotionNoise {
            sigma_xy: 0.05,
            sigma_yaw: 0.01,
        };
        let n = 20_000;
        let samples: Vec<Pose2> = (0..n)
            .map(|_| pose.compose(&sample(&delta, &noise, &mut rng)))
            .collect();
        let mean_x = samples.iter().map(|p| p.x).sum::<f64>() / n as f64;
        let mean_y = samples.iter().map(|p| p.y).sum::<f64>() / n as f64;
        // Forward in a frame turned by 90 degrees is +y in the world.
        assert!((mean_x - 1.0).abs() < 0.003 && (mean_y - 3.0).abs() < 0.003);
        let var_x = samples.iter().map(|p| (p.x - mean_x).powi(2)).sum::<f64>() / n as f64;
        assert!((var_x.sqrt() - 0.05).abs() < 0.003);
        let exact = MotionNoise::NONE;
        assert_eq!(sample(&delta, &exact, &mut rng), delta);
    }
}
