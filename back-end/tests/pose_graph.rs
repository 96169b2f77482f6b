//! The pose graph on simulated drives: a square loop driven four times with drifting
//! steps and closures between its laps, some of them wrong.

use back_end::{ClosureId, PoseGraph, PoseGraphError, PoseGraphSettings};
use nalgebra::Matrix3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};
use slam_geom::{Pose2, wrap_angle};
use std::f64::consts::{FRAC_PI_2, PI};

/// Steps along one side of the square, 0.25 m each (a 10 m side).
const SIDE: usize = 40;
const LAP: usize = 4 * SIDE;
const LAPS: usize = 4;
/// The front end's step noise (standard deviations, metres and radians; the chain drifts
/// by metres over the four laps) and the closures', each as their information says.
const STEP_XY: f64 = 0.01;
const STEP_YAW: f64 = 0.015;
const CLOSURE_XY: f64 = 0.03;
const CLOSURE_YAW: f64 = 0.01;

fn diagonal_information(xy: f64, yaw: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&nalgebra::Vector3::new(
        1.0 / (xy * xy),
        1.0 / (xy * xy),
        1.0 / (yaw * yaw),
    ))
}

/// `pose` moved by zero-mean noise of the given deviations.
fn noisy(pose: Pose2, xy: f64, yaw: f64, rng: &mut StdRng) -> Pose2 {
    let unit = Normal::new(0.0, 1.0).expect("a valid normal");
    Pose2::new(
        pose.x + xy * unit.sample(rng),
        pose.y + xy * unit.sample(rng),
        pose.yaw + yaw * unit.sample(rng),
    )
}

/// A drive: the true poses, the steps as the front end measured them, and closures.
struct Drive {
    truth: Vec<Pose2>,
    steps: Vec<Pose2>,
    /// `(from, to, seen)`, all right.
    closures: Vec<(usize, usize, Pose2)>,
}

/// The square driven [`LAPS`] times from the origin, a closure every 10 poses of each lap
/// after the first to the same place on the lap before and on the first lap.
fn square_drive(seed: u64) -> Drive {
    let mut rng = StdRng::seed_from_u64(seed);
    let true_steps: Vec<Pose2> = (0..LAPS * LAP)
        .map(|k| {
            let turn = if (k + 1) % SIDE == 0 { FRAC_PI_2 } else { 0.0 };
            Pose2::new(0.25, 0.0, turn)
        })
        .collect();
    let truth = compose_all(Pose2::IDENTITY, &true_steps);
    let steps = true_steps
        .iter()
        .map(|s| noisy(*s, STEP_XY, STEP_YAW, &mut rng))
        .collect();
    let mut closures = Vec::new();
    for to in (LAP..truth.len()).step_by(10) {
        let mut froms = vec![to - LAP];
        if to >= 2 * LAP {
            froms.push(to % LAP);
        }
        for from in froms {
            let true_seen = truth[from].between(&truth[to]);
            let seen = noisy(true_seen, CLOSURE_XY, CLOSURE_YAW, &mut rng);
            closures.push((from, to, seen));
        }
    }
    Drive {
        truth,
        steps,
        closures,
    }
}

fn compose_all(first: Pose2, steps: &[Pose2]) -> Vec<Pose2> {
    let mut poses = vec![first];
    for step in steps {
        let last = poses[poses.len() - 1];
        poses.push(last.compose(step));
    }
    poses
}

/// The graph of the drive's steps, from `first`, without closures.
fn chain(first: Pose2, steps: &[Pose2]) -> PoseGraph {
    let mut graph = PoseGraph::new(first).expect("a finite pose");
    let information = diagonal_information(STEP_XY, STEP_YAW);
    for step in steps {
        graph.add_node(*step, information).expect("a valid step");
    }
    graph
}

fn add_closures(graph: &mut PoseGraph, drive: &Drive) -> Vec<ClosureId> {
    let information = diagonal_information(CLOSURE_XY, CLOSURE_YAW);
    drive
        .closures
        .iter()
        .map(|&(from, to, seen)| {
            graph
                .add_closure(from, to, seen, information)
                .expect("a valid closure")
        })
        .collect()
}

/// Mean and largest distance between the positions of two paths, metres.
fn position_errors(a: &[Pose2], b: &[Pose2]) -> (f64, f64) {
    let distances: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(p, q)| (p.position() - q.position()).norm())
        .collect();
    let largest = distances.iter().copied().fold(0.0, f64::max);
    (
        distances.iter().sum::<f64>() / distances.len() as f64,
        largest,
    )
}

