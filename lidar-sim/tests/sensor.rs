//! The scanner model: noise statistics, dropouts, invalid values, exact noise-free scans.

use lidar_sim::{LidarModel, Pose2, RayCaster, SensorConfig, World};
use rand::SeedableRng;
use rand::rngs::StdRng;

/// One wall across the x axis at `x`, seen by a single beam looking along +x.
fn wall_at(x: f64) -> RayCaster {
    RayCaster::new(&World {
        walls: vec![vec![[x, -100.0], [x, 100.0]]],
        waypoints: vec![[0.0, 0.0], [1.0, 0.0]],
        speed: 1.0,
    })
}

fn one_beam(config: SensorConfig) -> LidarModel {
    let config = SensorConfig {
        beams: 1,
        angle_min: 0.0,
        ..config
    };
    LidarModel::new(config).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn range_noise_has_the_configured_mean_and_spread() {
    let lidar = one_beam(SensorConfig {
        dropout: 0.0,
        ..SensorConfig::default()
    });
    let mut rng = StdRng::seed_from_u64(11);
    let mut out = Vec::new();
    for truth in [5.0, 20.0] {
        let caster = wall_at(truth);
        let sigma = lidar.config().sigma_at(truth);
        let n = 20_000;
        let samples: Vec<f64> = (0..n)
            .map(|_| {
                lidar.scan(&caster, Pose2::new(0.0, 0.0, 0.0), &mut rng, &mut out);
                f64::from(out[0])
            })
            .collect();
        let mean = samples.iter().sum::<f64>() / n as f64;
        let var = samples.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        // f32 storage adds at most 1e-6 m of bias at 20 m; far below 4 sigma / sqrt(n).
        assert!(
            (mean - truth).abs() < 4.0 * sigma / (n as f64).sqrt(),
            "mean {mean} at {truth}"
        );
        assert!(
            (var.sqrt() / sigma - 1.0).abs() < 0.05,
            "std {} vs {sigma}",
            var.sqrt()
        );
    }
    let c = SensorConfig::default();
    assert_eq!(c.sigma_at(10.0), 0.01);
    assert!((c.sigma_at(30.0) - 0.05 / 3.0).abs() < 1e-12);
}

#[test]
fn dropouts_come_at_the_configured_rate() {
    let lidar = LidarModel::new(SensorConfig::default()).unwrap_or_else(|e| panic!("{e}"));
    let caster = RayCaster::new(&World::builtin("office").unwrap_or_else(|e| panic!("{e}")));
    let mut rng = StdRng::seed_from_u64(5);
    let mut out = Vec::new();
    let (mut nan, mut total) = (0usize, 0usize);
    for k in 0..200 {
        lidar.scan(
            &caster,
            Pose2::new(10.0 + 0.1 * f64::from(k), 6.4, 0.0),
            &mut rng,
            &mut out,
        );
        nan += out.iter().filter(|r| r.is_nan()).count();
        total += out.len();
    }
    let p = lidar.config().dropout;
    let sd = (total as f64 * p * (1.0 - p)).sqrt();
    assert!(
        (nan as f64 - total as f64 * p).abs() < 4.0 * sd,
        "{nan} NaN in {total}"
    );
}

#[test]
fn invalid_ranges_follow_rep_117() {
    let exact = one_beam(SensorConfig::default().noise_free());
    let mut rng = StdRng::seed_from_u64(1);
    let mut out = Vec::new();
    let pose = Pose2::new(0.0, 0.0, 0.0);
    exact.scan(&wall_at(0.05), pose, &mut rng, &mut out);
    assert_eq!(out, [f32::NEG_INFINITY], "closer than range_min");
    exact.scan(&wall_at(35.0), pose, &mut rng, &mut out);
    assert_eq!(out, [f32::INFINITY], "beyond range_max");
    exact.scan(&wall_at(-3.0), pose, &mut rng, &mut out);
    assert_eq!(out, [f32::INFINITY], "nothing ahead");
    exact.scan(&wall_at(12.5), pose, &mut rng, &mut out);
    assert_eq!(out, [12.5]);
    let always = one_beam(SensorConfig {
        dropout: 1.0,
        ..SensorConfig::default()
    });
    always.scan(&wall_at(12.5), pose, &mut rng, &mut out);
    assert!(out[0].is_nan());
}

#[test]
fn noise_free_scan_is_the_ray_cast_of_every_beam() {
    let lidar =
        LidarModel::new(SensorConfig::default().noise_free()).unwrap_or_else(|e| panic!("{e}"));
    let c = lidar.config().clone();
    assert_eq!(c.beams, 1081);
    assert!((c.angle_max() - 0.75 * std::f64::consts::PI).abs() < 1e-12);
    assert_eq!(c.period_ns(), 25_000_000);
    let caster = RayCaster::new(&World::builtin("hall").unwrap_or_else(|e| panic!("{e}")));
    let pose = Pose2::new(4.0, 10.75, 0.3);
    let mut out = Vec::new();
    lidar.scan(&caster, pose, &mut StdRng::seed_from_u64(0), &mut out);
    assert_eq!(out.len(), 1081);
    for (i, &r) in out.iter().enumerate() {
        let b = pose.yaw + c.angle_min + i as f64 * c.angle_increment;
        let want = caster
            .cast([pose.x, pose.y], b, 40.0)
            .filter(|&t| t <= c.range_max);
        assert_eq!(r, want.map_or(f32::INFINITY, |t| t as f32), "beam {i}");
    }
}

#[test]
fn bad_settings_are_named() {
    let e = LidarModel::new(SensorConfig {
        range_max: 0.05,
        ..SensorConfig::default()
    });
    assert!(e.is_err_and(|e| e.field == "range_max"));
    let e = LidarModel::new(SensorConfig {
        dropout: 1.5,
        ..SensorConfig::default()
    });
    assert!(e.is_err_and(|e| e.field == "dropout"));
}
