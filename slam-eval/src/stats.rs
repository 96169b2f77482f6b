//! Mean and spread of a list of errors, plain and squared, as the tables of Kuemmerle et
//! al. 2009 report them.

use serde::Serialize;

/// Statistics of non-negative errors `e_i`: of `e_i` and of `e_i^2`. Standard deviations
/// are those of the population (divided by n), describing the relations at hand.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
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
}
