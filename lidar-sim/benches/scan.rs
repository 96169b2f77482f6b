//! One 1081-beam UTM-30LX scan in the built-in worlds and in a world of 1000 random
//! segments (the ray caster's design target: well under 1 ms).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use lidar_sim::{LidarModel, Pose2, RayCaster, SensorConfig, World};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// 250 random 0.5 m squares in the hall's outline: 1000 segments plus the hall's walls.
fn random_world() -> World {
    let mut world = World::builtin("hall").unwrap_or_else(|e| panic!("{e}"));
    let mut rng = StdRng::seed_from_u64(7);
    let squares = (0..250).map(|_| {
        let (x, y): (f64, f64) = (rng.random_range(1.0..40.0), rng.random_range(1.0..28.0));
        vec![
            [x, y],
            [x + 0.5, y],
            [x + 0.5, y + 0.5],
            [x, y + 0.5],
            [x, y],
        ]
    });
    world.walls = squares.collect();
    world
}

fn bench(c: &mut Criterion) {
    let lidar = LidarModel::new(SensorConfig::default()).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = StdRng::seed_from_u64(1);
    let mut out = Vec::new();
    let mut cases: Vec<(String, World)> = ["hall", "office"]
        .iter()
        .map(|&n| {
            (
                n.to_string(),
                World::builtin(n).unwrap_or_else(|e| panic!("{e}")),
            )
        })
        .collect();
    cases.push(("random1000".into(), random_world()));
    for (name, world) in cases {
        let caster = RayCaster::new(&world);
        let [x, y] = world.waypoints[0];
        let pose = Pose2::new(x + 0.3, y + 0.2, 0.4);
        c.bench_function(
            &format!("scan_{name}_{}seg", caster.segments().len()),
            |b| {
                b.iter(|| {
                    lidar.scan(&caster, black_box(pose), &mut rng, &mut out);
                    black_box(&out);
                })
            },
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