/// The graph of a square drive with its right closures, optimized.
fn solved_square(drive: &Drive) -> (PoseGraph, Vec<ClosureId>) {
    let mut graph = chain(Pose2::IDENTITY, &drive.steps);
    let ids = add_closures(&mut graph, drive);
    let report = graph.optimize().expect("solvable");
    assert!(report.converged, "{report:?}");
    (graph, ids)
}

#[test]
fn a_chain_without_closures_stays_at_its_composed_steps() {
    let drive = square_drive(1);
    let first = Pose2::new(2.0, -1.0, 3.0);
    let mut graph = chain(first, &drive.steps);
    let composed = compose_all(first, &drive.steps);
    assert_eq!(graph.poses(), &composed[..]);
    let report = graph.optimize().expect("solvable");
    assert_eq!(graph.poses(), &composed[..]);
    assert!(report.converged);
    assert_eq!((report.accepted_closures, report.rejected_closures), (0, 0));
    assert!(report.final_cost < 1e-12, "{report:?}");
}

#[test]
fn right_closures_take_the_drift_out_of_a_square_driven_four_times() {
    let drive = square_drive(3);
    let drifted = compose_all(Pose2::IDENTITY, &drive.steps);
    let (before, before_largest) = position_errors(&drifted, &drive.truth);
    // The chain drifted by metres: a cold start.
    assert!(before_largest > 3.0, "{before_largest}");
    let (graph, ids) = solved_square(&drive);
    let (after, after_largest) = position_errors(graph.poses(), &drive.truth);
    assert!(after < 0.1 * before, "mean {after} against {before} m");
    assert!(
        after_largest < 0.1 * before_largest,
        "largest {after_largest} against {before_largest} m"
    );
    assert!(ids.iter().all(|id| graph.closure_accepted(*id)));
}

/// Node indices of two places 3 m apart: the second lap at 3 m along the first side, the
/// third lap at 6 m.
fn three_metres_apart() -> (usize, usize) {
    (LAP + 12, 2 * LAP + 24)
}

/// Adds a closure that says the two places 3 m apart are one, of `information`, and checks
/// that after optimizing it is rejected, every right closure accepted and the path where
/// the right closures alone put it.
fn a_wrong_closure_is_rejected(information: Matrix3<f64>, seed: u64) {
    let drive = square_drive(seed);
    let (right_only, right_ids) = solved_square(&drive);
    let (a, b) = three_metres_apart();
    assert!((drive.truth[a].position() - drive.truth[b].position()).norm() > 2.9);

    // Cold: the wrong closure is there from the start, among the right ones.
    let mut graph = chain(Pose2::IDENTITY, &drive.steps);
    let mut ids = add_closures(&mut graph, &drive);
    ids.insert(
        0,
        graph
            .add_closure(a, b, Pose2::IDENTITY, information)
            .expect("valid"),
    );
    let report = graph.optimize().expect("solvable");
    assert_rejects_the_first(&graph, &ids, &right_only);
    assert_eq!(report.rejected_closures, 1);

    // Warm: it comes after the right ones were solved.
    let mut graph = right_only.clone();
    let wrong = graph
        .add_closure(b, a, Pose2::IDENTITY, information)
        .expect("valid");
    graph.optimize().expect("solvable");
    let mut ids = right_ids;
    ids.insert(0, wrong);
    assert_rejects_the_first(&graph, &ids, &right_only);
}

fn assert_rejects_the_first(graph: &PoseGraph, ids: &[ClosureId], right_only: &PoseGraph) {
    assert!(
        !graph.closure_accepted(ids[0]),
        "{:?}",
        graph.closure_scale(ids[0])
    );
    for id in &ids[1..] {
        assert!(
            graph.closure_accepted(*id),
            "{id:?} {:?}",
            graph.closure_scale(*id)
        );
    }
    let (mean, largest) = position_errors(graph.poses(), right_only.poses());
    assert!(
        mean < 0.005 && largest < 0.02,
        "moved by {mean} m, at most {largest} m"
    );
}

#[test]
fn one_wrong_closure_among_right_ones_is_rejected() {
    a_wrong_closure_is_rejected(diagonal_information(CLOSURE_XY, CLOSURE_YAW), 4);
}

#[test]
fn a_very_sure_wrong_closure_does_not_win() {
    // It claims a millimetre, thirty times surer than the right ones.
    a_wrong_closure_is_rejected(diagonal_information(0.001, 0.0003), 5);
}

