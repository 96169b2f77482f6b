//! A whole run through the recorder: the files it leaves and what is in them.

mod common;

use std::fs;
use std::path::Path;

use common::Synthetic;
use map_sink::{
    CellState, GridConfig, MAP_CORNERS_FILE, MAP_SVG_FILE, Pose2, Recorder, RecorderOptions,
    SinkError, StampedPose, corners_csv_header,
};
use saved_map::{MAP_PNG_FILE, SavedMap};
use slam_eval::{
    FrameCounts, GROUND_TRUTH_FILE, METRICS_FILE, Metrics, RelationsFile, TRAJECTORY_FILE,
    TRAJECTORY_ONLINE_FILE, score_run,
};
use slam_geom::{format_stamp, read_tum};

type TestResult = Result<(), Box<dyn std::error::Error>>;

const BASE_KEYS: [&str; 10] = [
    "frames_published",
    "frames_processed",
    "frames_dropped",
    "path_length_m",
    "map_corners",
    "wall_s",
    "duration_s",
    "scans_per_s",
    "latency_ms_p50",
    "latency_ms_p99",
];
const TRUTH_KEYS: [&str; 6] = [
    "ate_rmse_m",
    "ate_max_m",
    "final_error_m",
    "map_corner_rmse_m",
    "dead_reckoning_ate_rmse_m",
    "online_ate_rmse_m",
];

/// The keys of the metrics file, in the order they appear in the text.
fn keys_in_order(json: &str) -> Result<Vec<String>, Box<dyn std::error::Error>> {
    let value: serde_json::Value = serde_json::from_str(json)?;
    let object = value.as_object().ok_or("metrics.json is not an object")?;
    let mut keys: Vec<(usize, String)> = object
        .keys()
        .map(|k| {
            (
                json.find(&format!("\"{k}\":")).unwrap_or(usize::MAX),
                k.clone(),
            )
        })
        .collect();
    keys.sort();
    Ok(keys.into_iter().map(|(_, k)| k).collect())
}

/// Proves the picture is well-formed XML with an `svg` root, and counts its elements.
fn check_svg(svg: &str) -> Result<usize, Box<dyn std::error::Error>> {
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(80)]);
    let doc = roxmltree::Document::parse(svg)?;
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    Ok(doc.descendants().filter(|n| n.is_element()).count())
}

fn no_tmp_files(dir: &Path) -> TestResult {
    for entry in fs::read_dir(dir)? {
        let name = entry?.file_name();
        assert!(
            !name.to_string_lossy().ends_with(".tmp"),
            "left behind: {name:?}"
        );
    }
    Ok(())
}

