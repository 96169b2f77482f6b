//! The office loop's occupancy grid against the world it was made in (issue 15, first
//! acceptance bullet): `map.yaml` and `map.pgm` are read here by the ROS map_server rules
//! with a parser of this file's own, not with the saved-map crate's code (with which map-sink
//! writes them), and the grid is compared with the simulator's walls.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use lidar_sim::{RayCaster, SensorConfig, World};
use slam_geom::{Point2, Se2Alignment, TumPose, WeightedPair, align_se2};
use tests::map_server::{Cell, MapDescription, parse_pgm, parse_yaml, read_pixel};
use tests::*;

/// An occupied cell counts as a wall when its centre is this close to one, and a wall point
/// counts as mapped when an occupied cell centre is this close to it.
const TOLERANCE_M: f64 = 0.1;
/// Wall points are sampled this far apart.
const SAMPLE_STEP_M: f64 = 0.02;

fn distance_to_segment(p: [f64; 2], [a, b]: [[f64; 2]; 2]) -> f64 {
    let e = [b[0] - a[0], b[1] - a[1]];
    let len2 = e[0] * e[0] + e[1] * e[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * e[0]).hypot(p[1] - a[1] - t * e[1])
}

/// The map-frame-to-world transform: the final path fitted onto the truth by stamp.
fn map_to_world(out: &Path) -> Se2Alignment {
    let xy = |p: &TumPose| Point2::new(p.position[0], p.position[1]);
    let truth: HashMap<u64, Point2> = read_tum(&out.join("ground_truth.tum"))
        .iter()
        .map(|p| (p.stamp_ns, xy(p)))
        .collect();
    let pairs: Vec<WeightedPair> = read_tum(&out.join("trajectory.tum"))
        .iter()
        .filter_map(|p| Some((xy(p), *truth.get(&p.stamp_ns)?, 1.0)))
        .collect();
    assert!(pairs.len() > 1000, "{} poses with truth", pairs.len());
    align_se2(&pairs).expect("a path fixes the rotation")
}

/// Points along the walls, `SAMPLE_STEP_M` apart, that the simulated scanner's beams hit
/// from some true pose: the wall the sensor saw.
fn seen_wall_points(world: &World, truth: &[TumPose]) -> Vec<[f64; 2]> {
    let caster = RayCaster::new(world);
    let sensor = SensorConfig::default();
    let key = |p: [f64; 2]| {
        [
            (p[0] / SAMPLE_STEP_M).floor() as i64,
            (p[1] / SAMPLE_STEP_M).floor() as i64,
        ]
    };
    let mut hit = HashSet::new();
    for pose in truth.iter().step_by(2) {
        let yaw = pose.yaw();
        let [x, y, _] = pose.position;
        for i in 0..sensor.beams {
            let bearing = yaw + sensor.angle_min + i as f64 * sensor.angle_increment;
            if let Some(r) = caster.cast([x, y], bearing, sensor.range_max) {
                hit.insert(key([x + r * bearing.cos(), y + r * bearing.sin()]));
            }
        }
    }
    let mut seen = Vec::new();
    for [a, b] in world.segments() {
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        let n = (length / SAMPLE_STEP_M).ceil().max(1.0) as usize;
        for k in 0..n {
            let t = (k as f64 + 0.5) / n as f64;
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let [x, y] = key(p);
            let near = (-1..=1).any(|dx| (-1..=1).any(|dy| hit.contains(&[x + dx, y + dy])));
            if near {
                seen.push(p);
            }
        }
    }
    seen
}

/// A run's grid as map_server reads it: the description, the image and the centres of its
/// occupied cells in the map frame.
struct ReadGrid {
    yaml: String,
    map: MapDescription,
    width: usize,
    height: usize,
    pixels: Vec<u8>,
    occupied: Vec<[f64; 2]>,
    free: usize,
}

impl ReadGrid {
    fn of(out: &Path) -> Self {
        let yaml = std::fs::read_to_string(out.join("map.yaml")).expect("map.yaml");
        let map = parse_yaml(&yaml);
        let (width, height, pixels) =
            parse_pgm(&std::fs::read(out.join(&map.image)).expect("map.pgm"));
        // map_server puts image row 0 at the top: cell (col, row) from the bottom-left has
        // its centre at origin + (col + 0.5, row + 0.5) * resolution.
        let mut occupied = Vec::new();
        let mut free = 0;
        for (i, &pixel) in pixels.iter().enumerate() {
            let (col, row) = (i % width, height - 1 - i / width);
            match read_pixel(&map, pixel) {
                Cell::Occupied => occupied.push([
                    map.origin[0] + (col as f64 + 0.5) * map.resolution,
                    map.origin[1] + (row as f64 + 0.5) * map.resolution,
                ]),
                Cell::Free => free += 1,
                Cell::Unknown => {}
            }
        }
        Self {
            yaml,
            map,
            width,
            height,
            pixels,
            occupied,
            free,
        }
    }

