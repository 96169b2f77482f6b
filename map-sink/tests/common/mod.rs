//! Shared helpers of the integration tests: scratch directories and a synthetic run.

#![allow(dead_code)] // Each test binary uses a different subset.

use std::f64::consts::PI;
use std::path::PathBuf;

use map_sink::{MapCorner, Pose2};

/// A fresh, empty directory under the system temp dir, unique to this process and name.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("map-sink-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A deterministic generator (SplitMix64), so tests need no random-number dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A standard normal sample (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

/// A room 16 m x 10 m with a square pillar and an alcove, as wall segments.
pub struct World {
    pub walls: Vec<[[f64; 2]; 2]>,
    /// Corner tips with the unit directions of their two walls.
    pub corners: Vec<([f64; 2], [f64; 2], [f64; 2])>,
}

impl World {
    pub fn new() -> Self {
        let outline = [
            [0.0, 0.0],
            [16.0, 0.0],
            [16.0, 6.0],
            [14.5, 6.0],
            [14.5, 8.0],
            [16.0, 8.0],
            [16.0, 10.0],
            [0.0, 10.0],
        ];
        let pillar = [[6.5, 4.2], [8.0, 4.2], [8.0, 5.8], [6.5, 5.8]];
        let mut walls = Vec::new();
        let mut corners = Vec::new();
        for polygon in [&outline[..], &pillar[..]] {
            let n = polygon.len();
            for i in 0..n {
                let (prev, tip, next) =
                    (polygon[(i + n - 1) % n], polygon[i], polygon[(i + 1) % n]);
                walls.push([tip, next]);
                corners.push((tip, unit(tip, prev), unit(tip, next)));
            }
        }
        Self { walls, corners }
    }

    pub fn corner_positions(&self) -> Vec<[f64; 2]> {
        self.corners.iter().map(|c| c.0).collect()
    }

    /// The range along a ray from `origin` at `bearing` (world frame), `inf` for no hit.
    pub fn cast(&self, origin: [f64; 2], bearing: f64) -> f64 {
        let d = [bearing.cos(), bearing.sin()];
        let mut best = f64::INFINITY;
        for [a, b] in &self.walls {
            let e = [b[0] - a[0], b[1] - a[1]];
            let denom = d[0] * e[1] - d[1] * e[0];
            if denom.abs() < 1e-12 {
                continue;
            }
            let w = [a[0] - origin[0], a[1] - origin[1]];
            let t = (w[0] * e[1] - w[1] * e[0]) / denom;
            let s = (w[0] * d[1] - w[1] * d[0]) / denom;
            if t > 0.0 && (0.0..=1.0).contains(&s) {
                best = best.min(t);
            }
        }
        best
    }

    /// The true corners as a SLAM map would hold them, moved by `t` and perturbed.
    pub fn map_corners(&self, t: Pose2, rng: &mut Rng, sigma: f64) -> Vec<MapCorner> {
        self.corners
            .iter()
            .map(|(tip, d1, d2)| {
                let p: [f64; 2] = t.transform((*tip).into()).into();
                let heading = (-(d1[1] + d2[1])).atan2(-(d1[0] + d2[0]));
                let covariance = nalgebra::Matrix4::from_diagonal(&nalgebra::Vector4::new(
                    0.01, 0.01, 0.002, 0.003,
                ));
                MapCorner {
                    x: p[0] + sigma * rng.normal(),
                    y: p[1] + sigma * rng.normal(),
                    heading: slam_geom::wrap_angle(heading + t.yaw),
                    angle: (d1[0] * d2[0] + d1[1] * d2[1]).clamp(-1.0, 1.0).acos(),
                    covariance,
                    observations: 5 + (rng.uniform() * 50.0) as u32,
                }
            })
            .collect()
    }
}

fn unit(from: [f64; 2], to: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    let n = dx.hypot(dy);
    [dx / n, dy / n]
}

