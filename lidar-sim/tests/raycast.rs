//! Ray casting against geometry with known answers, and the grid against brute force.

use std::f64::consts::{FRAC_PI_2, PI};

use lidar_sim::{BUILTIN_WORLDS, RayCaster, World};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn world(walls: Vec<Vec<[f64; 2]>>) -> World {
    World {
        walls,
        waypoints: vec![[0.0, 0.0], [1.0, 0.0]],
        speed: 1.0,
    }
}

fn room() -> RayCaster {
    RayCaster::new(&world(vec![vec![
        [0.0, 0.0],
        [10.0, 0.0],
        [10.0, 10.0],
        [0.0, 10.0],
        [0.0, 0.0],
    ]]))
}

fn close(got: Option<f64>, want: f64) {
    let t = got.unwrap_or(f64::NAN);
    assert!((t - want).abs() < 1e-9, "got {got:?}, want {want}");
}

#[test]
fn axis_directions_and_vertices_in_a_room() {
    let c = room();
    let o = [3.0, 4.0];
    close(c.cast(o, 0.0, 30.0), 7.0);
    close(c.cast(o, FRAC_PI_2, 30.0), 6.0);
    close(c.cast(o, PI, 30.0), 3.0);
    close(c.cast(o, -FRAC_PI_2, 30.0), 4.0);
    // Exactly at the vertices.
    close(c.cast(o, 6f64.atan2(7.0), 30.0), 85f64.sqrt());
    close(c.cast(o, (-4f64).atan2(-3.0), 30.0), 5.0);
    close(c.cast(o, 6f64.atan2(-3.0), 30.0), 45f64.sqrt());
    // Beyond max_range: no hit.
    assert_eq!(c.cast(o, 0.0, 6.9), None);
}

#[test]
fn every_direction_from_inside_a_closed_room() {
    let c = room();
    let o = [3.0, 4.0];
    for k in 0..3600 {
        let a = -PI + k as f64 * (2.0 * PI / 3600.0);
        let (s, co) = a.sin_cos();
        let along = |d: f64, p: f64| match d {
            d if d > 0.0 => (10.0 - p) / d,
            d if d < 0.0 => -p / d,
            _ => f64::INFINITY,
        };
        close(c.cast(o, a, 30.0), along(co, o[0]).min(along(s, o[1])));
    }
}

#[test]
fn parallel_and_end_on_beams_and_misses() {
    let c = RayCaster::new(&world(vec![vec![[0.0, 1.0], [10.0, 1.0]]]));
    // Parallel to the wall, beside it: nothing.
    assert_eq!(c.cast([0.0, 0.0], 0.0, 30.0), None);
    assert_eq!(c.cast([0.0, 0.0], PI, 30.0), None);
    // Along its line: the end face of the thin wall.
    close(c.cast([-2.0, 1.0], 0.0, 30.0), 2.0);
    close(c.cast([12.5, 1.0], PI, 30.0), 2.5);
    // Straight at it, from outside the grid, and away from it.
    close(c.cast([5.0, -20.0], FRAC_PI_2, 30.0), 21.0);
    assert_eq!(c.cast([5.0, -20.0], -FRAC_PI_2, 30.0), None);
    assert_eq!(c.cast([50.0, 50.0], 0.3, 1e6), None);
    // Past either end: nothing.
    assert_eq!(c.cast([10.5, 0.0], FRAC_PI_2, 30.0), None);
    close(c.cast([10.0, 0.0], FRAC_PI_2, 30.0), 1.0);
}

fn agree(caster: &RayCaster, o: [f64; 2], a: f64) {
    let (g, b) = (caster.cast(o, a, 30.0), caster.cast_brute_force(o, a, 30.0));
    let same = match (g, b) {
        (Some(g), Some(b)) => (g - b).abs() <= 1e-9,
        (None, None) => true,
        _ => false,
    };
    assert!(same, "grid {g:?} vs brute force {b:?} from {o:?} at {a}");
}

#[test]
fn grid_agrees_with_brute_force_in_every_builtin_world() {
    let mut rng = StdRng::seed_from_u64(3);
    for name in BUILTIN_WORLDS {
        let w = World::builtin(name).unwrap_or_else(|e| panic!("{e}"));
        let caster = RayCaster::new(&w);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in w.walls.iter().flatten() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k] - 2.0);
                hi[k] = hi[k].max(p[k] + 2.0);
            }
        }
        for _ in 0..20_000 {
            let o = [
                rng.random_range(lo[0]..hi[0]),
                rng.random_range(lo[1]..hi[1]),
            ];
            agree(&caster, o, rng.random_range(-PI..PI));
        }
        // Aimed exactly at vertices, and along the grid lines' axes.
        for p in w.walls.iter().flatten() {
            let o = [
                rng.random_range(lo[0]..hi[0]),
                rng.random_range(lo[1]..hi[1]),
            ];
            agree(&caster, o, (p[1] - o[1]).atan2(p[0] - o[0]));
            agree(&caster, [p[0], o[1]], FRAC_PI_2);
            agree(&caster, [o[0], p[1]], 0.0);
        }
    }
}