    /// The share of occupied cells within `TOLERANCE_M` of a wall, once moved into the world.
    fn precision(&self, to_world: &Se2Alignment, walls: &[[[f64; 2]; 2]]) -> f64 {
        let on_a_wall = self
            .occupied
            .iter()
            .filter(|c| {
                let p = to_world.apply(**c);
                walls
                    .iter()
                    .any(|w| distance_to_segment(p, *w) <= TOLERANCE_M)
            })
            .count();
        on_a_wall as f64 / self.occupied.len() as f64
    }

    /// Whether each of the world points `seen` has an occupied cell centre within
    /// `TOLERANCE_M` of it, once moved into the map frame.
    fn mapped(&self, to_world: &Se2Alignment, seen: &[[f64; 2]]) -> Vec<bool> {
        let map = &self.map;
        let to_map = to_world.inverse();
        let cell_key = |p: [f64; 2]| {
            [
                ((p[0] - map.origin[0]) / map.resolution).floor() as i64,
                ((p[1] - map.origin[1]) / map.resolution).floor() as i64,
            ]
        };
        let occupied_cells: HashSet<[i64; 2]> =
            self.occupied.iter().map(|c| cell_key(*c)).collect();
        let reach = (TOLERANCE_M / map.resolution).ceil() as i64 + 1;
        seen.iter()
            .map(|p| {
                let q = to_map.apply(*p);
                let [x, y] = cell_key(q);
                (-reach..=reach).any(|dx| {
                    (-reach..=reach).any(|dy| {
                        let c = [x + dx, y + dy];
                        let centre = [
                            map.origin[0] + (c[0] as f64 + 0.5) * map.resolution,
                            map.origin[1] + (c[1] as f64 + 0.5) * map.resolution,
                        ];
                        occupied_cells.contains(&c)
                            && (centre[0] - q[0]).hypot(centre[1] - q[1]) <= TOLERANCE_M
                    })
                })
            })
            .collect()
    }
}

fn share(flags: &[bool]) -> f64 {
    flags.iter().filter(|&&f| f).count() as f64 / flags.len() as f64
}