#[test]
fn full_run_writes_every_file() -> TestResult {
    let run = Synthetic::lap(200, 361);
    let (dir, mut recorder) = common::driven_recorder("full-run", RecorderOptions::default(), run)?;
    recorder.set_counts(FrameCounts {
        published: 205,
        processed: 200,
        dropped: 5,
    });
    let metrics = recorder.finish()?;

    assert_eq!(read_tum(&dir.join(TRAJECTORY_FILE))?.len(), 200);
    assert_eq!(read_tum(&dir.join(GROUND_TRUTH_FILE))?.len(), 200);
    assert_eq!(read_tum(&dir.join("dead_reckoning.tum"))?.len(), 200);
    no_tmp_files(&dir)?;

    let csv = fs::read_to_string(dir.join(MAP_CORNERS_FILE))?;
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "x,y,heading,angle,cov_xx,cov_xy,cov_xh,cov_xa,cov_yy,cov_yh,cov_ya,cov_hh,cov_ha,cov_aa,observations"
        )
    );
    assert_eq!(corners_csv_header().split(',').count(), 15);
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), common::World::new().corners.len());
    assert!(rows.iter().all(|r| r.split(',').count() == 15));

    // The run's directory is a map: the landmarks and the grid traced from its scans.
    let map = SavedMap::load(&dir)?;
    assert_eq!(map.landmarks.corners.len(), rows.len());
    let grid = map.grid.ok_or("no grid")?;
    assert!(grid.cells.contains(&CellState::Occupied));
    assert!(dir.join(MAP_PNG_FILE).is_file());

    let json = fs::read_to_string(dir.join(METRICS_FILE))?;
    let expected: Vec<&str> = BASE_KEYS.iter().chain(&TRUTH_KEYS).copied().collect();
    assert_eq!(keys_in_order(&json)?, expected);
    assert_eq!((metrics.frames_published, metrics.frames_dropped), (205, 5));
    let ate = metrics.ate_rmse_m.ok_or("no ATE")?;
    assert!(ate > 0.005 && ate < 0.06, "ATE {ate}");
    let corners = metrics.map_corner_rmse_m.ok_or("no corner RMSE")?;
    assert!(corners < 0.1, "corner RMSE {corners}");
    let dr = metrics
        .dead_reckoning_ate_rmse_m
        .ok_or("no dead-reckoning ATE")?;
    assert!(dr > 2.0 * ate, "dead reckoning {dr} vs {ate}");
    // An ellipse of semi-axes 5 and 3.2 is about 26 m round.
    assert!(
        (metrics.path_length_m - 26.0).abs() < 1.5,
        "{}",
        metrics.path_length_m
    );
    let p50 = metrics.latency_ms_p50.ok_or("no latency")?;
    assert!((2.0..5.0).contains(&p50));

    let svg = fs::read_to_string(dir.join(MAP_SVG_FILE))?;
    assert!(check_svg(&svg)? > 20);
    assert_eq!(
        svg.matches("<polyline").count(),
        3,
        "estimate, truth, dead reckoning"
    );
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

/// Relations between the true poses `step` scans apart, as a relations file would give
/// them (`t1 t2 x y z roll pitch yaw`), plus one whose second stamp no run has.
fn relations_from_truth(truth: &Path, step: usize) -> Result<String, Box<dyn std::error::Error>> {
    let poses = read_tum(truth)?;
    let mut text = String::from("# t1 t2 x y z roll pitch yaw\n");
    for ((_, a), (_, b)) in poses.iter().zip(poses.iter().skip(step)) {
        let (pa, pb) = (
            Pose2::new(a.position[0], a.position[1], a.yaw()),
            Pose2::new(b.position[0], b.position[1], b.yaw()),
        );
        let delta = pa.between(&pb);
        text.push_str(&format!(
            "{} {} {} {} 0 0 0 {}\n",
            format_stamp(a.stamp_ns),
            format_stamp(b.stamp_ns),
            delta.x,
            delta.y,
            delta.yaw
        ));
    }
    text.push_str(&format!(
        "{} 1.5 1 0 0 0 0 0\n",
        format_stamp(poses[0].1.stamp_ns)
    ));
    Ok(text)
}

