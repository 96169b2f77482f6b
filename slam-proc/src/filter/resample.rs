//! Weights in log space and systematic (low-variance) resampling.

/// `ln sum exp(v)`, stable for any magnitudes; `-inf` for no finite value.
pub(crate) fn log_sum_exp(values: &[f64]) -> f64 {
    let max = values
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return max;
    }
    max + values
        .iter()
        .filter(|v| !v.is_nan())
        .map(|v| (v - max).exp())
        .sum::<f64>()
        .ln()
}

/// Normalised weights from log weights. Log weights that are all `-inf` or NaN (every
/// particle impossible) give uniform weights: nothing distinguishes the particles then.
pub(crate) fn normalise(log_weights: &[f64], weights: &mut Vec<f64>) {
    weights.clear();
    let total = log_sum_exp(log_weights);
    if total.is_finite() {
        weights.extend(
            log_weights
                .iter()
                .map(|l| if l.is_nan() { 0.0 } else { (l - total).exp() }),
        );
    } else {
        weights.resize(log_weights.len(), 1.0 / log_weights.len().max(1) as f64);
    }
}

/// The normalised weights of `log_weights`, as the filter makes them (all `-inf` or NaN:
/// uniform): the particles' weights as a viewer shows them.
pub fn normalised_weights(log_weights: &[f64]) -> Vec<f64> {
    let mut weights = Vec::with_capacity(log_weights.len());
    normalise(log_weights, &mut weights);
    weights
}

/// `1 / sum w_i^2` of normalised weights: N for uniform weights, 1 when one dominates.
pub(crate) fn effective_sample_size(weights: &[f64]) -> f64 {
    let sum_squares: f64 = weights.iter().map(|w| w * w).sum();
    if sum_squares > 0.0 {
        1.0 / sum_squares
    } else {
        0.0
    }
}

/// The index of the largest weight, the first of equals: ties must not depend on anything
/// but the order. 0 for no weights.
pub(crate) fn heaviest(weights: &[f64]) -> usize {
    let mut best = 0;
    for (i, w) in weights.iter().enumerate() {
        if *w > weights[best] {
            best = i;
        }
    }
    best
}

/// Systematic resampling: one uniform `u` in `[0, 1)` places N evenly spaced pointers on
/// the cumulative weights, so particle `i` gets `floor(N w_i)` or `ceil(N w_i)` copies.
/// Writes the parent index of each new particle to `parents`, in order.
pub(crate) fn systematic(weights: &[f64], u: f64, parents: &mut Vec<usize>) {
    parents.clear();
    let n = weights.len();
    if n == 0 {
        return;
    }
    let step = 1.0 / n as f64;
    let mut cumulative = weights[0];
    let mut i = 0;
    for m in 0..n {
        let pointer = (u + m as f64) * step;
        // Rounding can leave the cumulative sum a hair below 1: the last particle takes it.
        while pointer > cumulative && i + 1 < n {
            i += 1;
            cumulative += weights[i];
        }
        parents.push(i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn log_sum_exp_survives_extreme_values() {
        assert!((log_sum_exp(&[-1000.0, -1000.0]) - (-1000.0 + 2f64.ln())).abs() < 1e-12);
        assert!((log_sum_exp(&[800.0, 0.0]) - 800.0).abs() < 1e-12);
        assert_eq!(log_sum_exp(&[f64::NEG_INFINITY]), f64::NEG_INFINITY);
        let mut w = Vec::new();
        normalise(&[-1e3, -1e3 + 2f64.ln()], &mut w);
        assert!((w[0] - 1.0 / 3.0).abs() < 1e-12 && (w[1] - 2.0 / 3.0).abs() < 1e-12);
        normalise(&[f64::NEG_INFINITY; 4], &mut w);
        assert_eq!(w, vec![0.25; 4]);
    }

    #[test]
    fn systematic_keeps_n_and_gives_floor_or_ceil_copies() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let n = 1000;
        let raw: Vec<f64> = (0..n).map(|_| rng.random::<f64>().powi(4)).collect();
        let total: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / total).collect();
        let mut parents = Vec::new();
        for _ in 0..20 {
            systematic(&weights, rng.random(), &mut parents);
            assert_eq!(parents.len(), n);
            assert!(parents.windows(2).all(|p| p[0] <= p[1]));
            let mut counts = vec![0usize; n];
            for &p in &parents {
                counts[p] += 1;
            }
            for (count, w) in counts.iter().zip(&weights) {
                let expected = w * n as f64;
                assert!(
                    (*count as f64 - expected).abs() < 1.0 + 1e-9,
                    "{count} copies for {expected}"
                );
            }
        }
    }

    #[test]
    fn systematic_follows_the_weights_on_average() {
        let weights = [0.5, 0.3, 0.15, 0.05];
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut counts = [0usize; 4];
        let mut parents = Vec::new();
        let draws = 20_000;
        for _ in 0..draws {
            systematic(&weights, rng.random(), &mut parents);
            for &p in &parents {
                counts[p] += 1;
            }
        }
        for (count, w) in counts.iter().zip(weights) {
            let frequency = *count as f64 / (4 * draws) as f64;
            assert!((frequency - w).abs() < 0.005, "{frequency} for weight {w}");
        }
    }

    #[test]
    fn effective_sample_size_spans_one_to_n() {
        assert!((effective_sample_size(&[0.25; 4]) - 4.0).abs() < 1e-12);
        assert!((effective_sample_size(&[1.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_heaviest_is_the_first_of_equal_largest_weights() {
        assert_eq!(heaviest(&[0.1, 0.4, 0.1, 0.4]), 1);
        assert_eq!(heaviest(&[0.7, 0.2, 0.1]), 0);
        assert_eq!(heaviest(&[]), 0);
    }
}
