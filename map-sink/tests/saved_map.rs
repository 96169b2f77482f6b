//! The saved map: the conventions of the files map-sink writes (image rows, origin) and the
//! loader's refusal of directories that are not a whole map.

use std::fs;
use std::path::{Path, PathBuf};

use map_sink::{CellState, CompactScan, GridConfig, MapCorner, OccupancyGrid, Pose2, write_map};
use saved_map::{LANDMARKS_FILE, MAP_PGM_FILE, MAP_YAML_FILE, MapLoadError, SavedMap};

type TestResult = Result<(), Box<dyn std::error::Error>>;

/// A fresh directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("map-sink-saved-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    let _ = fs::create_dir_all(&dir);
    dir
}

/// A sensor at (0.3, 0.3) looking up (+y) at a wall 1 m away, 20 times: the wall is the
/// only occupied row, above the free space, in a grid of 0.1 m cells.
fn wall_above() -> Result<OccupancyGrid, Box<dyn std::error::Error>> {
    let ranges: Vec<f32> = (0..21)
        .map(|i| {
            let bearing = -0.2 + 0.02 * f64::from(i);
            (1.0 / bearing.cos()) as f32
        })
        .collect();
    let scan = CompactScan::new(-0.2, 0.02, 0.1, 30.0, &ranges, 0.0, 5.0);
    let pose = Pose2::new(0.33, 0.33, std::f64::consts::FRAC_PI_2);
    let scans: Vec<(Pose2, &CompactScan)> = (0..20).map(|_| (pose, &scan)).collect();
    let config = GridConfig {
        resolution_m: 0.1,
        ..GridConfig::default()
    };
    Ok(OccupancyGrid::build(&config, &scans)?.ok_or("no grid")?)
}

fn corner() -> MapCorner {
    let covariance = nalgebra::Matrix4::identity() * 1e-4;
    MapCorner {
        x: 1.0,
        y: 2.0,
        heading: 0.5,
        angle: 1.2,
        covariance,
        observations: 3,
    }
}

/// Writes a map of [`wall_above`] with one corner into a fresh directory.
fn saved(name: &str) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let dir = scratch(name);
    write_map(&dir, Some(&wall_above()?), &[corner()])?;
    Ok(dir)
}

/// A map [`saved`] and then spoiled in one place: `from` replaced by `to` in `file`.
fn spoiled(
    name: &str,
    file: &str,
    from: &str,
    to: &str,
) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let dir = saved(name)?;
    let text = fs::read_to_string(dir.join(file))?;
    assert!(text.contains(from), "{from:?} not in {file}");
    fs::write(dir.join(file), text.replace(from, to))?;
    Ok(dir)
}

#[test]
fn the_image_starts_with_the_largest_y_and_the_origin_is_the_lower_left_corner() -> TestResult {
    let grid = wall_above()?;
    let dir = scratch("conventions");
    write_map(&dir, Some(&grid), &[])?;
    let yaml = fs::read_to_string(dir.join(MAP_YAML_FILE))?;
    // The cells are aligned to multiples of 0.1 m: the lowest is the sensor's (y 0.3-0.4),
    // the wall's end points (x from about 0.13 to 0.53) bound the columns.
    assert!(yaml.contains("origin: [0.1, 0.3, 0]\n"), "{yaml}");
    assert!(yaml.contains("resolution: 0.1\n"), "{yaml}");
    let pgm = fs::read(dir.join(MAP_PGM_FILE))?;
    let header = format!("P5\n{} {}\n255\n", grid.width(), grid.height());
    assert!(pgm.starts_with(header.as_bytes()));
    let pixels = &pgm[header.len()..];
    let w = grid.width();
    let rows: Vec<&[u8]> = pixels.chunks(w).collect();
    assert_eq!(rows.len(), grid.height());
    // The wall at y = 1.33 is in the top row of the image, the sensor's free cell (0.3, 0.3)
    // in the bottom row, column 2 counted from the origin's x of 0.1.
    assert!(rows[0].contains(&0), "top row {:?}", rows[0]);
    assert!(!rows[rows.len() - 1].contains(&0));
    assert_eq!(rows[rows.len() - 1][2], 254, "{:?}", rows[rows.len() - 1]);
    assert_eq!(grid.state(2, grid.height() - 1), CellState::Occupied);
    // map_server's reading puts the wall back at the top: y = origin + (row + 0.5) * res.
    let top_y = 0.3 + (grid.height() as f64 - 0.5) * 0.1;
    assert!((top_y - 1.35).abs() < 1e-9, "{top_y}");
    Ok(())
}