#[test]
fn relations_score_every_trajectory_file() -> TestResult {
    let run = || Synthetic::lap(200, 181);
    // A first run gives the true poses the relations are made of.
    let (truth_dir, recorder) =
        common::driven_recorder("relations-truth", RecorderOptions::default(), run())?;
    recorder.finish()?;
    let relations_path = truth_dir.join("truth.relations");
    fs::write(
        &relations_path,
        relations_from_truth(&truth_dir.join(GROUND_TRUTH_FILE), 5)?,
    )?;

    let options = RecorderOptions {
        relations: Some(RelationsFile::read(&relations_path)?),
        ..RecorderOptions::default()
    };
    let (dir, recorder) = common::driven_recorder("relations", options, run())?;
    let metrics = recorder.finish()?;

    let rpe = metrics.relative_pose_error.clone().ok_or("no score")?;
    assert_eq!(rpe.relations_file, relations_path);
    let estimate = rpe.trajectory.ok_or("trajectory not scored")?;
    assert_eq!(
        (estimate.relations, estimate.used, estimate.unmatched),
        (196, 195, 1)
    );
    // The estimate wobbles by centimetres around the truth in the robot's frame, which
    // turns by 9 degrees over the 5 scans of a relation: errors of about 2 cm.
    let t = estimate.errors.ok_or("no errors")?.translation_m;
    assert!(t.mean > 0.005 && t.mean < 0.05, "{t:?}");
    let dead_reckoning = rpe.dead_reckoning.ok_or("dead reckoning not scored")?;
    let r = dead_reckoning.errors.ok_or("no errors")?.rotation_deg;
    // 0.12 rad over 200 scans: 0.003 rad = 0.17 degrees every 5 scans, beside the wobble.
    assert!((r.mean - 0.17).abs() < 0.05, "{r:?}");
    // Without a final path from the filter, the final trajectory is the online one.
    assert_eq!(rpe.trajectory_online, rpe.trajectory);

    // metrics.json reads back typed, and the picture says it.
    let json = fs::read_to_string(dir.join(METRICS_FILE))?;
    let back = serde_json::from_str::<Metrics>(&json)?
        .relative_pose_error
        .and_then(|rpe| rpe.trajectory)
        .ok_or("no score in metrics.json")?;
    assert_eq!(back.used, estimate.used);
    let back_t = back
        .errors
        .ok_or("no errors in metrics.json")?
        .translation_m;
    assert!((back_t.mean - t.mean).abs() < 1e-12);
    let svg = fs::read_to_string(dir.join(MAP_SVG_FILE))?;
    check_svg(&svg)?;
    let line = format!(
        "relative pose error: estimate {:.3} +- {:.3} m",
        t.mean, t.std
    );
    assert!(svg.contains(&line), "{line} not in the picture");

    // Scoring the directory again gives the same.
    let options = RelationsFile::read(&relations_path)?;
    let again = score_run(&dir, &options, slam_eval_tolerance())?;
    assert_eq!(again.trajectory, rpe.trajectory);
    let _ = fs::remove_dir_all(&dir);
    let _ = fs::remove_dir_all(&truth_dir);
    Ok(())
}

/// The tolerance map-sink uses by default.
fn slam_eval_tolerance() -> u64 {
    RecorderOptions::default().relations_tolerance_ns
}

