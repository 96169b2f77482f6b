//! Exact and noisy ray-cast scans of simple geometry: accuracy, orientation independence,
//! covariance consistency, and robustness against malformed scans.

mod common;

use common::eval::{ScanGeometry, View, World};
use common::{Noise, full_turn, hokuyo, input, room};
use feature_proc::{Extractor, FeatureConfig, ScanError, ScanInput};
use nalgebra::{Vector2, Vector4};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use slam_geom::{ScanGeometryError, wrap_angle};

/// A detected corner in the world frame, for a sensor at `pose`.
fn to_world(pose: [f64; 3], x: f64, y: f64) -> [f64; 2] {
    let (s, c) = pose[2].sin_cos();
    [pose[0] + c * x - s * y, pose[1] + s * x + c * y]
}

#[test]
fn a_room_without_noise_gives_its_corners_within_a_millimetre() {
    let world = room(10.0, 8.0);
    // docs/CONVENTIONS.md: a room corner seen from inside points away from the room.
    let far = world
        .corners()
        .iter()
        .find(|c| c.x == 10.0 && c.y == 8.0)
        .unwrap();
    assert!((far.heading - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
    assert!((far.angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    let pose = [3.2, 2.7, 0.4];
    // The 270-degree scan cannot see the corner at the origin behind the sensor.
    for (geometry, visible) in [(hokuyo(), 3), (full_turn(), 4)] {
        let ranges = world.scan(pose, &geometry);
        let mut extractor = Extractor::new(FeatureConfig::default());
        let view = View::for_config(geometry, extractor.config(), 15.0);
        let expected = world.corners_in_view(pose, &view);
        assert_eq!(expected.len(), visible);
        let found = extractor.extract(&input(&geometry, &ranges)).unwrap();
        assert_eq!(found.corners.len(), visible, "{:#?}", found.corners);
        assert_eq!(found.lines.len(), visible + 1 - usize::from(visible == 4));
        for truth in &expected {
            let corner = found
                .corners
                .iter()
                .find(|c| {
                    let p = to_world(pose, c.x, c.y);
                    (p[0] - truth.x).hypot(p[1] - truth.y) < 1e-3
                })
                .unwrap_or_else(|| panic!("no corner within 1 mm of {truth:?}"));
            assert!((corner.angle - truth.angle).abs() < 0.1f64.to_radians());
            let heading = wrap_angle(corner.heading + pose[2] - truth.heading);
            assert!(
                heading.abs() < 0.1f64.to_radians(),
                "heading off by {heading}"
            );
            let covariance = corner.covariance;
            assert!(
                covariance.cholesky().is_some(),
                "not positive definite: {covariance}"
            );
        }
    }
}

#[test]
fn lines_fit_equally_well_at_any_orientation() {
    // One noisy scan of a wall 3 m ahead; turning the beams by phi turns the wall by phi in
    // the sensor frame and must change nothing else.
    let mut world = World::new();
    world.add_polyline(&[[3.0, -4.0], [3.0, 4.0]], false);
    let geometry = hokuyo();
    let ranges = Noise::new(7, 0.02).scan(&world, [0.0, 0.0, 0.0], &geometry);
    let mut extractor = Extractor::new(FeatureConfig::default());
    let base = extractor.extract(&input(&geometry, &ranges)).unwrap().lines[0];
    assert!((base.rho - 3.0).abs() < 0.01 && base.theta.abs() < 0.01);
    for degrees in [30.0f64, 45.0, 90.0, 135.0, 180.0, -90.0] {
        let phi = degrees.to_radians();
        let turned = ScanGeometry {
            angle_min: geometry.angle_min + phi,
            ..geometry
        };
        let line = extractor.extract(&input(&turned, &ranges)).unwrap().lines[0];
        assert!((line.rho - base.rho).abs() < 1e-9, "rho at {degrees} deg");
        let turn = wrap_angle(line.theta - base.theta - phi);
        assert!(turn.abs() < 1e-9, "theta at {degrees} deg off by {turn}");
        // The theta variance and the rho variance are invariant; the cross term too.
        assert!((line.covariance - base.covariance).abs().max() < 1e-12);
    }
}

/// Mean normalised estimation error squared of `samples` (error, covariance).
fn mean_nees<const D: usize>(
    samples: &[(nalgebra::SVector<f64, D>, nalgebra::SMatrix<f64, D, D>)],
) -> f64 {
    let total: f64 = samples
        .iter()
        .map(|(e, p)| (e.transpose() * p.try_inverse().unwrap() * e)[(0, 0)])
        .sum();
    total / samples.len() as f64
}

#[test]
fn reported_covariances_match_the_observed_spread() {
    let sigma = 0.02;
    // The extractor's sigma about a wall is the scanner's range noise times the walls'
    // allowance: the scanner that gives `sigma` about a wall.
    let config = FeatureConfig {
        range_sigma: sigma / feature_proc::WALL_SIGMA_FACTOR,
        ..FeatureConfig::default()
    };
    let world = room(10.0, 8.0);
    let geometry = hokuyo();
    let view = View::for_config(geometry, &config, 15.0);
    let mut extractor = Extractor::new(config);
    let mut noise = Noise::new(42, sigma);
    let (mut lines, mut positions, mut corners) = (Vec::new(), Vec::new(), Vec::new());
    for pose in [[3.2, 2.7, 0.4], [6.5, 4.0, 2.5], [2.0, 6.0, -1.2]] {
        let truths = world.corners_in_view(pose, &view);
        // Each wall as (rho, theta) in the sensor frame.
        let walls: Vec<(f64, f64)> = world
            .walls()
            .iter()
            .map(|[a, b]| {
                let (a, b) = (sensor(pose, *a), sensor(pose, *b));
                let theta = (a[0] - b[0]).atan2(b[1] - a[1]);
                let rho = a[0] * theta.cos() + a[1] * theta.sin();
                if rho < 0.0 {
                    (-rho, wrap_angle(theta + std::f64::consts::PI))
                } else {
                    (rho, theta)
                }
            })
            .collect();
        for _ in 0..300 {
            let ranges = noise.scan(&world, pose, &geometry);
            let found = extractor.extract(&input(&geometry, &ranges)).unwrap();
            for line in &found.lines {
                if let Some(&(rho, theta)) = walls.iter().find(|(rho, theta)| {
                    (line.rho - rho).abs() < 0.1 && wrap_angle(line.theta - theta).abs() < 0.05
                }) {
                    let error = Vector2::new(line.rho - rho, wrap_angle(line.theta - theta));
                    lines.push((error, line.covariance));
                }
            }
            for truth in &truths {
                let tip = sensor(pose, [truth.x, truth.y]);
                let Some(c) = found
                    .corners
                    .iter()
                    .find(|c| (c.x - tip[0]).hypot(c.y - tip[1]) < 0.2)
                else {
                    continue;
                };
                let error = Vector4::new(
                    c.x - tip[0],
                    c.y - tip[1],
                    wrap_angle(c.heading - (truth.heading - pose[2])),
                    c.angle - truth.angle,
                );
                positions.push((
                    error.fixed_rows::<2>(0).into_owned(),
                    c.covariance.fixed_view::<2, 2>(0, 0).into_owned(),
                ));
                corners.push((error, c.covariance));
            }
        }
    }
    let (line_nees, position_nees, corner_nees) = (
        mean_nees(&lines),
        mean_nees(&positions),
        mean_nees(&corners),
    );
    eprintln!(
        "{} lines: NEES {line_nees:.3} (2); {} corners: position NEES {position_nees:.3} (2), full {corner_nees:.3} (4)",
        lines.len(),
        corners.len()
    );
    assert!(lines.len() > 2000 && corners.len() > 2000);
    assert!((1.6..=2.4).contains(&line_nees), "line NEES {line_nees}");
    assert!(
        (1.6..=2.4).contains(&position_nees),
        "position NEES {position_nees}"
    );
    assert!(
        (3.2..=4.8).contains(&corner_nees),
        "corner NEES {corner_nees}"
    );
}

/// A world point in the frame of a sensor at `pose`.
fn sensor(pose: [f64; 3], p: [f64; 2]) -> [f64; 2] {
    let (s, c) = pose[2].sin_cos();
    let d = [p[0] - pose[0], p[1] - pose[1]];
    [c * d[0] + s * d[1], -s * d[0] + c * d[1]]
}

#[test]
fn malformed_scans_are_typed_errors_never_panics() {
    let mut extractor = Extractor::new(FeatureConfig::default());
    let geometry = hokuyo();
    let mut check = |scan: ScanInput<'_>| extractor.extract(&scan).cloned();
    assert_eq!(check(input(&geometry, &[])).unwrap_err(), ScanError::Empty);
    let many = vec![1.0f32; 8193];
    assert!(matches!(
        check(input(&geometry, &many)),
        Err(ScanError::TooManyBeams { .. })
    ));
    let nans = vec![f32::NAN; 1081];
    assert!(matches!(
        check(input(&geometry, &nans)),
        Err(ScanError::TooFewValid { .. })
    ));
    let mixed: Vec<f32> = (0..1081)
        .map(|i| {
            [
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                1e30,
                -5.0,
                0.0,
                f32::MAX,
                3.0,
            ][i % 8]
        })
        .collect();
    assert!(check(input(&geometry, &mixed)).is_ok());
    let ones = vec![1.0f32; 1081];
    for (angle_min, angle_increment) in [(f64::NAN, 0.01), (0.0, f64::INFINITY), (0.0, 0.0)] {
        let mut scan = input(&geometry, &ones);
        scan.geometry.angle_min = angle_min;
        scan.geometry.angle_increment = angle_increment;
        assert!(matches!(
            check(scan),
            Err(ScanError::Geometry(
                ScanGeometryError::AngleMin | ScanGeometryError::AngleIncrement
            ))
        ));
    }
    let mut wide = input(&geometry, &ones);
    wide.geometry.angle_increment = 0.1;
    assert!(matches!(check(wide), Err(ScanError::SpanTooWide { .. })));
    let mut limits = input(&geometry, &ones);
    limits.geometry.range_min = 5.0;
    limits.geometry.range_max = 1.0;
    assert!(matches!(
        check(limits),
        Err(ScanError::Geometry(ScanGeometryError::RangeLimits))
    ));

    // Random bit patterns, lengths and beam patterns.
    let mut rng = StdRng::seed_from_u64(3);
    for _ in 0..300 {
        let len = rng.random_range(0..1200);
        let ranges: Vec<f32> = (0..len)
            .map(|_| match rng.random_range(0..4) {
                0 => f32::from_bits(rng.random()),
                1 => rng.random_range(0.0..40.0),
                2 => 2.0 + rng.random_range(0.0..0.01),
                _ => f32::NAN,
            })
            .collect();
        let pick = |rng: &mut StdRng| match rng.random_range(0..4) {
            0 => f64::from_bits(rng.random()),
            1 => rng.random_range(-10.0..10.0),
            2 => rng.random_range(-0.01..0.01),
            _ => 0.0,
        };
        let scan = ScanInput {
            geometry: slam_geom::ScanGeometry {
                angle_min: pick(&mut rng),
                angle_increment: pick(&mut rng),
                time_increment: 0.0,
                scan_time: 0.0,
                range_min: pick(&mut rng),
                range_max: pick(&mut rng).abs() * 10.0,
            },
            ranges: &ranges,
        };
        if let Ok(found) = check(scan) {
            for c in &found.corners {
                assert!(c.x.is_finite() && c.y.is_finite() && c.angle.is_finite());
            }
        }
    }
}

#[test]
fn an_invalid_configuration_is_reported_per_scan() {
    let config = FeatureConfig {
        min_line_points: 1,
        ..FeatureConfig::default()
    };
    let mut extractor = Extractor::new(config);
    let ranges = room(10.0, 8.0).scan([3.0, 3.0, 0.0], &hokuyo());
    let error = extractor.extract(&input(&hokuyo(), &ranges)).unwrap_err();
    assert!(matches!(error, ScanError::Config(_)), "{error}");
}
