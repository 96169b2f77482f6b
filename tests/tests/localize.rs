//! Localization on a saved map and mapping on top of one, through `slam-launch` (issue 15):
//! map a run, then localize another run on its map from a known and from an unknown start,
//! and refuse a damaged map, or one of another building (issue 47).

use std::path::{Path, PathBuf};
use std::process::Output;

use tests::*;

/// Maps the whole office loop (seed 1): the map the office tests localize on.
fn office_map(tag: &str) -> PathBuf {
    launched(
        &format!("office-map-{tag}"),
        &["--world", "office", "--seed", "1", "--rate", "0"],
    )
    .out
}

/// Localizes the office loop of `seed` on `map`, from `initial_pose` or searching.
fn localize_office(map: &Path, seed: u64, initial_pose: Option<&str>, tag: &str) -> PathBuf {
    let seed = seed.to_string();
    let mut args = vec![
        "--world",
        "office",
        "--seed",
        &seed,
        "--rate",
        "0",
        "--map",
        map.to_str().unwrap(),
        "--localize",
    ];
    let pose_arg;
    if let Some(pose) = initial_pose {
        pose_arg = format!("--initial-pose={pose}");
        args.push(&pose_arg);
    }
    launched(&format!("office-localize-{tag}"), &args).out
}

/// The truth of a localization run, moved into the map's frame (the mapping run's first
/// true pose at the origin), against the run's trajectory.
fn office_gaps(map: &Path, run: &Path, from_convergence: bool) -> slam_eval::Gaps {
    localization_gaps(
        run,
        &run.join("ground_truth.tum"),
        &frame_of_first_pose(&map.join("ground_truth.tum")),
        from_convergence,
    )
}

#[test]
fn the_office_map_localizes_another_run_from_a_known_and_an_unknown_start() {
    let map = office_map("known-unknown");
    let landmarks = std::fs::read(map.join("landmarks.json")).unwrap();
    let grid = std::fs::read(map.join("map.pgm")).unwrap();

    // Another seed's run from the map's origin, where both runs start.
    let known = localize_office(&map, 2, Some("0,0,0"), "known");
    let gaps = office_gaps(&map, &known, false);
    eprintln!(
        "office seed 2, known start: {} poses, RMSE {:.4} m, max {:.4} m",
        gaps.matched, gaps.rmse_m, gaps.stats.max
    );
    assert!(gaps.matched > 3900, "{gaps:?}");
    // ATE as the project scores it (aligned, docs/CONVENTIONS.md): the acceptance's figure.
    let ate = metrics(&known)
        .ate_rmse_m
        .expect("metrics.json has ate_rmse_m");
    eprintln!("office seed 2, known start: ATE RMSE {ate:.4} m");
    assert!(ate <= 0.03, "ATE {ate} m");
    // Unaligned, in the map's frame, the map's own error counts too (the mapping run is
    // 0.018 m from its truth so): a looser bound.
    assert!(gaps.rmse_m <= 0.05, "{gaps:?}");
    assert_eq!(
        metrics(&known)
            .converged_at_scan
            .expect("metrics.json has converged_at_scan"),
        0
    );

    let unknown = localize_office(&map, 2, None, "unknown");
    let converged = metrics(&unknown)
        .converged_at_scan
        .expect("metrics.json has converged_at_scan");
    let gaps = office_gaps(&map, &unknown, true);
    eprintln!(
        "office seed 2, unknown start: converged at scan {converged}, then RMSE {:.4} m, max {:.4} m",
        gaps.rmse_m, gaps.stats.max
    );
    assert!(converged <= 200, "converged at scan {converged}");
    assert!(gaps.rmse_m <= 0.05, "{gaps:?}");

    // Localizing leaves the map as it was.
    assert_eq!(
        std::fs::read(map.join("landmarks.json")).unwrap(),
        landmarks
    );
    assert_eq!(std::fs::read(map.join("map.pgm")).unwrap(), grid);
}

