//! Absolute trajectory error after alignment, corner scoring and percentiles.

use std::f64::consts::PI;

use slam_eval::{ate, nearest_rmse, percentile};
use slam_geom::Se2Alignment;

/// A deterministic standard normal sample (splitmix64, Box-Muller): the noise of a truth.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

fn moved(points: &[[f64; 2]], t: Se2Alignment) -> Vec<[f64; 2]> {
    points.iter().map(|p| t.apply(*p)).collect()
}

fn lap(n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / n as f64;
            [4.0 * t.cos() + 0.3 * (3.0 * t).sin(), 2.5 * t.sin()]
        })
        .collect()
}

#[test]
fn known_rigid_motion_is_recovered_exactly() {
    let est = lap(200);
    let truth_from_est = Se2Alignment {
        rotation: 2.4,
        translation: [12.0, -7.5],
    };
    let truth = moved(&est, truth_from_est);
    let stats = ate(&est, &truth).expect("paired, non-empty");
    let found = stats.alignment;
    assert!((found.rotation - 2.4).abs() < 1e-12, "{found:?}");
    assert!(
        (found.translation[0] - 12.0).abs() < 1e-10 && (found.translation[1] + 7.5).abs() < 1e-10
    );
    assert!(stats.rmse_m < 1e-10 && stats.max_m < 1e-10 && stats.final_error_m < 1e-10);
    assert_eq!(stats.pairs, 200);
}

#[test]
fn rotation_near_pi_does_not_flip_or_reflect() {
    let est = lap(50);
    let t = Se2Alignment {
        rotation: -PI,
        translation: [1.0, 1.0],
    };
    let found = ate(&est, &moved(&est, t)).expect("paired").alignment;
    assert!((found.rotation.abs() - PI).abs() < 1e-12);
    let back = found.inverse();
    let p = back.apply(found.apply([3.0, -2.0]));
    assert!((p[0] - 3.0).abs() < 1e-12 && (p[1] + 2.0).abs() < 1e-12);
}

#[test]
fn noisy_truth_gives_the_noise_level() {
    let est = lap(2000);
    let t = Se2Alignment {
        rotation: -0.7,
        translation: [3.0, 4.0],
    };
    let sigma = 0.05;
    let mut rng = Rng(7);
    let truth: Vec<[f64; 2]> = moved(&est, t)
        .into_iter()
        .map(|p| [p[0] + sigma * rng.normal(), p[1] + sigma * rng.normal()])
        .collect();
    let stats = ate(&est, &truth).expect("paired, non-empty");
    assert!(
        (stats.alignment.rotation + 0.7).abs() < 0.01,
        "{:?}",
        stats.alignment
    );
    assert!((stats.alignment.translation[0] - 3.0).abs() < 0.01);
    assert!((stats.alignment.translation[1] - 4.0).abs() < 0.01);
    // A 2-D isotropic error of sigma per axis has RMS length sigma * sqrt(2).
    let expected = sigma * 2_f64.sqrt();
    assert!(
        (stats.rmse_m - expected).abs() < 0.1 * expected,
        "{}",
        stats.rmse_m
    );
    assert!(stats.max_m > stats.rmse_m);
}

#[test]
fn degenerate_inputs() {
    // One pose fixes no rotation: it is aligned by translation alone.
    let one = ate(&[[1.0, 2.0]], &[[4.0, 6.0]])
        .expect("one pair")
        .alignment;
    assert_eq!(one.rotation, 0.0);
    assert_eq!(one.translation, [3.0, 4.0]);
    let standing = ate(&[[1.0, 2.0]; 3], &[[4.0, 6.0]; 3]).expect("three pairs");
    assert_eq!(standing.alignment.translation, [3.0, 4.0]);
    assert_eq!(standing.rmse_m, 0.0);
    assert!(ate(&[], &[]).is_none());
    assert!(ate(&[[0.0, 0.0]], &[]).is_none());
}

#[test]
fn corner_rmse_uses_the_nearest_true_corner() {
    let truth = [[0.0, 0.0], [10.0, 0.0]];
    let map = [[0.3, 0.4], [10.0, 0.0], [9.4, 0.8]];
    let rmse = nearest_rmse(&map, &truth).expect("non-empty");
    assert!((rmse - ((0.25 + 0.0 + 1.0) / 3.0_f64).sqrt()).abs() < 1e-12);
    assert!(nearest_rmse(&[], &truth).is_none());
    assert!(nearest_rmse(&map, &[]).is_none());
}

#[test]
fn percentiles_interpolate_like_numpy() {
    let values: Vec<f64> = (1..=100).map(f64::from).collect();
    assert_eq!(percentile(&values, 50.0), Some(50.5));
    assert!((percentile(&values, 99.0).unwrap_or(0.0) - 99.01).abs() < 1e-9);
    assert_eq!(percentile(&values, 0.0), Some(1.0));
    assert_eq!(percentile(&values, 100.0), Some(100.0));
    assert_eq!(percentile(&[3.0, 1.0, 2.0, f64::NAN], 50.0), Some(2.0));
    assert_eq!(percentile(&[], 50.0), None);
    assert_eq!(percentile(&[1.0], 101.0), None);
}