#[test]
fn the_office_grid_matches_the_world() {
    let out = launched(
        "grid-office",
        &["--world", "office", "--rate", "0", "--seed", "1"],
    )
    .out;

    let grid = ReadGrid::of(&out);
    let (map, width, height) = (&grid.map, grid.width, grid.height);
    assert_eq!(map.image, "map.pgm");
    assert_eq!(map.mode, "trinary");
    assert_eq!(map.resolution, 0.05);
    assert_eq!(map.origin[2], 0.0);
    assert!(!map.negate);
    assert!(
        grid.pixels.iter().all(|p| [0, 205, 254].contains(p)),
        "a trinary image has three values"
    );
    assert_eq!(read_pixel(map, 205), Cell::Unknown, "{}", grid.yaml);
    assert_eq!(read_pixel(map, 254), Cell::Free);
    assert_eq!(read_pixel(map, 0), Cell::Occupied);
    let (occupied, free) = (&grid.occupied, grid.free);
    assert!(free > 10 * occupied.len(), "{free} free cells");

    let world = World::builtin("office").expect("office");
    let walls: Vec<[[f64; 2]; 2]> = world.segments().collect();
    let to_world = map_to_world(&out);
    let precision = grid.precision(&to_world, &walls);

    let truth = read_tum(&out.join("ground_truth.tum"));
    let seen = seen_wall_points(&world, &truth);
    let total: f64 = walls
        .iter()
        .map(|[a, b]| (b[0] - a[0]).hypot(b[1] - a[1]))
        .sum();
    let recall = share(&grid.mapped(&to_world, &seen));
    eprintln!(
        "office grid {width} x {height}: {} occupied cells, {:.2} % within {TOLERANCE_M} m of a wall; \
         {:.1} of {total:.1} m of wall seen, {:.2} % of it with an occupied cell within {TOLERANCE_M} m",
        occupied.len(),
        100.0 * precision,
        seen.len() as f64 * SAMPLE_STEP_M,
        100.0 * recall
    );
    assert!(
        precision >= 0.95,
        "{:.2} % of occupied cells on a wall",
        100.0 * precision
    );
    assert!(
        recall >= 0.90,
        "{:.2} % of the seen wall mapped",
        100.0 * recall
    );

    // The rest of the saved map: the PNG for people and the landmarks beside the grid.
    let png = std::fs::read(out.join("map.png")).expect("map.png");
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    let landmarks: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("landmarks.json")).expect("landmarks.json"),
    )
    .expect("landmarks.json is JSON");
    assert_eq!(landmarks["format"], "lidar-slam-landmarks");
    assert_eq!(landmarks["version"], 1);
    assert_eq!(landmarks["grid"]["width"], width);
    assert_eq!(
        landmarks["corners"].as_array().map(Vec::len),
        Some(metrics(&out).map_corners)
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Mapping on a saved map (issue 15, point 4): the output is the map of the building, not
/// only of what the new run saw. The saved map covers most of the office loop; the run on top
/// of it (another seed) only its first stretch, and its grid must still hold the walls of
/// both, as cleanly as each alone.
#[test]
fn a_run_on_a_saved_map_keeps_the_saved_grid_s_walls() {
    let office = |tag: &str, options: &[&str]| {
        let mut args = vec!["--world", "office", "--rate", "0"];
        args.extend(options);
        launched(tag, &args).out
    };
    let first = office("grid-saved-part", &["--frames", "3000"]);
    let short = ["--seed", "2", "--frames", "1200"];
    let alone = office("grid-short-alone", &short);
    let saved_dir = first.to_str().expect("a UTF-8 path");
    let on_top = office(
        "grid-short-on-top",
        &[&short[..], &["--map", saved_dir]].concat(),
    );

    let world = World::builtin("office").expect("office");
    let walls: Vec<[[f64; 2]; 2]> = world.segments().collect();
    let mut truth = read_tum(&first.join("ground_truth.tum"));
    truth.extend(read_tum(&alone.join("ground_truth.tum")));
    let seen = seen_wall_points(&world, &truth);
    let coverage = |out: &Path| {
        let grid = ReadGrid::of(out);
        let to_world = map_to_world(out);
        (
            grid.mapped(&to_world, &seen),
            grid.precision(&to_world, &walls),
            grid,
        )
    };
    let (saved, saved_precision, saved_grid) = coverage(&first);
    let (short_alone, _, _) = coverage(&alone);
    let (merged, precision, merged_grid) = coverage(&on_top);
    let union: Vec<bool> = saved.iter().zip(&short_alone).map(|(a, b)| a | b).collect();
    let kept = union.iter().zip(&merged).filter(|&(&u, &m)| u && m).count() as f64
        / union.iter().filter(|&&u| u).count() as f64;
    eprintln!(
        "office on a saved map: wall seen by either run mapped: saved {:.2} %, short run alone {:.2} %, \
         both {:.2} %, on top of the saved map {:.2} % ({:.2} % of the union); occupied cells on a wall: \
         saved {:.2} %, on top {:.2} %",
        100.0 * share(&saved),
        100.0 * share(&short_alone),
        100.0 * share(&union),
        100.0 * share(&merged),
        100.0 * kept,
        100.0 * saved_precision,
        100.0 * precision
    );
    // The short run alone maps much less than the saved map: what the test tells apart.
    assert!(share(&short_alone) < 0.8 * share(&saved));
    assert!(kept >= 0.97, "{:.2} % of the union kept", 100.0 * kept);
    assert!(
        precision >= 0.95,
        "{:.2} % of occupied cells on a wall",
        100.0 * precision
    );
    // The saved map's extent is kept: the merged image covers the saved one.
    let corner = |g: &ReadGrid| {
        [
            g.map.origin[0],
            g.map.origin[1],
            g.map.origin[0] + g.width as f64 * g.map.resolution,
            g.map.origin[1] + g.height as f64 * g.map.resolution,
        ]
    };
    let (s, m) = (corner(&saved_grid), corner(&merged_grid));
    let slack = 1e-6;
    assert!(
        m[0] <= s[0] + slack
            && m[1] <= s[1] + slack
            && m[2] >= s[2] - slack
            && m[3] >= s[3] - slack,
        "saved {s:?}, merged {m:?}"
    );
    // Extending a map in place is refused before anything starts: the run would clear the
    // map's files while its stages read them.
    let in_place = launch(
        &domain("grid-in-place"),
        &first,
        &["--world", "office", "--frames", "10", "--map", saved_dir],
    );
    let stderr = String::from_utf8_lossy(&in_place.stderr);
    assert_eq!(in_place.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("is the saved map's directory"), "{stderr}");
    assert!(first.join("landmarks.json").is_file() && first.join("map.pgm").is_file());
    for out in [first, alone, on_top] {
        let _ = std::fs::remove_dir_all(&out);
    }
}