/// The acceptance figures over seeds 1-5 (slow: ten runs); run with `--ignored`.
#[test]
#[ignore]
fn office_convergence_over_seeds() {
    let map = office_map("seeds");
    for seed in 1..=5 {
        let known = localize_office(&map, seed, Some("0,0,0"), &format!("known-{seed}"));
        let known_gaps = office_gaps(&map, &known, false);
        let unknown = localize_office(&map, seed, None, &format!("unknown-{seed}"));
        let converged = metrics(&unknown).converged_at_scan;
        let gaps = office_gaps(&map, &unknown, true);
        eprintln!(
            "seed {seed}: known start RMSE {:.4} m | unknown start converged at scan {converged:?}, then RMSE {:.4} m, max {:.4} m",
            known_gaps.rmse_m, gaps.rmse_m, gaps.stats.max
        );
    }
}

#[test]
fn mapping_on_a_saved_map_extends_its_landmarks() {
    // The first 1200 scans, then the whole loop on top of them.
    let first = launched(
        "office-first-part",
        &["--world", "office", "--frames", "1200", "--rate", "0"],
    )
    .out;
    let saved = read_map_corners(&first).len();
    let out = launched(
        "office-on-top",
        &[
            "--world",
            "office",
            "--seed",
            "2",
            "--rate",
            "0",
            "--map",
            first.to_str().unwrap(),
        ],
    )
    .out;
    let corners = read_map_corners(&out);
    assert!(corners.len() > saved + 40, "{saved} -> {}", corners.len());
    let duplicates = duplicate_corners(&corners, 0.5, 0.5);
    assert!(duplicates.is_empty(), "duplicated corners: {duplicates:?}");
    let ate = metrics(&out)
        .ate_rmse_m
        .expect("metrics.json has ate_rmse_m");
    assert!(ate < 0.05, "ATE {ate} m");
}

/// The rectangle a run's grid covers, `[x0, y0, x1, y1]` in its map frame, as map_server
/// reads `map.yaml` and `map.pgm`.
fn grid_extent(out: &Path) -> [f64; 4] {
    let yaml = tests::map_server::parse_yaml(
        &std::fs::read_to_string(out.join("map.yaml")).expect("map.yaml"),
    );
    let (width, height, _) =
        tests::map_server::parse_pgm(&std::fs::read(out.join(&yaml.image)).expect("map.pgm"));
    let [x, y, _] = yaml.origin;
    [
        x,
        y,
        x + width as f64 * yaml.resolution,
        y + height as f64 * yaml.resolution,
    ]
}