#[test]
fn a_bad_relations_file_names_its_line() -> TestResult {
    let dir = common::scratch_dir("bad-relations");
    fs::create_dir_all(&dir)?;
    let path = dir.join("bad.relations");
    fs::write(&path, "1.0 2.0 1 0 0 0 0 0\n1.0 2.0 1 0 0 0 0\n")?;
    let error = RelationsFile::read(&path).err().ok_or("accepted")?;
    assert!(
        error
            .to_string()
            .ends_with("bad.relations, line 2: 7 fields, expected 8 (t1 t2 x y z roll pitch yaw)"),
        "{error}"
    );
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn run_without_truth_has_no_truth_keys() -> TestResult {
    let run = Synthetic {
        truth: false,
        dead_reckoning: false,
        ..Synthetic::lap(60, 181)
    };
    let (dir, recorder) = common::driven_recorder("no-truth", RecorderOptions::default(), run)?;
    let metrics = recorder.finish()?;
    let json = fs::read_to_string(dir.join(METRICS_FILE))?;
    assert_eq!(keys_in_order(&json)?, BASE_KEYS);
    assert!(metrics.ate_rmse_m.is_none() && metrics.map_corner_rmse_m.is_none());
    // Derived counts: every scan got its pose.
    assert_eq!(
        (
            metrics.frames_published,
            metrics.frames_processed,
            metrics.frames_dropped
        ),
        (60, 60, 0)
    );
    assert!(!dir.join(GROUND_TRUTH_FILE).exists());
    let svg = fs::read_to_string(dir.join(MAP_SVG_FILE))?;
    check_svg(&svg)?;
    assert!(svg.contains("no ground truth"));
    no_tmp_files(&dir)?;
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn empty_run_still_finishes() -> TestResult {
    let dir = common::scratch_dir("empty");
    let metrics = Recorder::create(&dir, RecorderOptions::default())?.finish()?;
    assert_eq!(metrics.frames_processed, 0);
    assert_eq!(metrics.scans_per_s, None);
    let json = fs::read_to_string(dir.join(METRICS_FILE))?;
    assert!(json.contains("\"latency_ms_p50\": null"), "{json}");
    check_svg(&fs::read_to_string(dir.join(MAP_SVG_FILE))?)?;
    assert_eq!(
        fs::read_to_string(dir.join(MAP_CORNERS_FILE))?
            .lines()
            .count(),
        1
    );
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

/// `trajectory.tum` holds `poses`, in order.
fn assert_trajectory_is(dir: &Path, poses: &[Pose2]) -> TestResult {
    let written = read_tum(&dir.join(TRAJECTORY_FILE))?;
    assert_eq!(written.len(), poses.len());
    assert!(written.iter().zip(poses).all(
        |((_, w), p)| (w.position[0] - p.x).abs() < 1e-9 && (w.position[1] - p.y).abs() < 1e-9
    ));
    Ok(())
}

#[test]
fn the_final_path_becomes_the_trajectory_and_is_scored() -> TestResult {
    let dir = common::scratch_dir("final-path");
    let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
    let (mut truth, mut path) = (Vec::new(), Vec::new());
    for seq in 0..50_u64 {
        let stamp_ns = 1_000_000_000 + seq * 25_000_000;
        let pose = Pose2::new(0.1 * seq as f64, 0.02 * seq as f64, 0.01 * seq as f64);
        recorder.record_truth(stamp_ns, pose)?;
        // The online estimate is off by a wobble; the final path is exact.
        let wobble = if seq % 2 == 0 { 0.05 } else { -0.05 };
        let online = Pose2::new(pose.x, pose.y + wobble, pose.yaw);
        recorder.record_pose(seq, stamp_ns, online, None, None)?;
        truth.push(pose);
        path.push(StampedPose { stamp_ns, pose });
    }
    recorder.set_final_path(path.clone());
    let metrics = recorder.finish()?;

    assert_trajectory_is(&dir, &truth)?;
    assert_eq!(read_tum(&dir.join(TRAJECTORY_ONLINE_FILE))?.len(), 50);
    let ate = metrics.ate_rmse_m.ok_or("no ATE")?;
    let online = metrics.online_ate_rmse_m.ok_or("no online ATE")?;
    assert!(ate < 1e-9, "the final path is the truth: {ate}");
    assert!(online > 0.01, "the online estimate wobbles: {online}");
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn a_path_too_wide_for_a_grid_is_written_with_its_numbers_and_landmarks() -> TestResult {
    let dir = common::scratch_dir("too-wide");
    let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
    // Two scans 4 km apart: their grid would have 80 000 x 80 000 cells of 0.05 m, so it
    // cannot be traced.
    let poses = [Pose2::new(0.0, 0.0, 0.0), Pose2::new(4000.0, 4000.0, 0.5)];
    let path: Vec<StampedPose> = poses
        .iter()
        .zip([1_000_000_000, 1_100_000_000])
        .map(|(&pose, stamp_ns)| StampedPose { stamp_ns, pose })
        .collect();
    for (seq, p) in (0_u64..).zip(&path) {
        recorder.record_scan(seq, -1.0, 0.5, 0.1, 30.0, &[2.0, 2.1, 2.2, 2.3, 2.2]);
        recorder.record_pose(seq, p.stamp_ns, p.pose, None, None)?;
    }
    recorder.set_final_path(path.clone());
    let result = recorder.finish();
    assert!(matches!(result, Err(SinkError::Grid(_))), "{result:?}");
    // What a run killed while its grid is made leaves too: the path, the corners, a
    // landmark map without a grid and the numbers, each whole, and nothing half written.
    assert_trajectory_is(&dir, &poses)?;
    let metrics: Metrics = serde_json::from_str(&fs::read_to_string(dir.join(METRICS_FILE))?)?;
    assert_eq!(metrics.frames_processed, 2);
    assert!(SavedMap::load(&dir)?.grid.is_none());
    assert_eq!(
        fs::read_to_string(dir.join(MAP_CORNERS_FILE))?
            .lines()
            .count(),
        1
    );
    assert!(!dir.join(MAP_PNG_FILE).exists() && !dir.join(MAP_SVG_FILE).exists());
    no_tmp_files(&dir)?;
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn killed_run_keeps_its_trajectory_and_no_stale_results() -> TestResult {
    let dir = common::scratch_dir("killed");
    fs::create_dir_all(&dir)?;
    fs::write(dir.join(METRICS_FILE), "{}")?;
    fs::write(dir.join(GROUND_TRUTH_FILE), "1.0 0 0 0 0 0 0 1\n")?;
    let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
    assert!(!dir.join(METRICS_FILE).exists() && !dir.join(GROUND_TRUTH_FILE).exists());
    for seq in 0..25_u64 {
        // Each pose's scan first, as a source publishes it before the pose is made.
        recorder.record_scan(seq, -1.0, 0.5, 0.1, 30.0, &[2.0, 2.1, 2.2, 2.3, 2.2]);
        recorder.record_pose(
            seq,
            seq * 1_000_000,
            Pose2::new(seq as f64, 0.0, 0.1),
            None,
            None,
        )?;
    }
    // Read while the recorder is alive: every line of the online estimate is already in
    // its file; the final trajectory is only written by a run that finishes.
    assert_eq!(read_tum(&dir.join(TRAJECTORY_ONLINE_FILE))?.len(), 25);
    drop(recorder);
    assert_eq!(read_tum(&dir.join(TRAJECTORY_ONLINE_FILE))?.len(), 25);
    assert!(!dir.join(TRAJECTORY_FILE).exists());
    assert!(!dir.join(METRICS_FILE).exists());
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn invalid_grid_settings_are_refused() {
    let dir = common::scratch_dir("invalid");
    for (resolution_m, no_return_reach_m) in [
        (0.0, 5.0),
        (f64::NAN, 5.0),
        (0.001, 5.0),
        (20.0, 5.0),
        (0.05, 0.0),
        (0.05, f64::INFINITY),
    ] {
        let options = RecorderOptions {
            grid: GridConfig {
                resolution_m,
                no_return_reach_m,
            },
            ..RecorderOptions::default()
        };
        assert!(
            matches!(
                Recorder::create(&dir, options),
                Err(SinkError::InvalidOption(_))
            ),
            "{resolution_m} m, reach {no_return_reach_m} m"
        );
    }
}

/// A run of the size the pipeline produces (1200 scans of 1081 beams). Set
/// `MAP_SINK_EXAMPLE_SVG=/some/path.svg` to keep its picture for a look.
#[test]
fn example_picture_of_a_full_run() -> TestResult {
    let options = RecorderOptions {
        title: "map-sink example: synthetic room, one lap around the pillar".to_owned(),
        ..RecorderOptions::default()
    };
    let run = Synthetic::lap(1200, 1081);
    let (dir, mut recorder) = common::driven_recorder("example", options, run)?;
    recorder.set_counts(FrameCounts {
        published: 1203,
        processed: 1200,
        dropped: 3,
    });
    recorder.set_wall_time(121.5);
    let metrics = recorder.finish()?;
    assert!((metrics.scans_per_s.unwrap_or(0.0) - 1200.0 / 121.5).abs() < 1e-9);
    let svg = fs::read_to_string(dir.join(MAP_SVG_FILE))?;
    assert!(svg.len() < 5_000_000, "{} bytes", svg.len());
    check_svg(&svg)?;
    if let Some(path) = std::env::var_os("MAP_SINK_EXAMPLE_SVG") {
        fs::write(path, &svg)?;
    }
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

/// A localization of `scans` scans on the synthetic lap that searches 5 m off the truth
/// until scan `converged`, then follows it exactly.
fn localized_run(
    name: &str,
    scans: usize,
    converged: u64,
) -> Result<(std::path::PathBuf, Metrics), Box<dyn std::error::Error>> {
    let dir = common::scratch_dir(name);
    let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
    for i in 0..scans {
        let seq = i as u64;
        let stamp_ns = 1_700_000_000_000_000_000 + seq * 100_000_000;
        let truth = common::true_pose(i, scans);
        let estimate = if seq < converged {
            Pose2::new(truth.x + 5.0, truth.y - 1.0, truth.yaw)
        } else {
            truth
        };
        recorder.record_pose(seq, stamp_ns, estimate, Some(truth), None)?;
        recorder.record_truth(stamp_ns, truth)?;
        recorder.record_localization(seq, stamp_ns, seq >= converged);
    }
    let metrics = recorder.finish()?;
    Ok((dir, metrics))
}

#[test]
fn a_localization_is_scored_from_convergence_with_its_search_apart() -> TestResult {
    let (dir, metrics) = localized_run("localized", 200, 40)?;
    assert_eq!(metrics.converged_at_scan, Some(40));
    // From convergence on, the estimate is the truth.
    let ate = metrics.ate_rmse_m.ok_or("no ATE")?;
    assert!(ate < 1e-9, "ATE {ate}");
    assert!(metrics.online_ate_rmse_m.is_some_and(|a| a < 1e-9));
    // The search's poses, moved by that alignment, are 5.1 m off.
    let search = metrics.search_phase.ok_or("no search phase")?;
    assert_eq!(search.scans, 40);
    let off = search.ate_rmse_m.ok_or("no search ATE")?;
    assert!((off - 26f64.sqrt()).abs() < 1e-6, "{off}");
    let json = fs::read_to_string(dir.join(METRICS_FILE))?;
    assert!(json.contains("\"search_phase\""), "{json}");
    let _ = fs::remove_dir_all(&dir);

    // Never converged: nothing but the search to score, by its own alignment.
    let (dir, metrics) = localized_run("never-localized", 100, u64::MAX)?;
    assert_eq!(metrics.converged_at_scan, None);
    assert_eq!(metrics.ate_rmse_m, None);
    let search = metrics.search_phase.ok_or("no search phase")?;
    assert_eq!(search.scans, 100);
    assert!(search.ate_rmse_m.is_some_and(|a| a < 1e-6));
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn a_saved_grid_that_does_not_fit_the_scans_is_not_merged() -> TestResult {
    // A saved map 40 m away from the synthetic room, occupied throughout.
    let saved = saved_map::GridMap {
        yaml: saved_map::MapYaml::trinary("map.pgm", 0.05, [40.0, 40.0]),
        width: 40,
        height: 40,
        cells: vec![CellState::Occupied; 1600],
    };
    let extent = |dir: &Path| -> Result<[f64; 2], Box<dyn std::error::Error>> {
        let grid = SavedMap::load(dir)?.grid.ok_or("no grid")?;
        Ok([
            grid.yaml.origin[0] + grid.width as f64 * grid.yaml.resolution,
            grid.yaml.origin[1] + grid.height as f64 * grid.yaml.resolution,
        ])
    };
    for (fit, merged) in [
        (
            slam_eval::MapFit {
                beams_judged: 20_000,
                beams_explained: 19_000,
            },
            true,
        ),
        (
            slam_eval::MapFit {
                beams_judged: 20_000,
                beams_explained: 2_000,
            },
            false,
        ),
    ] {
        let (dir, mut recorder) = common::driven_recorder(
            &format!("fit-merged-{merged}"),
            RecorderOptions::default(),
            Synthetic::lap(60, 181),
        )?;
        recorder.map_on(&saved)?;
        recorder.set_map_fit(fit);
        assert_eq!(recorder.saved_grid_set_aside(), !merged);
        let metrics = recorder.finish()?;
        let summary = metrics.map_fit.ok_or("no map fit")?;
        assert_eq!(summary.verdict == slam_eval::FitVerdict::Fits, merged);
        // The saved grid reaches x = 42 m; the room alone, a few metres.
        let [x, y] = extent(&dir)?;
        assert_eq!(x > 41.9 && y > 41.9, merged, "{x}, {y}");
        let _ = fs::remove_dir_all(&dir);
    }
    Ok(())
}
