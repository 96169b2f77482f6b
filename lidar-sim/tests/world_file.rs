//! World files: a valid one, each refusal by name, the built-in worlds and their paths.

use lidar_sim::geometry::Segment;
use lidar_sim::{BUILTIN_WORLDS, World, WorldError};

const VALID: &str = r#"{"walls": [[[0, 0], [4, 0], [4, 3], [0, 3], [0, 0]]],
                         "waypoints": [[1, 1], [3, 1]]}"#;

#[test]
fn valid_file_parses_with_default_speed_and_round_trips() {
    let w = World::from_json_str(VALID).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(w.speed, 1.0);
    assert_eq!(w.walls[0].len(), 5);
    assert_eq!(w.true_corners().len(), 4);
    let text = serde_json::to_string(&w).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(World::from_json_str(&text).ok(), Some(w.clone()));
    let path = std::env::temp_dir().join(format!("lidar-sim-world-{}.json", std::process::id()));
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
    let loaded = World::resolve(&path.display().to_string());
    std::fs::remove_file(&path).ok();
    assert_eq!(loaded.ok(), Some(w));
}

fn refused(text: &str) -> WorldError {
    match World::from_json_str(text) {
        Ok(w) => panic!("accepted {text}: {w:?}"),
        Err(e) => e,
    }
}

#[test]
fn each_problem_is_named() {
    let e = refused("{\"walls\": [\n  [[0, 0], [1, 0]],\n");
    assert!(matches!(e, WorldError::Json { line: 3, .. }), "{e}");
    assert!(e.to_string().contains("line 3"), "{e}");
    let e = refused(r#"{"waypoints": [[0, 0], [1, 0]]}"#);
    assert!(matches!(e, WorldError::MissingKey { key: "walls" }), "{e}");
    let e = refused(r#"{"walls": [[[0, 0], [1, 0]]]}"#);
    assert!(
        matches!(e, WorldError::MissingKey { key: "waypoints" }),
        "{e}"
    );
    let e = refused(r#"{"walls": [[[0, 0], [1, 0]]], "waypoints": [[0, 1], [1, 1]], "sped": 2}"#);
    assert!(
        matches!(&e, WorldError::UnknownKey { key } if key == "sped"),
        "{e}"
    );
    let e = refused(r#"{"walls": [[[0, 0], [1, 0]]], "waypoints": [[0, 1], [1, 1, 2]]}"#);
    assert!(
        matches!(&e, WorldError::WrongType { path, .. } if path == "waypoints[1]"),
        "{e}"
    );
    let e = refused(r#"{"walls": [[[0, 0], [1, "a"]]], "waypoints": [[0, 1], [1, 1]]}"#);
    assert!(
        matches!(&e, WorldError::WrongType { path, .. } if path == "walls[0][1][1]"),
        "{e}"
    );
    let e = refused(r#"{"walls": [[[0, 0], [1, 0]]], "waypoints": [[0, 1]]}"#);
    assert!(matches!(e, WorldError::TooFewWaypoints { count: 1 }), "{e}");
    let e = refused(r#"{"walls": [], "waypoints": [[0, 1], [1, 1]]}"#);
    assert!(matches!(e, WorldError::NoWalls), "{e}");
    let e = refused(r#"{"walls": [[[0, 0], [1, 0]], [[5, 5]]], "waypoints": [[0, 1], [1, 1]]}"#);
    assert!(
        matches!(
            e,
            WorldError::ShortWall {
                index: 1,
                points: 1
            }
        ),
        "{e}"
    );
    let e = refused(r#"{"walls": [[[0, 0], [1, 0], [1, 0]]], "waypoints": [[0, 1], [1, 1]]}"#);
    assert!(
        matches!(&e, WorldError::ZeroLengthSegment { path } if path == "walls[0][2]"),
        "{e}"
    );
    for speed in ["0", "-1.5"] {
        let text = format!(
            r#"{{"walls": [[[0, 0], [1, 0]]], "waypoints": [[0, 1], [1, 1]], "speed": {speed}}}"#
        );
        assert!(matches!(
            refused(&text),
            WorldError::NonPositiveSpeed { .. }
        ));
    }
    // JSON cannot spell a non-finite number; worlds built in code are checked the same way.
    let mut w = World::from_json_str(VALID).unwrap_or_else(|e| panic!("{e}"));
    w.walls[0][2][1] = f64::NAN;
    let e = w.validate().err();
    assert!(
        matches!(&e, Some(WorldError::NonFinite { path, .. }) if path == "walls[0][2][1]"),
        "{e:?}"
    );
    w.walls[0][2][1] = 3.0;
    w.speed = f64::INFINITY;
    assert!(matches!(w.validate(), Err(WorldError::NonFinite { path, .. }) if path == "speed"));
    let e = World::resolve("/nonexistent/world.json").err();
    assert!(matches!(e, Some(WorldError::Read(_))), "{e:?}");
    assert!(matches!(
        World::builtin("hal"),
        Err(WorldError::UnknownBuiltin { .. })
    ));
}

/// Smallest distance between the waypoint path and any wall.
fn path_clearance(w: &World) -> f64 {
    let walls: Vec<Segment> = w.segments().map(|[a, b]| Segment::new(a, b)).collect();
    w.waypoints
        .windows(2)
        .map(|p| Segment::new(p[0], p[1]))
        .flat_map(|p| walls.iter().map(move |s| p.distance_to_segment(s)))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn builtin_worlds_are_valid_and_their_paths_keep_clear_of_walls() {
    for name in BUILTIN_WORLDS {
        let w = World::resolve(name).unwrap_or_else(|e| panic!("{e}"));
        w.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        let clearance = path_clearance(&w);
        println!(
            "{name}: {} wall segments in {} polygons, {} true corners, path {:.1} m, clearance {clearance:.2} m",
            w.segments().count(),
            w.walls.len(),
            w.true_corners().len(),
            w.path_length()
        );
        assert!(
            clearance >= 0.5,
            "{name}: the path comes within {clearance} m of a wall"
        );
        assert!(
            w.walls.iter().all(|p| p.first() == p.last()),
            "{name}: closed outlines"
        );
    }
    let office = World::builtin("office").unwrap_or_else(|e| panic!("{e}"));
    assert!(office.path_length() >= 100.0);
    assert_eq!(
        office.waypoints.first(),
        office.waypoints.last(),
        "the office path is a loop"
    );
    assert!(World::builtin("hall").is_ok_and(|w| w.path_length() >= 50.0));
}