/// Issue 47, point 6: a map of another building is not believed. The office world
/// localized on the hall's map converges somewhere all the same; the share of its beams
/// the map explains says it does not fit, and the run fails naming it. The office's own map
/// explains nearly every beam, and that localization is scored from its convergence on.
/// Mapping the office on the hall's map warns and maps the office alone.
#[test]
fn a_map_of_another_building_is_refused_and_not_merged() {
    let hall = launched(
        "hall-map-misfit",
        &["--world", "hall", "--seed", "1", "--rate", "0"],
    )
    .out;
    let hall_arg = hall.to_str().unwrap();
    let office = office_map("misfit");
    let office_seed_2 = ["--world", "office", "--seed", "2", "--rate", "0"];

    let out = scratch("office-on-hall");
    let output = launch(
        &domain("office-on-hall"),
        &out,
        &[&office_seed_2[..], &["--map", hall_arg, "--localize"]].concat(),
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    let named = format!("the map in {hall_arg} does not fit this run's scans");
    assert!(stderr.contains(&named), "{stderr}");
    // Its results are written all the same, with the verdict.
    let fit = metrics(&out).map_fit.expect("metrics.json has map_fit");
    eprintln!("office on the hall's map: {fit:?}");
    assert_eq!(fit.verdict, slam_eval::FitVerdict::DoesNotFit);
    assert!(
        fit.explained_share.is_some_and(|share| share < 0.4),
        "{fit:?}"
    );

    // The office's own map: converged, believed, scored from convergence on.
    let right = localize_office(&office, 2, None, "misfit-right");
    let m = metrics(&right);
    let fit = m.map_fit.expect("metrics.json has map_fit");
    let converged = m.converged_at_scan.expect("converged");
    let search = m.search_phase.expect("metrics.json has search_phase");
    let ate = m.ate_rmse_m.expect("metrics.json has ate_rmse_m");
    eprintln!(
        "office on its own map: {fit:?}; converged at scan {converged}, then ATE {ate:.4} m, the search {:?} m",
        search.ate_rmse_m
    );
    assert_eq!(fit.verdict, slam_eval::FitVerdict::Fits);
    assert!(
        fit.explained_share.is_some_and(|share| share > 0.9),
        "{fit:?}"
    );
    assert_eq!(search.scans, converged);
    assert!(ate <= 0.05, "ATE {ate} m after convergence");

    // Mapping the office on the hall's map: a warning, and the office's map alone.
    let onto = scratch("office-onto-hall");
    let output = launch(
        &domain("office-onto-hall"),
        &onto,
        &[&office_seed_2[..], &["--map", hall_arg]].concat(),
    );
    assert_success(&output);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!(
            "warning: the saved map in {hall_arg} does not fit this run's scans"
        )) && stderr.contains("it was not merged"),
        "{stderr}"
    );
    let m = metrics(&onto);
    assert_eq!(
        m.map_fit.map(|fit| fit.verdict),
        Some(slam_eval::FitVerdict::DoesNotFit)
    );
    // Not the hall's corners beside the office's, nor its grid.
    let (alone, saved) = (
        read_map_corners(&office).len(),
        read_map_corners(&hall).len(),
    );
    let corners = read_map_corners(&onto).len();
    assert!(
        corners < alone + saved / 4,
        "{corners} corners; the office alone has {alone}, the hall {saved}"
    );
    let ([hx0, hy0, hx1, hy1], [x0, y0, x1, y1]) = (grid_extent(&hall), grid_extent(&onto));
    assert!(
        !(x0 <= hx0 && y0 <= hy0 && x1 >= hx1 && y1 >= hy1),
        "the grid {:?} covers the hall's {:?}",
        [x0, y0, x1, y1],
        [hx0, hy0, hx1, hy1]
    );
    let ate = m.ate_rmse_m.expect("metrics.json has ate_rmse_m");
    assert!(ate < 0.05, "ATE {ate} m");
}

fn refused(output: &Output, names: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "stderr:\n{stderr}");
    assert!(
        stderr.contains("refusing to start: cannot use the map in") && stderr.contains(names),
        "stderr does not name {names}:\n{stderr}"
    );
}

#[test]
fn a_damaged_map_is_refused_before_anything_starts() {
    let map = launched(
        "small-map",
        &["--world", "hall", "--frames", "100", "--rate", "0"],
    )
    .out;
    let try_map = |dir: &Path, tag: &str| {
        launch(
            &domain(tag),
            &scratch(tag),
            &[
                "--world",
                "hall",
                "--frames",
                "10",
                "--map",
                dir.to_str().unwrap(),
                "--localize",
            ],
        )
    };
    // Missing.
    refused(
        &try_map(&map.join("nothing-here"), "missing"),
        "landmarks.json",
    );
    // Truncated image.
    let damaged = scratch("damaged-map");
    for file in ["landmarks.json", "map.yaml", "map.pgm"] {
        std::fs::copy(map.join(file), damaged.join(file)).unwrap();
    }
    let pgm = std::fs::read(map.join("map.pgm")).unwrap();
    std::fs::write(damaged.join("map.pgm"), &pgm[..pgm.len() / 2]).unwrap();
    refused(&try_map(&damaged, "truncated"), "map.pgm");
    // A YAML whose image is another one.
    std::fs::copy(map.join("map.pgm"), damaged.join("map.pgm")).unwrap();
    let yaml = std::fs::read_to_string(map.join("map.yaml")).unwrap();
    std::fs::write(damaged.join("other.pgm"), &pgm).unwrap();
    std::fs::write(
        damaged.join("map.yaml"),
        yaml.replace("map.pgm", "other.pgm"),
    )
    .unwrap();
    refused(&try_map(&damaged, "mismatch"), "other.pgm");
    // Foreign landmarks.
    std::fs::write(
        damaged.join("landmarks.json"),
        "{\"format\": \"something-else\"}",
    )
    .unwrap();
    refused(&try_map(&damaged, "foreign"), "landmarks.json");
    // A bad initial pose is named too.
    let output = launch(
        &domain("bad-pose"),
        &scratch("bad-pose"),
        &[
            "--world",
            "hall",
            "--map",
            map.to_str().unwrap(),
            "--localize",
            "--initial-pose",
            "1,2",
        ],
    );
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("--initial-pose"));
}

