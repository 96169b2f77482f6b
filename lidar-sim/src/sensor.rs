//! Settings of the simulated scanner; the defaults are a Hokuyo UTM-30LX.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};
use slam_geom::ScanGeometry;

use stage_kit::settings::{SettingError, check, check_non_negative};

/// Scanner geometry, timing and noise. Metres, radians, seconds.
///
/// Range noise is Gaussian with a standard deviation that is constant up to `noise_knee`
/// and grows linearly beyond it. The UTM-30LX data sheet gives an accuracy of +-30 mm from
/// 0.1 to 10 m and +-50 mm from 10 to 30 m; reading those bounds as 3 sigma gives the
/// defaults: 10 mm up to 10 m, rising to 50/3 = 16.7 mm at 30 m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    /// Beams per scan.
    pub beams: usize,
    /// Bearing of the first beam in the sensor frame (0 = forward, counterclockwise).
    pub angle_min: f64,
    /// Bearing step between neighbouring beams.
    pub angle_increment: f64,
    pub range_min: f64,
    pub range_max: f64,
    /// Scans per second; the simulated time step is its inverse.
    pub rate: f64,
    /// Range noise standard deviation up to `noise_knee`.
    pub noise_sigma: f64,
    /// Range beyond which the noise grows, metres.
    pub noise_knee: f64,
    /// Growth of the standard deviation per metre beyond the knee.
    pub noise_slope: f64,
    /// Probability that a beam returns nothing usable (reported as NaN).
    pub dropout: f64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        Self {
            beams: 1081,
            angle_min: -0.75 * PI,
            angle_increment: PI / 720.0,
            range_min: 0.1,
            range_max: 30.0,
            rate: 40.0,
            noise_sigma: 0.01,
            noise_knee: 10.0,
            noise_slope: (0.05 / 3.0 - 0.01) / 20.0,
            dropout: 0.005,
        }
    }
}

impl SensorConfig {
    /// The same scanner without range noise or dropouts, for exact tests.
    pub fn noise_free(self) -> SensorConfig {
        SensorConfig {
            noise_sigma: 0.0,
            noise_slope: 0.0,
            dropout: 0.0,
            ..self
        }
    }

    /// Standard deviation of a reading of true range `r`.
    pub fn sigma_at(&self, r: f64) -> f64 {
        self.noise_sigma + self.noise_slope * (r - self.noise_knee).max(0.0)
    }

    /// Bearing of the last beam.
    pub fn angle_max(&self) -> f64 {
        self.angle_min + (self.beams.saturating_sub(1)) as f64 * self.angle_increment
    }

    /// Time between scans, nanoseconds.
    pub fn period_ns(&self) -> u64 {
        (1e9 / self.rate).round() as u64
    }

    /// Checks every setting; [`crate::LidarModel::new`] refuses what fails.
    /// The geometry of the scans it publishes. A UTM-30LX sweeps 1440 steps per turn, so
    /// its beams are a 1440th of a scan period apart.
    pub fn scan_geometry(&self) -> ScanGeometry {
        let scan_time = 1.0 / self.rate;
        ScanGeometry {
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            time_increment: scan_time / 1440.0,
            scan_time,
            range_min: self.range_min,
            range_max: self.range_max,
        }
    }

    pub fn validate(&self) -> Result<(), SettingError> {
        let n = self.beams as f64;
        check(
            "beams",
            n,
            (1..=8192).contains(&self.beams),
            "must be in 1..=8192",
        )?;
        let a = self.angle_min;
        check(
            "angle_min",
            a,
            a.is_finite() && a.abs() <= PI,
            "must be in [-pi, pi]",
        )?;
        let inc = self.angle_increment;
        let ok = inc.is_finite() && inc > 0.0 && inc * (n - 1.0) <= 2.0 * PI;
        check(
            "angle_increment",
            inc,
            ok,
            "must be > 0 with all beams within one turn",
        )?;
        let (lo, hi) = (self.range_min, self.range_max);
        check(
            "range_min",
            lo,
            lo.is_finite() && lo >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "range_max",
            hi,
            hi.is_finite() && hi > lo,
            "must be finite and > range_min",
        )?;
        let r = self.rate;
        check(
            "rate",
            r,
            r.is_finite() && (0.1..=1e6).contains(&r),
            "must be in [0.1, 1e6] Hz",
        )?;
        check_non_negative(&[
            ("noise_sigma", self.noise_sigma),
            ("noise_knee", self.noise_knee),
            ("noise_slope", self.noise_slope),
        ])?;
        let p = self.dropout;
        check(
            "dropout",
            p,
            (0.0..=1.0).contains(&p),
            "must be a probability in [0, 1]",
        )
    }
}
