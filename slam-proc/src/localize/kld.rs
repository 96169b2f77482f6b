//! KLD-sampling (Fox 2003, as AMCL does it): how many particles a resampling should draw
//! so that, with probability `1 - delta`, the Kullback-Leibler divergence between the
//! sample-based and the true posterior stays under `epsilon`, for a posterior spread over
//! `k` histogram bins.

use std::collections::HashSet;

/// The particle count KLD-sampling asks for when the particles drawn so far fill `bins`
/// bins; `z` is the upper `1 - delta` quantile of the standard normal.
pub(crate) fn kld_count(bins: usize, epsilon: f64, z: f64) -> usize {
    if bins <= 1 {
        return 1;
    }
    let k = (bins - 1) as f64;
    let a = 2.0 / (9.0 * k);
    let n = k / (2.0 * epsilon) * (1.0 - a + a.sqrt() * z).powi(3);
    n.ceil() as usize
}

/// The histogram bins the drawn particles fall into: `(x, y, yaw)` cells.
#[derive(Debug, Clone, Default)]
pub(crate) struct Bins {
    occupied: HashSet<(i32, i32, i32)>,
}

impl Bins {
    pub fn clear(&mut self) {
        self.occupied.clear();
    }

    /// Counts the bin of a pose; returns how many bins are occupied now.
    pub fn insert(&mut self, x: f64, y: f64, yaw: f64, size_xy: f64, size_yaw: f64) -> usize {
        // `as` saturates: a pose far off the map lands in an edge bin, never panics.
        let key = (
            (x / size_xy).floor() as i32,
            (y / size_xy).floor() as i32,
            (yaw / size_yaw).floor() as i32,
        );
        self.occupied.insert(key);
        self.occupied.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_count_grows_with_the_bins_and_matches_fox() {
        // epsilon 0.05 and delta 0.01 (z = 2.326), 10 bins: 217 by the formula.
        let few = kld_count(10, 0.05, 2.326);
        assert_eq!(few, 217);
        let many = kld_count(1000, 0.05, 2.326);
        assert!(many > 10 * few, "{many}");
        assert_eq!(kld_count(1, 0.05, 2.326), 1);
    }

    #[test]
    fn bins_count_distinct_cells() {
        let mut bins = Bins::default();
        assert_eq!(bins.insert(0.1, 0.1, 0.0, 0.5, 0.2), 1);
        assert_eq!(bins.insert(0.2, 0.3, 0.1, 0.5, 0.2), 1);
        assert_eq!(bins.insert(0.6, 0.3, 0.1, 0.5, 0.2), 2);
        assert_eq!(bins.insert(f64::NAN, 1e30, -1e30, 0.5, 0.2), 3);
        bins.clear();
        assert_eq!(bins.insert(0.1, 0.1, 0.0, 0.5, 0.2), 1);
    }
}