#[test]
fn aces_mapped_again_on_its_own_map_stays_in_the_map_frame() {
    // Seed 1 maps aces; seed 3 maps it again on that map. Its particles climb the saved
    // grid at every corner update and search wider once back after a stretch off it: a
    // search that jumped to a neighbouring wall's basin (0.9 m and 12 degrees after 10 m
    // off the grid) once lost the run for good, 5.6 m from the saved path on average.
    let log = test_data::carmen_log("aces");
    let map = replayed("aces-first", &log, &["--rate", "0", "--seed", "1"]).out;
    let again = replayed(
        "aces-again",
        &log,
        &["--rate", "0", "--seed", "3", "--map", map.to_str().unwrap()],
    )
    .out;
    let gaps = localization_gaps(
        &again,
        &map.join("trajectory.tum"),
        &slam_eval::Pose::identity(),
        false,
    );
    let translation = metrics(&again)
        .relative_pose_error
        .and_then(|rpe| rpe.trajectory)
        .and_then(|score| score.errors)
        .expect("metrics.json scores trajectory.tum")
        .translation_m
        .mean;
    eprintln!(
        "aces seed 3 on seed 1's map: RPE {translation:.4} m, {} poses {:.3} m from the saved path on average, {:.3} m at most",
        gaps.matched, gaps.stats.mean, gaps.stats.max
    );
    // In the saved map's frame to centimetres, and as accurate as GMapping's published
    // figure for mapping the log from scratch.
    assert!(gaps.stats.mean <= 0.15, "{gaps:?}");
    assert!(gaps.stats.max <= 1.0, "{gaps:?}");
    assert!(translation <= 0.06, "RPE {translation} m");
}

#[test]
fn aces_is_localized_from_an_unknown_start_at_three_points_of_the_log() {
    let log = test_data::carmen_log("aces");
    let map = replayed("aces-map", &log, &["--rate", "0", "--seed", "1"]).out;
    for start in ["1000", "3000", "5000"] {
        let out = replayed(
            &format!("aces-from-{start}"),
            &log,
            &[
                "--rate",
                "0",
                "--map",
                map.to_str().unwrap(),
                "--localize",
                "--replay-start",
                start,
            ],
        )
        .out;
        let converged = metrics(&out)
            .converged_at_scan
            .expect("metrics.json has converged_at_scan");
        // The mapping run's path is in the map's frame already.
        let gaps = localization_gaps(
            &out,
            &map.join("trajectory.tum"),
            &slam_eval::Pose::identity(),
            true,
        );
        eprintln!(
            "aces from scan {start}: converged at scan {converged}, then {} poses, RMSE {:.3} m, mean {:.3} m, max {:.3} m, {:+.4} m ahead on average",
            gaps.matched, gaps.rmse_m, gaps.stats.mean, gaps.stats.max, gaps.along_track_m
        );
        assert!(converged <= 300, "converged at scan {converged}");
        // Converged in the right place (a wrong one is metres off) and then following the
        // mapping run's path. Where the map disagrees with its own path, the two paths part
        // by a decimetre or two for a while (docs/localization.md), which the RMSE allows
        // for; never by a third of a metre.
        assert!(gaps.rmse_m <= 0.06, "{gaps:?}");
        assert!(gaps.stats.mean <= 0.045, "{gaps:?}");
        assert!(gaps.stats.max <= 0.3, "{gaps:?}");
        // Scored by the wall faces its beams can reach, the localizer does not run ahead
        // of the mapping path (on every occupied cell it ran 1.4-2.1 cm ahead).
        assert!(gaps.along_track_m.abs() <= 0.012, "{gaps:?}");
    }
}
