//! Mean and spread of a list of errors, plain and squared, as the tables of Kuemmerle et
//! al. 2009 report them.

use serde::{Deserialize, Serialize};

/// Statistics of non-negative errors `e_i`: of `e_i` and of `e_i^2`. Standard deviations
/// are those of the population (divided by n), describing the relations at hand.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ErrorStats {
    pub mean: f64,
    pub std: f64,
    pub squared_mean: f64,
    pub squared_std: f64,
    pub max: f64,
}

impl ErrorStats {
    /// Statistics of `errors`; all zero for an empty list.
    pub fn of(errors: &[f64]) -> Self {
        if errors.is_empty() {
            return Self::default();
        }
        let squared: Vec<f64> = errors.iter().map(|e| e * e).collect();
        let (mean, std) = mean_std(errors);
        let (squared_mean, squared_std) = mean_std(&squared);
        Self {
            mean,
            std,
            squared_mean,
            squared_std,
            max: errors.iter().copied().fold(0.0, f64::max),
        }
    }

    /// The same statistics in another unit: `factor` scales the errors (e.g. radians to
    /// degrees), so the squared ones scale by its square.
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            mean: self.mean * factor,
            std: self.std * factor,
            squared_mean: self.squared_mean * factor * factor,
            squared_std: self.squared_std * factor * factor,
            max: self.max * factor,
        }
    }

    /// The statistics of several sets of errors taken together, from each set's count and
    /// statistics alone: the same numbers as [`ErrorStats::of`] over all the errors at once
    /// (to rounding). Sets with no errors count for nothing; `None` if no set has any.
    pub fn pooled(parts: &[(usize, ErrorStats)]) -> Option<Self> {
        let total: usize = parts.iter().map(|(n, _)| n).sum();
        if total == 0 {
            return None;
        }
        let weight = |n: usize| n as f64 / total as f64;
        // Mean and standard deviation pooled from (n, mean, std): the pooled second moment
        // is the weighted mean of std^2 + mean^2.
        let pool = |mean: fn(&ErrorStats) -> f64, std: fn(&ErrorStats) -> f64| {
            let m: f64 = parts.iter().map(|(n, s)| weight(*n) * mean(s)).sum();
            let second: f64 = parts
                .iter()
                .map(|(n, s)| weight(*n) * (std(s).powi(2) + mean(s).powi(2)))
                .sum();
            (m, (second - m * m).max(0.0).sqrt())
        };
        let (mean, std) = pool(|s| s.mean, |s| s.std);
        let (squared_mean, squared_std) = pool(|s| s.squared_mean, |s| s.squared_std);
        let max = parts
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(_, s)| s.max)
            .fold(0.0, f64::max);
        Some(Self {
            mean,
            std,
            squared_mean,
            squared_std,
            max,
        })
    }
}

fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, variance.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_and_squared_statistics() {
        let stats = ErrorStats::of(&[1.0, 3.0]);
        assert_eq!(stats.mean, 2.0);
        assert_eq!(stats.std, 1.0);
        assert_eq!(stats.squared_mean, 5.0);
        assert_eq!(stats.squared_std, 4.0);
        assert_eq!(stats.max, 3.0);
        let scaled = stats.scaled(10.0);
        assert_eq!((scaled.mean, scaled.squared_mean), (20.0, 500.0));
        assert_eq!(ErrorStats::of(&[]), ErrorStats::default());
    }

    #[test]
    fn pooled_statistics_equal_those_of_all_errors_at_once() {
        let a = [0.1, 0.4, 0.2];
        let b = [1.0, 0.3];
        let all: Vec<f64> = a.iter().chain(&b).copied().collect();
        let pooled = ErrorStats::pooled(&[
            (a.len(), ErrorStats::of(&a)),
            (0, ErrorStats::default()),
            (b.len(), ErrorStats::of(&b)),
        ])
        .unwrap();
        let direct = ErrorStats::of(&all);
        for (p, d) in [
            (pooled.mean, direct.mean),
            (pooled.std, direct.std),
            (pooled.squared_mean, direct.squared_mean),
            (pooled.squared_std, direct.squared_std),
            (pooled.max, direct.max),
        ] {
            assert!((p - d).abs() < 1e-12, "{pooled:?} != {direct:?}");
        }
        assert_eq!(ErrorStats::pooled(&[(0, ErrorStats::default())]), None);
    }
}