/// The true pose at step `i` of `n`: one lap of an ellipse around the pillar, facing along it.
pub fn true_pose(i: usize, n: usize) -> Pose2 {
    let t = 2.0 * PI * i as f64 / n as f64;
    let (x, y) = (7.25 + 5.0 * t.cos(), 5.0 + 3.2 * t.sin());
    let yaw = (3.2 * t.cos()).atan2(-5.0 * t.sin());
    Pose2::new(x, y, yaw)
}

/// What a synthetic run includes.
#[derive(Debug, Clone, Copy)]
pub struct Synthetic {
    pub scans: usize,
    pub beams: usize,
    pub truth: bool,
    pub dead_reckoning: bool,
}

impl Synthetic {
    /// One lap in `scans` scans of `beams` beams, with ground truth and dead reckoning.
    pub fn lap(scans: usize, beams: usize) -> Self {
        Self {
            scans,
            beams,
            truth: true,
            dead_reckoning: true,
        }
    }
}

/// A recorder in the fresh directory `name` (see [`scratch_dir`]), driven through `run`
/// and left open for the test to finish.
pub fn driven_recorder(
    name: &str,
    options: map_sink::RecorderOptions,
    run: Synthetic,
) -> Result<(PathBuf, map_sink::Recorder), map_sink::SinkError> {
    let dir = scratch_dir(name);
    let mut recorder = map_sink::Recorder::create(&dir, options)?;
    drive(&mut recorder, run)?;
    Ok((dir, recorder))
}

/// Drives a recorder through one lap of the synthetic room as the pipeline would: scans
/// ray-cast from the true poses, an estimate in the SLAM frame (the first pose is the
/// origin) with small errors, a drifting dead reckoning, and a map of perturbed corners.
/// Scans arrive before their pose for even sequence numbers and after it for odd ones.
pub fn drive(recorder: &mut map_sink::Recorder, run: Synthetic) -> Result<(), map_sink::SinkError> {
    let world = World::new();
    let mut rng = Rng::new(42);
    let n = run.scans;
    let slam_from_world = true_pose(0, n).inverse();
    let angle_min = -0.75 * PI;
    let angle_increment = 1.5 * PI / (run.beams - 1) as f64;
    if run.truth {
        recorder.set_true_corners(world.corner_positions());
    }
    let mut ranges = vec![0.0_f32; run.beams];
    for i in 0..n {
        let seq = i as u64;
        let stamp_ns = 1_700_000_000_000_000_000 + seq * 100_000_000;
        let truth = true_pose(i, n);
        for (b, range) in ranges.iter_mut().enumerate() {
            let r = world.cast(
                truth.position().into(),
                truth.yaw + angle_min + b as f64 * angle_increment,
            );
            let r = r + 0.01 * rng.normal();
            *range = if rng.uniform() < 0.01 {
                f32::NAN
            } else if r > 30.0 {
                f32::INFINITY
            } else {
                r as f32
            };
        }
        // The estimate wanders a few centimetres around the truth, smoothly.
        let phase = 2.0 * PI * i as f64 / n as f64;
        let wobble = Pose2::new(
            0.04 * (3.0 * phase).sin(),
            0.03 * (5.0 * phase).cos() - 0.03,
            0.004 * phase.sin(),
        );
        let est = slam_from_world.compose(&truth.compose(&wobble));
        // Dead reckoning: a heading bias integrates into a swing about the start.
        let drift = Pose2::new(0.0, 0.0, 0.12 * i as f64 / n as f64);
        let dr = drift.compose(&est);
        let latency_ns = 2_000_000 + (rng.uniform() * 3_000_000.0) as u64;
        let scan_first = i % 2 == 0;
        if scan_first {
            recorder.record_scan(seq, angle_min, angle_increment, 0.1, 30.0, &ranges);
        }
        recorder.record_pose(
            seq,
            stamp_ns,
            est,
            run.dead_reckoning.then_some(dr),
            Some(latency_ns),
        )?;
        if !scan_first {
            recorder.record_scan(seq, angle_min, angle_increment, 0.1, 30.0, &ranges);
        }
        if run.truth {
            recorder.record_truth(stamp_ns, truth)?;
        }
    }
    recorder.set_map(world.map_corners(slam_from_world, &mut rng, 0.03));
    Ok(())
}
