//! Shared helpers of the integration tests: beam patterns and noisy ray-cast scans.

#![allow(dead_code)]

pub mod eval;
pub mod recorded;

use eval::{ScanGeometry, World};
use feature_proc::ScanInput;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

/// A Hokuyo UTM-30LX: 1081 beams over 270 degrees, forward on +x.
pub fn hokuyo() -> ScanGeometry {
    ScanGeometry {
        angle_min: -0.75 * std::f64::consts::PI,
        angle_increment: std::f64::consts::PI / 720.0,
        beams: 1081,
        range_max: 30.0,
    }
}

/// A full turn in quarter degrees, starting behind the sensor.
pub fn full_turn() -> ScanGeometry {
    ScanGeometry {
        angle_min: -std::f64::consts::PI,
        angle_increment: std::f64::consts::PI / 720.0,
        beams: 1440,
        range_max: 30.0,
    }
}

pub fn input<'a>(geometry: &ScanGeometry, ranges: &'a [f32]) -> ScanInput<'a> {
    ScanInput {
        geometry: slam_geom::ScanGeometry {
            angle_min: geometry.angle_min,
            angle_increment: geometry.angle_increment,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.05,
            range_max: geometry.range_max,
        },
        ranges,
    }
}

/// Seeded Gaussian range noise.
pub struct Noise {
    rng: StdRng,
    normal: Normal<f64>,
}

impl Noise {
    pub fn new(seed: u64, sigma: f64) -> Self {
        Self {
            rng: StdRng::seed_from_u64(seed),
            normal: Normal::new(0.0, sigma).unwrap(),
        }
    }

    /// An exact scan from `pose` with noise added to every return.
    pub fn scan(&mut self, world: &World, pose: [f64; 3], geometry: &ScanGeometry) -> Vec<f32> {
        let mut ranges = world.scan(pose, geometry);
        for r in &mut ranges {
            if r.is_finite() {
                *r = (f64::from(*r) + self.normal.sample(&mut self.rng)) as f32;
            }
        }
        ranges
    }
}

/// A rectangular room `[0, w] x [0, h]`, walls counter-clockwise.
pub fn room(w: f64, h: f64) -> World {
    let mut world = World::new();
    world.add_polyline(&[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]], true);
    world
}
