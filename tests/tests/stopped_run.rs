//! Issue 15, maps that outlive the run: a live run stopped with Ctrl-C keeps its map however
//! long it was. The back end (graph-proc) publishes its path and grid as it stops, and
//! map-sink writes them, each file whole.

use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

use tests::map_server::{Cell, parse_pgm, parse_yaml, read_pixel};
use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(180);
/// Past the end of the 400 scans of the file: the looping emulator has started over.
const POSES: usize = 500;

#[test]
fn a_stopped_live_run_keeps_the_back_ends_path_as_a_whole_map() {
    let (mut emulator, addr) = start_hokuyo_emulator_with(&test_data::seed_hall_csv(), &["--loop"]);
    let out = scratch("stopped-run").join("run");
    let args = ["--source", "hokuyo", "--addr", &addr];
    let mut launcher = spawn_launch(&domain("stopped-run"), &out, &args, Stdio::piped());
    let console = read_console(&mut launcher);
    wait_for_poses(&mut launcher, &out, POSES, LIMIT);
    send(pid_of(&launcher), Signal::SIGINT);
    let status = wait_within(&mut launcher, LIMIT);
    if status.is_none() {
        stop(&mut launcher);
    }
    let _ = emulator.kill();
    let _ = emulator.wait();
    let console = console.join().expect("the console");
    // Ctrl-C is how a live run ends: a success, with map-sink done before the grace ended.
    assert!(status.is_some_and(|s| s.success()), "{status:?}\n{console}");
    assert!(!console.contains("killed"), "{console}");
    let log = std::fs::read_to_string(out.join("logs/graph-proc.log")).expect("graph-proc's log");
    assert!(log.contains("solved and published"), "{log}");

    let metrics = metrics(&out);
    // The back end's path, which graph-proc sends as it stops, not the online estimate
    // standing in for it.
    let trajectory = read_tum(&out.join("trajectory.tum"));
    assert!(trajectory.len() >= POSES, "{} poses", trajectory.len());
    assert_ne!(
        std::fs::read(out.join("trajectory.tum")).expect("trajectory.tum"),
        std::fs::read(out.join("trajectory_online.tum")).expect("trajectory_online.tum")
    );

    // The map as map_server reads it, traced along that path.
    let yaml = std::fs::read_to_string(out.join("map.yaml")).expect("map.yaml");
    let map = parse_yaml(&yaml);
    assert_eq!(map.image, "map.pgm");
    let (width, height, pixels) = parse_pgm(&std::fs::read(out.join(&map.image)).expect("map.pgm"));
    assert!(pixels.iter().all(|p| [0, 205, 254].contains(p)));
    let occupied = pixels
        .iter()
        .filter(|&&p| read_pixel(&map, p) == Cell::Occupied)
        .count();
    assert!(occupied > 1000, "{occupied} occupied cells");
    let extent = |axis: usize, cells: usize| {
        map.origin[axis]..map.origin[axis] + cells as f64 * map.resolution
    };
    let (xs, ys) = (extent(0, width), extent(1, height));
    assert!(
        trajectory
            .iter()
            .all(|p| xs.contains(&p.position[0]) && ys.contains(&p.position[1])),
        "the path leaves the grid traced along it"
    );
    // The landmarks name that grid and hold the map's corners.
    let landmarks: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("landmarks.json")).expect("landmarks.json"),
    )
    .expect("landmarks.json parses");
    assert_eq!(landmarks["grid"]["image"], "map.pgm");
    assert_eq!(landmarks["grid"]["width"], width);
    assert_eq!(landmarks["grid"]["height"], height);
    let corners = landmarks["corners"].as_array().expect("corners").len();
    assert_eq!(corners, metrics.map_corners);
    assert!(corners > 0);
    assert_eq!(leftover_temporaries(&out), Vec::<String>::new());
}

/// Files of a run's directory still under their temporary names.
fn leftover_temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("the run's directory")
        .filter_map(|entry| {
            let name = entry.ok()?.file_name().to_string_lossy().into_owned();
            name.ends_with(".tmp").then_some(name)
        })
        .collect()
}
