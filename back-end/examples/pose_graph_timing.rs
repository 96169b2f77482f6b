//! Times the pose graph at the size of a long online run: a chain of 15,000 nodes (a
//! 100 m loop driven 15 times in 0.1 m steps) with 500 closures between its laps.
//!
//! `cargo run -p back-end --release --example pose_graph_timing`

use std::time::Instant;

use back_end::{PoseGraph, SolveReport};
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};
use slam_geom::Pose2;

const NODES: usize = 15_000;
/// Nodes in one lap of the 30 m x 20 m rectangle.
const LAP: usize = 1000;
/// A closure every this many nodes from the second lap on: 500 in all.
const CLOSURE_EVERY: usize = 28;
const STEP_XY: f64 = 0.005;
const STEP_YAW: f64 = 0.001;
const CLOSURE_XY: f64 = 0.03;
const CLOSURE_YAW: f64 = 0.01;

fn information(xy: f64, yaw: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(xy.powi(-2), xy.powi(-2), yaw.powi(-2)))
}

fn noisy(pose: Pose2, xy: f64, yaw: f64, rng: &mut StdRng) -> Pose2 {
    let unit = Normal::new(0.0, 1.0).expect("a valid normal");
    Pose2::new(
        pose.x + xy * unit.sample(rng),
        pose.y + xy * unit.sample(rng),
        pose.yaw + yaw * unit.sample(rng),
    )
}

/// The true poses and the measured steps of the drive.
fn drive(rng: &mut StdRng) -> (Vec<Pose2>, Vec<Pose2>) {
    // 300 steps along the long side, 200 along the short one, turning at the corners.
    let corners = [300, 500, 800, 1000];
    let true_steps: Vec<Pose2> = (1..NODES)
        .map(|k| {
            let turn = corners.contains(&(k % LAP)) || k % LAP == 0;
            Pose2::new(
                0.1,
                0.0,
                if turn {
                    std::f64::consts::FRAC_PI_2
                } else {
                    0.0
                },
            )
        })
        .collect();
    let mut truth = vec![Pose2::IDENTITY];
    for step in &true_steps {
        let last = truth[truth.len() - 1];
        truth.push(last.compose(step));
    }
    let steps = true_steps
        .iter()
        .map(|s| noisy(*s, STEP_XY, STEP_YAW, rng))
        .collect();
    (truth, steps)
}

/// Runs of each optimization timed (each on a copy of the same graph): the machine is
/// shared, so the least and the median say more than one run.
const RUNS: usize = 5;

/// The time this thread has spent on a CPU, nanoseconds (Linux's schedstat; `None`
/// elsewhere): on a shared machine the wall clock also counts the time others had it.
fn cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

fn least_and_median(mut milliseconds: Vec<f64>) -> (f64, f64) {
    milliseconds.sort_by(f64::total_cmp);
    (milliseconds[0], milliseconds[milliseconds.len() / 2])
}

/// Optimizes `graph`, timed over [`RUNS`] copies of it, and prints the timings.
fn timed(label: &str, graph: &mut PoseGraph) -> SolveReport {
    let mut wall = Vec::with_capacity(RUNS);
    let mut cpu = Vec::with_capacity(RUNS);
    let mut last = None;
    for _ in 0..RUNS {
        let mut copy = graph.clone();
        let (start, start_cpu) = (Instant::now(), cpu_ns());
        let report = copy.optimize().expect("solvable");
        wall.push(start.elapsed().as_secs_f64() * 1e3);
        if let (Some(a), Some(b)) = (start_cpu, cpu_ns()) {
            cpu.push((b - a) as f64 * 1e-6);
        }
        last = Some((copy, report));
    }
    // Every run solved the same graph to the same answer: the graph goes on from it.
    let (solved, report) = last.expect("at least one run");
    *graph = solved;
    let (wall_least, wall_median) = least_and_median(wall);
    let cpu = if cpu.len() == RUNS {
        let (least, median) = least_and_median(cpu);
        format!("on CPU {least:>5.1} / {median:>5.1} ms")
    } else {
        String::new()
    };
    println!(
        "{label:<38} wall {wall_least:>5.1} / {wall_median:>5.1} ms, {cpu} (least / median); \
         {:>2} iterations, converged {}, closures {} accepted, {} rejected",
        report.iterations, report.converged, report.accepted_closures, report.rejected_closures
    );
    report
}

fn largest_error(poses: &[Pose2], truth: &[Pose2]) -> f64 {
    poses
        .iter()
        .zip(truth)
        .map(|(p, t)| (p.position() - t.position()).norm())
        .fold(0.0, f64::max)
}

fn main() {
    let mut rng = StdRng::seed_from_u64(7);
    let (truth, steps) = drive(&mut rng);
    let closures: Vec<(usize, usize, Pose2)> = (LAP..NODES)
        .step_by(CLOSURE_EVERY)
        .map(|to| {
            let from = to - LAP;
            let seen = noisy(
                truth[from].between(&truth[to]),
                CLOSURE_XY,
                CLOSURE_YAW,
                &mut rng,
            );
            (from, to, seen)
        })
        .collect();
    let (last_from, last_to, last_seen) = closures[closures.len() - 1];
    let closure_information = information(CLOSURE_XY, CLOSURE_YAW);

    // All but the last closure and the nodes after the one before it, cold.
    let mut graph = PoseGraph::new(Pose2::IDENTITY).expect("finite");
    let held_back = closures[closures.len() - 2].1 + 1;
    for step in &steps[..held_back - 1] {
        graph
            .add_node(*step, information(STEP_XY, STEP_YAW))
            .expect("valid");
    }
    for &(from, to, seen) in &closures[..closures.len() - 1] {
        graph
            .add_closure(from, to, seen, closure_information)
            .expect("valid");
    }
    println!(
        "{} nodes, {} closures; odometry off the truth by up to {:.2} m",
        graph.node_count(),
        graph.closure_count(),
        largest_error(graph.poses(), &truth)
    );
    timed("cold start (odometry)", &mut graph);
    println!(
        "  solved: off the truth by up to {:.2} m",
        largest_error(graph.poses(), &truth)
    );
    timed("warm, nothing new", &mut graph);

    // The robot drives on and closes a loop: the online case.
    for step in &steps[held_back - 1..] {
        graph
            .add_node(*step, information(STEP_XY, STEP_YAW))
            .expect("valid");
    }
    let mut wrong_graph = graph.clone();
    graph
        .add_closure(last_from, last_to, last_seen, closure_information)
        .expect("valid");
    timed("warm, new nodes and one right closure", &mut graph);

    // ...or a wrong one: the place 3 m along the lap.
    let wrong = wrong_graph
        .add_closure(last_from + 30, last_to, last_seen, closure_information)
        .expect("valid");
    timed("warm, new nodes and one wrong closure", &mut wrong_graph);
    println!(
        "  wrong closure accepted: {}",
        wrong_graph.closure_accepted(wrong)
    );
    println!(
        "{} nodes, {} closures; solved off the truth by up to {:.2} m",
        graph.node_count(),
        graph.closure_count(),
        largest_error(graph.poses(), &truth)
    );
}
