//! Whole runs: determinism per seed, the vehicle's limits and clearance, and the corners in
//! view along the paths.

use lidar_sim::geometry::Segment;
use lidar_sim::{
    BUILTIN_WORLDS, Laps, Point2, RayCaster, SensorConfig, SimulatedScan, Simulation, Vehicle,
    VehicleConfig, World, visible_corners, wrap_angle,
};

fn world(name: &str) -> World {
    World::builtin(name).unwrap_or_else(|e| panic!("{e}"))
}

fn frames(seed: u64, n: usize) -> Vec<SimulatedScan> {
    let mut sim = Simulation::new(
        world("office"),
        SensorConfig::default(),
        VehicleConfig::default(),
        seed,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    (0..n).map_while(|_| sim.next_frame()).collect()
}

/// Frames compared bit for bit (NaN dropouts included).
fn bits(f: &SimulatedScan) -> (u64, u64, [u64; 6], Vec<u32>) {
    let p = [
        f.pose.x,
        f.pose.y,
        f.pose.yaw,
        f.odometry.x,
        f.odometry.y,
        f.odometry.yaw,
    ];
    (
        f.seq,
        f.stamp_ns,
        p.map(f64::to_bits),
        f.ranges.iter().map(|r| r.to_bits()).collect(),
    )
}

#[test]
fn same_seed_same_frames_other_seed_other_noise() {
    let (a, b, c) = (frames(7, 300), frames(7, 300), frames(8, 300));
    assert_eq!(a.len(), 300);
    assert!(a.iter().zip(&b).all(|(x, y)| bits(x) == bits(y)));
    assert!(
        a.iter().zip(&c).all(|(x, y)| x.pose == y.pose),
        "the truth does not depend on the seed"
    );
    assert!(
        a.iter()
            .zip(&c)
            .skip(1)
            .all(|(x, y)| x.ranges != y.ranges && x.odometry != y.odometry)
    );
    for (k, f) in a.iter().enumerate() {
        assert_eq!((f.seq, f.stamp_ns), (k as u64, k as u64 * 25_000_000));
    }
    // Odometry drifts only a little over 300 frames.
    let (last, odo) = (a[299].pose, a[299].odometry);
    assert!((last.x - odo.x).hypot(last.y - odo.y) < 0.5);
}

/// Drives the vehicle alone at 10 ms, once and three laps (round a loop, back and forth
/// along an open route), and checks its limits, its clearance from every wall and that it
/// stops on the last waypoint.
#[test]
fn vehicle_turns_within_its_limits_keeps_clear_and_stops_at_the_end() {
    let config = VehicleConfig::default();
    for (name, laps) in BUILTIN_WORLDS.into_iter().flat_map(|w| [(w, 1), (w, 3)]) {
        let w = world(name);
        let walls: Vec<Segment> = w.segments().map(|[a, b]| Segment::new(a, b)).collect();
        let laps = Laps::new(laps).unwrap_or_else(|e| panic!("{e}"));
        let mut v = Vehicle::with_laps(&w, config.clone(), laps).unwrap_or_else(|e| panic!("{e}"));
        let dt = 0.01;
        let (mut t, mut prev_speed, mut clearance) = (0.0, 0.0, f64::INFINITY);
        let laps = f64::from(laps.get());
        while !v.finished() {
            let before = v.pose();
            v.step(dt);
            let p = v.pose();
            t += dt;
            assert!(
                t < (3.0 * w.path_length() / w.speed + 60.0) * laps,
                "{name}: never arrives"
            );
            assert!(wrap_angle(p.yaw - before.yaw).abs() <= config.max_yaw_rate * dt + 1e-12);
            assert!(v.speed() <= w.speed + 1e-12);
            assert!(
                (v.speed() - prev_speed).abs() <= config.max_accel * dt + 1e-9,
                "{name} at {t}"
            );
            prev_speed = v.speed();
            let here = Point2::new(p.x, p.y);
            clearance = walls
                .iter()
                .map(|s| s.distance_to_point(here))
                .fold(clearance, f64::min);
        }
        let end = w.waypoints[w.waypoints.len() - 1];
        let p = v.pose();
        println!("{name}, {laps} laps: {t:.1} s, clearance of the driven path {clearance:.2} m");
        assert!(
            (p.x - end[0]).hypot(p.y - end[1]) < 0.05,
            "{name}: stopped at {p:?}"
        );
        assert!(
            clearance >= 0.4,
            "{name}: came within {clearance} m of a wall"
        );
    }
}

#[test]
fn corridor_run_ends_after_the_last_waypoint() {
    let sensor = SensorConfig {
        beams: 10,
        ..SensorConfig::default()
    };
    let mut sim = Simulation::new(world("corridor"), sensor, VehicleConfig::default(), 1)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut last = None;
    while let Some(f) = sim.next_frame() {
        last = Some(f);
    }
    let f = last.unwrap_or_else(|| panic!("no frames"));
    assert!(
        (f.pose.x - 68.0).abs() < 0.05 && (f.pose.y - 1.25).abs() < 0.05,
        "{:?}",
        f.pose
    );
    assert!(sim.next_frame().is_none());
    // 66 m at up to 1 m/s: a little over 66 s.
    let seconds = f.stamp_ns as f64 * 1e-9;
    assert!((66.0..80.0).contains(&seconds), "{seconds} s");
}

/// Corners within 15 m with a clear view of both arms, every 0.25 m along each path, with
/// and without the 270 degree field of view (facing along the path).
#[test]
fn corners_in_view_along_the_paths() {
    for name in BUILTIN_WORLDS {
        let w = world(name);
        let caster = RayCaster::new(&w);
        let corners = w.true_corners();
        let (mut min, mut sum, mut min_fov, mut n) = (usize::MAX, 0, usize::MAX, 0);
        for p in w.waypoints.windows(2) {
            let (a, b) = (Point2::new(p[0][0], p[0][1]), Point2::new(p[1][0], p[1][1]));
            let yaw = (b.y - a.y).atan2(b.x - a.x);
            let steps = ((b - a).norm() / 0.25).ceil() as usize;
            for k in 0..steps {
                let q = a + (b - a) * (k as f64 / steps as f64);
                let seen = visible_corners(&caster, &corners, [q.x, q.y], 15.0);
                let in_fov = seen
                    .iter()
                    .filter(|&&i| {
                        let bearing = (corners[i].y - q.y).atan2(corners[i].x - q.x);
                        wrap_angle(bearing - yaw).abs() <= 0.75 * std::f64::consts::PI
                    })
                    .count();
                min = min.min(seen.len());
                min_fov = min_fov.min(in_fov);
                sum += seen.len();
                n += 1;
            }
        }
        let mean = sum as f64 / n as f64;
        println!(
            "{name}: visible corners within 15 m: min {min}, mean {mean:.1}; in the field of view: min {min_fov}"
        );
        if name == "office" {
            assert!(
                min_fov >= 4,
                "office: only {min_fov} corners in view somewhere"
            );
        }
    }
}