#[test]
fn a_saved_map_loads_with_its_grid_and_landmarks() -> TestResult {
    let dir = saved("whole")?;
    let map = SavedMap::load(&dir)?;
    assert_eq!(map.landmarks.map_corners(), [corner()]);
    let grid = map.grid.ok_or("no grid")?;
    let built = wall_above()?;
    assert_eq!((grid.width, grid.height), (built.width(), built.height()));
    for row in 0..grid.height {
        for col in 0..grid.width {
            assert_eq!(
                grid.state(col, row),
                built.state(col, row),
                "({col}, {row})"
            );
        }
    }
    assert_eq!(grid.yaml.origin, [0.1, 0.3, 0.0]);
    Ok(())
}

fn refusal(dir: &Path) -> MapLoadError {
    match SavedMap::load(dir) {
        Ok(_) => panic!("{} loaded", dir.display()),
        Err(e) => e,
    }
}

#[test]
fn a_missing_file_is_named() -> TestResult {
    let empty = scratch("empty");
    let e = refusal(&empty);
    assert!(matches!(&e, MapLoadError::Missing { path } if path.ends_with(LANDMARKS_FILE)));
    assert!(e.to_string().contains("not a saved map"), "{e}");
    for file in [MAP_YAML_FILE, MAP_PGM_FILE] {
        let dir = saved(&format!("missing-{file}"))?;
        fs::remove_file(dir.join(file))?;
        assert!(
            matches!(refusal(&dir), MapLoadError::Missing { path } if path.ends_with(file)),
            "{file}"
        );
    }
    Ok(())
}

#[test]
fn a_truncated_file_is_named() -> TestResult {
    for file in [LANDMARKS_FILE, MAP_PGM_FILE] {
        let dir = saved(&format!("truncated-{file}"))?;
        let bytes = fs::read(dir.join(file))?;
        fs::write(dir.join(file), &bytes[..bytes.len() - 7])?;
        let e = refusal(&dir);
        assert!(
            matches!(&e, MapLoadError::Truncated { path, .. } if path.ends_with(file)),
            "{file}: {e}"
        );
        assert!(e.to_string().contains("truncated"), "{e}");
    }
    Ok(())
}

#[test]
fn a_foreign_file_is_named() -> TestResult {
    let cases: [(&str, &[u8]); 4] = [
        (LANDMARKS_FILE, b"{\"type\": \"FeatureCollection\"}"),
        (LANDMARKS_FILE, b"x,y,heading,angle\n1,2,3,4\n"),
        (MAP_YAML_FILE, b"walls: 3\nspeed: 1\n"),
        (MAP_PGM_FILE, b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"),
    ];
    for (i, (file, content)) in cases.into_iter().enumerate() {
        let dir = saved(&format!("foreign-{i}"))?;
        fs::write(dir.join(file), content)?;
        let e = refusal(&dir);
        assert!(
            matches!(&e, MapLoadError::Foreign { path, .. } if path.ends_with(file)),
            "{file}: {e}"
        );
    }
    let e = refusal(&spoiled(
        "newer",
        LANDMARKS_FILE,
        "\"version\": 1",
        "\"version\": 7",
    )?);
    assert!(matches!(e, MapLoadError::Version { .. }), "{e}");
    assert!(e.to_string().contains("version 7"), "{e}");
    Ok(())
}

#[test]
fn an_image_that_does_not_match_is_refused() -> TestResult {
    // Another run's image of another size in place of this one's.
    let dir = saved("other-size")?;
    let other = format!("P5\n3 2\n255\n{}", "\u{0}".repeat(6));
    fs::write(dir.join(MAP_PGM_FILE), other)?;
    let e = refusal(&dir);
    assert!(
        matches!(&e, MapLoadError::ImageMismatch { path, .. } if path.ends_with(MAP_PGM_FILE)),
        "{e}"
    );
    assert!(e.to_string().contains("3 x 2 pixels"), "{e}");
    // A description naming another image than the one the landmarks record.
    let dir = spoiled(
        "other-name",
        MAP_YAML_FILE,
        "image: map.pgm",
        "image: old.pgm",
    )?;
    fs::copy(dir.join(MAP_PGM_FILE), dir.join("old.pgm"))?;
    assert!(matches!(refusal(&dir), MapLoadError::ImageMismatch { .. }));
    // A description at another resolution than the landmarks record.
    let dir = spoiled(
        "other-resolution",
        MAP_YAML_FILE,
        "resolution: 0.1",
        "resolution: 0.05",
    )?;
    assert!(matches!(refusal(&dir), MapLoadError::ImageMismatch { .. }));
    Ok(())
}