#[test]
fn a_sure_right_closure_keeps_the_say_its_information_gives_it() {
    // The counterpart of the sure wrong closure: closures right to the millimetre that say
    // so are taken, and met to a millimetre, although the selection levels their say.
    let drive = square_drive(3);
    let mut graph = chain(Pose2::IDENTITY, &drive.steps);
    let ids = add_closures(&mut graph, &drive);
    let sure = diagonal_information(0.001, 0.0003);
    let pairs = [
        (LAP + 20, 2 * LAP + 20),
        (5, 3 * LAP + 5),
        (LAP + 77, 3 * LAP + 77),
    ];
    let sure_ids: Vec<ClosureId> = pairs
        .iter()
        .map(|&(from, to)| {
            let seen = drive.truth[from].between(&drive.truth[to]);
            graph.add_closure(from, to, seen, sure).expect("valid")
        })
        .collect();
    graph.optimize().expect("solvable");
    assert!(
        ids.iter()
            .chain(&sure_ids)
            .all(|id| graph.closure_accepted(*id))
    );
    for (from, to) in pairs {
        let solved = graph.pose(from).between(&graph.pose(to));
        let truth = drive.truth[from].between(&drive.truth[to]);
        let missed = (solved.position() - truth.position()).norm();
        assert!(missed < 1e-3, "{from} {to}: {missed} m");
    }
}

#[test]
fn closures_added_one_at_a_time_as_the_robot_drives_end_where_all_at_once_do() {
    let drive = square_drive(6);
    let (batch, _) = solved_square(&drive);
    let mut graph = PoseGraph::new(Pose2::IDENTITY).expect("a finite pose");
    let step_information = diagonal_information(STEP_XY, STEP_YAW);
    let closure_information = diagonal_information(CLOSURE_XY, CLOSURE_YAW);
    let mut ids = Vec::new();
    for step in &drive.steps {
        let node = graph
            .add_node(*step, step_information)
            .expect("a valid step");
        let closing: Vec<_> = drive.closures.iter().filter(|c| c.1 == node).collect();
        for &&(from, to, seen) in &closing {
            ids.push(
                graph
                    .add_closure(from, to, seen, closure_information)
                    .expect("valid"),
            );
        }
        if !closing.is_empty() {
            let report = graph.optimize().expect("solvable");
            assert!(report.converged, "{report:?}");
            assert_eq!(report.rejected_closures, 0, "at node {node}");
        }
    }
    assert!(ids.iter().all(|id| graph.closure_accepted(*id)));
    let (mean, largest) = position_errors(graph.poses(), batch.poses());
    assert!(largest < 0.01, "{mean} {largest}");
}

#[test]
fn priors_hold_the_graph_instead_of_its_first_node() {
    // A straight line of 20 one-metre steps that came out 5 % short, with priors at both
    // ends: the line is stretched between them, its first node moved off where it started.
    let short = Pose2::new(0.95, 0.0, 0.0);
    let mut graph = chain(Pose2::new(0.5, 0.0, 0.0), &[short; 20]);
    let firm = Matrix3::identity() * 1e6;
    graph.add_prior(0, Pose2::IDENTITY, firm).expect("valid");
    graph
        .add_prior(20, Pose2::new(20.0, 0.0, 0.0), firm)
        .expect("valid");
    graph.optimize().expect("solvable");
    assert!(
        graph.pose(0).position().norm() < 1e-3,
        "{:?}",
        graph.pose(0)
    );
    assert!(
        (graph.pose(20).x - 20.0).abs() < 1e-3,
        "{:?}",
        graph.pose(20)
    );
    assert!(
        (graph.pose(10).x - 10.0).abs() < 1e-3,
        "{:?}",
        graph.pose(10)
    );
}

