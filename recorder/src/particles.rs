//! The particle cloud as `foxglove.PosesInFrame`, once all its pieces are in.

use schemars::JsonSchema;
use serde::Serialize;

use ipc_types::{Header, Particle, ParticleCloud, Pose2};

use crate::geometry::Pose;
use crate::pose::MAP_FRAME;
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// Every particle at one scan, drawn as arrows in the map. The cloud is display data, so
/// its numbers are rounded to what a viewer shows (millimetres, milliradians, a weight to
/// three significant digits): a cloud every few scans would otherwise weigh as much as the
/// scans. Foxglove's fields, then the scan's `seq` and each particle's weight.
#[derive(Debug, Serialize, JsonSchema)]
pub struct ParticlesMessage {
    pub timestamp: Time,
    pub frame_id: &'static str,
    pub poses: Vec<Pose>,
    /// The scan whose particles these are.
    pub seq: u64,
    /// Each particle's weight, normalised over the cloud, in the order of `poses`.
    pub weights: Vec<f64>,
}

impl ChannelMessage for ParticlesMessage {
    const TOPIC: &'static str = "/slam/particles";
    const SCHEMA: &'static str = "foxglove.PosesInFrame";
}

impl ParticlesMessage {
    pub fn new(header: &Header, particles: &[Particle]) -> Self {
        Self {
            timestamp: Time::from_ns(header.stamp_ns),
            frame_id: MAP_FRAME,
            poses: particles.iter().map(|p| display_pose(p.pose)).collect(),
            seq: header.seq,
            weights: particles.iter().map(|p| significant(p.weight)).collect(),
        }
    }
}

/// `value` rounded to `1 / scale`: the nearest `f64` to the rounded decimal, which JSON
/// then prints in its short form.
fn rounded(value: f64, scale: f64) -> f64 {
    (value * scale).round() / scale
}

/// The pose at millimetres and milliradians, its quaternion at four decimals (a
/// thousandth of a radian, as the yaw).
fn display_pose(p: Pose2) -> Pose {
    let mut pose = Pose::from(Pose2::new(
        rounded(p.x, 1e3),
        rounded(p.y, 1e3),
        rounded(p.yaw, 1e3),
    ));
    pose.orientation.z = rounded(pose.orientation.z, 1e4);
    pose.orientation.w = rounded(pose.orientation.w, 1e4);
    pose
}

/// `value` to three significant digits (the closest `f64` to that decimal).
fn significant(value: f64) -> f64 {
    if !value.is_finite() || value == 0.0 {
        return if value.is_finite() { value } else { 0.0 };
    }
    format!("{value:.2e}").parse().unwrap_or(value)
}

/// Collects a cloud's pieces; they arrive in order on one topic. In real time a piece may
/// be lost: its cloud is then left out.
#[derive(Debug, Default)]
pub struct ParticlePieces {
    header: Option<Header>,
    particles: Vec<Particle>,
    /// Clouds left out because a piece of them did not come.
    pub incomplete: u64,
}

impl ParticlePieces {
    /// Takes a piece; returns the scan's header and the whole cloud when it completes one.
    pub fn add(&mut self, piece: &ParticleCloud) -> Option<(Header, Vec<Particle>)> {
        if piece.first == 0 {
            if !self.particles.is_empty() {
                self.incomplete += 1;
            }
            self.particles.clear();
            self.header = Some(piece.header);
        } else if piece.first != self.particles.len() as u64
            || self.header.map(|h| h.seq) != Some(piece.header.seq)
        {
            // A piece of a cloud whose start was lost, or after a lost piece.
            if !self.particles.is_empty() {
                self.incomplete += 1;
            }
            self.particles.clear();
            self.header = None;
            return None;
        }
        self.particles.extend_from_slice(piece.particles());
        if !piece.is_last_piece() {
            return None;
        }
        let header = self.header.take()?;
        Some((header, std::mem::take(&mut self.particles)))
    }
}
