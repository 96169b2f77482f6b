//! Chi-square gates. Every test here has an even number of degrees of freedom (4 per
//! corner), for which the distribution function has a closed form, so the thresholds are
//! exact rather than approximated.

/// `P(X <= x)` for `X ~ chi2(dof)`, `dof` even and > 0: `P(Poisson(x / 2) >= dof / 2)`.
pub(crate) fn cdf_even(x: f64, dof: usize) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let lambda = x / 2.0;
    let k = dof / 2;
    // Terms e^-l l^i / i! in log space: they under- and overflow separately for large l.
    let ln_lambda = lambda.ln();
    let mut ln_term = -lambda;
    let mut ln_terms = Vec::with_capacity(k);
    for i in 0..k {
        if i > 0 {
            ln_term += ln_lambda - (i as f64).ln();
        }
        ln_terms.push(ln_term);
    }
    let max = ln_terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let tail: f64 = ln_terms.iter().map(|t| (t - max).exp()).sum::<f64>() * max.exp();
    (1.0 - tail).clamp(0.0, 1.0)
}

/// The `p` quantile of `chi2(dof)`, `dof` even and > 0, `p` in `(0, 1)`, by bisection.
pub(crate) fn quantile_even(p: f64, dof: usize) -> f64 {
    let mut high = dof as f64 + 10.0;
    while cdf_even(high, dof) < p {
        high *= 2.0;
    }
    let mut low = 0.0;
    for _ in 0..100 {
        let mid = 0.5 * (low + high);
        if cdf_even(mid, dof) < p {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.5 * (low + high)
}

/// Thresholds of the association tests at one probability: the individual test of one
/// corner (4 dof) and the joint tests of `k` corners (4k dof), grown on demand.
#[derive(Debug, Clone)]
pub(crate) struct Gates {
    probability: f64,
    /// `joint[k]` is the threshold for `k` pairings; `joint[0]` is 0.
    joint: Vec<f64>,
}

impl Gates {
    pub fn new(probability: f64) -> Self {
        let mut gates = Self {
            probability,
            joint: vec![0.0],
        };
        gates.ensure(8);
        gates
    }

    /// Makes thresholds for up to `pairings` corners available.
    pub fn ensure(&mut self, pairings: usize) {
        while self.joint.len() <= pairings {
            let k = self.joint.len();
            self.joint.push(quantile_even(self.probability, 4 * k));
        }
    }

    /// The individual (4 dof) threshold.
    pub fn individual(&self) -> f64 {
        self.joint[1]
    }

    /// Thresholds indexed by the number of pairings.
    pub fn joint(&self) -> &[f64] {
        &self.joint
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_tables() {
        // Reference values from standard chi-square tables.
        for (p, dof, expected) in [
            (0.95, 2, 5.991_464_547),
            (0.99, 4, 13.276_704_13),
            (0.999, 4, 18.466_826_95),
            (0.99, 40, 63.690_739_75),
            (0.999, 100, 149.449_252_9),
        ] {
            let q = quantile_even(p, dof);
            assert!(
                (q - expected).abs() < 1e-6 * expected,
                "chi2({p}, {dof}) = {q}, not {expected}"
            );
        }
    }

    #[test]
    fn gates_grow_on_demand() {
        let mut gates = Gates::new(0.99);
        gates.ensure(20);
        assert_eq!(gates.joint().len(), 21);
        assert!((gates.individual() - 13.276_704_13).abs() < 1e-6);
        assert!(gates.joint().windows(2).all(|w| w[0] < w[1]));
    }
}