#[test]
fn bad_input_is_refused_and_leaves_the_graph_as_it_was() {
    let not_finite = Pose2 {
        x: f64::NAN,
        y: 0.0,
        yaw: 0.0,
    };
    assert_eq!(
        PoseGraph::new(not_finite).err(),
        Some(PoseGraphError::NotFinite {
            what: "the first pose"
        })
    );
    let mut graph = chain(Pose2::IDENTITY, &[Pose2::new(1.0, 0.0, 0.1); 3]);
    let fine = Matrix3::identity();
    let step = Pose2::new(1.0, 0.0, 0.0);
    let infinite_step = Pose2 {
        yaw: f64::INFINITY,
        ..step
    };
    assert!(matches!(
        graph.add_node(infinite_step, fine),
        Err(PoseGraphError::NotFinite { .. })
    ));
    let mut nan_information = fine;
    nan_information[(2, 2)] = f64::NAN;
    assert!(matches!(
        graph.add_node(step, nan_information),
        Err(PoseGraphError::NotFinite { .. })
    ));
    let not_positive_definite = [
        // Nothing known of the heading.
        Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, 0.0)),
        // A negative variance.
        Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, -1.0, 1.0)),
        // Not symmetric.
        Matrix3::new(1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        // Symmetric with a positive diagonal, but indefinite.
        Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    ];
    for information in not_positive_definite {
        assert!(matches!(
            graph.add_node(step, information),
            Err(PoseGraphError::NotPositiveDefinite { .. })
        ));
        assert!(matches!(
            graph.add_closure(0, 3, step, information),
            Err(PoseGraphError::NotPositiveDefinite { .. })
        ));
        assert!(matches!(
            graph.add_prior(1, step, information),
            Err(PoseGraphError::NotPositiveDefinite { .. })
        ));
    }
    assert!(matches!(
        graph.add_closure(0, 3, not_finite, fine),
        Err(PoseGraphError::NotFinite { .. })
    ));
    assert_eq!(
        graph.add_closure(0, 4, step, fine),
        Err(PoseGraphError::NoSuchNode { index: 4, nodes: 4 })
    );
    assert_eq!(
        graph.add_closure(2, 2, step, fine),
        Err(PoseGraphError::SelfClosure(2))
    );
    assert_eq!(
        graph.add_prior(9, step, fine),
        Err(PoseGraphError::NoSuchNode { index: 9, nodes: 4 })
    );
    assert_eq!((graph.node_count(), graph.closure_count()), (4, 0));
    let settings = PoseGraphSettings {
        robust_threshold: 0.0,
        ..PoseGraphSettings::default()
    };
    assert_eq!(
        PoseGraph::with_settings(Pose2::IDENTITY, settings).err(),
        Some(PoseGraphError::BadSetting {
            what: "robust_threshold"
        })
    );
    let report = graph.optimize().expect("solvable");
    assert!(report.final_cost < 1e-12);
}

#[test]
fn a_corridor_driven_west_and_back_across_the_heading_of_pi_closes() {
    // Out along a corridor heading west (yaw pi, where it wraps to -pi), back east, twice;
    // each pass on the way back is tied to the way out (a turn of pi between the two, as
    // measured wrapping either way) and the second out to the first. The same drive
    // started heading north, where no heading wraps, must give the same path turned.
    const PASS: usize = 60;
    let turn = |k: usize| k % PASS == PASS - 1;
    let true_steps: Vec<Pose2> = (0..4 * PASS)
        .map(|k| Pose2::new(0.25, 0.0, if turn(k) { PI } else { 0.0 }))
        .collect();
    let truth = compose_all(Pose2::new(0.0, 0.0, PI), &true_steps);
    let mut rng = StdRng::seed_from_u64(8);
    let steps: Vec<Pose2> = true_steps
        .iter()
        .map(|s| noisy(*s, STEP_XY, STEP_YAW, &mut rng))
        .collect();
    let mut closures = Vec::new();
    for to in (PASS..truth.len()).step_by(5).filter(|to| to % PASS != 0) {
        // The same place on each earlier pass: `pass * PASS + k` is `k` steps out on an
        // outbound pass, `PASS - k` on a way back (a pass's first node is the turn).
        let (pass, k) = (to / PASS, to % PASS);
        for earlier in 0..pass {
            let from = if (pass - earlier) % 2 == 0 {
                earlier * PASS + k
            } else {
                earlier * PASS + PASS - k
            };
            let true_seen = truth[from].between(&truth[to]);
            let seen = noisy(true_seen, CLOSURE_XY, CLOSURE_YAW, &mut rng);
            closures.push((from, to, seen));
        }
    }
    // Some closures turn by just under pi, some by just over (wrapped to near -pi).
    assert!(closures.iter().any(|c| c.2.yaw > 3.1) && closures.iter().any(|c| c.2.yaw < -3.1));
    let drive = Drive {
        truth,
        steps,
        closures,
    };

    let solve = |first: Pose2| {
        let mut graph = chain(first, &drive.steps);
        let ids = add_closures(&mut graph, &drive);
        let report = graph.optimize().expect("solvable");
        assert!(report.converged, "{report:?}");
        assert!(
            ids.iter().all(|id| graph.closure_accepted(*id)),
            "{report:?}"
        );
        graph
    };
    let west = solve(drive.truth[0]);
    let north = solve(Pose2::new(0.0, 0.0, FRAC_PI_2));
    let turned = Pose2::new(0.0, 0.0, FRAC_PI_2);
    for (w, n) in west.poses().iter().zip(north.poses()) {
        assert!((-PI..PI).contains(&w.yaw), "{w:?}");
        let n = turned.compose(n);
        assert!((w.position() - n.position()).norm() < 1e-6, "{w:?} {n:?}");
        assert!(wrap_angle(w.yaw - n.yaw).abs() < 1e-6, "{w:?} {n:?}");
    }
    let drifted = compose_all(drive.truth[0], &drive.steps);
    let (before, _) = position_errors(&drifted, &drive.truth);
    let (after, _) = position_errors(west.poses(), &drive.truth);
    assert!(after < before, "{after} against {before}");
}
