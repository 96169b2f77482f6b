//! What the view reads, lossy: the topics a person watches a run by.

use anyhow::Result;
use iceoryx2::prelude::{Node, ipc};
use ipc_types::prelude::*;
use ipc_types::{Topic, Wakeable};
use recorder::{
    FeaturesScene, GraphGridMessage, GraphPathMessage, MapMessage, MapScene, Output,
    ParticlesMessage, PathMessage, PoseMessage, RecordError, Recording, ScanMessage,
    TransformMessage,
};
use view_proc::{LiveChannels, ViewError};

/// The view's inlets; the optional ones exist when their publisher runs in this pipeline.
pub struct Inlets {
    scans: Inlet<LaserScan>,
    features: Inlet<Features>,
    poses: Inlet<PoseEstimate>,
    maps: Inlet<MapSnapshot>,
    path: Inlet<PathChunk>,
    particles: Option<Inlet<ParticleCloud>>,
    graph_path: Option<Inlet<PathChunk>>,
    graph_grid: Option<Inlet<GridCells>>,
}

/// Opens the channels a person looks at before their first message, so that a client
/// that connects early sees them all: the scan, the frames, the pose, the cloud and the
/// paths, the grid, the map's corners.
pub fn declare_channels(channels: &mut LiveChannels) -> Result<(), ViewError> {
    channels.declare::<ScanMessage<'static>>()?;
    channels.declare::<TransformMessage<'static>>()?;
    channels.declare::<PoseMessage>()?;
    channels.declare::<ParticlesMessage>()?;
    channels.declare::<PathMessage>()?;
    channels.declare::<GraphPathMessage>()?;
    channels.declare::<GraphGridMessage>()?;
    channels.declare::<MapScene>()?;
    channels.declare::<FeaturesScene>()?;
    channels.declare::<MapMessage>()?;
    Ok(())
}

impl Inlets {
    /// Subscribes lossy to each topic once its publisher has created it.
    pub fn open(node: &Node<ipc::Service>, particles: bool, back_end: bool) -> Result<Self> {
        Ok(Self {
            scans: Inlet::open_lossy(node, topic::SCAN)?,
            features: Inlet::open_lossy(node, topic::FEATURES)?,
            poses: Inlet::open_lossy(node, topic::POSE)?,
            maps: Inlet::open_lossy(node, topic::MAP)?,
            path: Inlet::open_lossy(node, topic::PATH)?,
            particles: open_if(particles, node, topic::PARTICLES)?,
            graph_grid: open_if(back_end, node, topic::GRAPH_GRID)?,
            graph_path: open_if(back_end, node, topic::GRAPH_PATH)?,
        })
    }

    pub fn wakeables(&self) -> Vec<&dyn Wakeable> {
        let mut all: Vec<&dyn Wakeable> = vec![
            &self.scans,
            &self.features,
            &self.poses,
            &self.maps,
            &self.path,
        ];
        all.extend(self.particles.as_ref().map(|i| i as &dyn Wakeable));
        all.extend(self.graph_path.as_ref().map(|i| i as &dyn Wakeable));
        all.extend(self.graph_grid.as_ref().map(|i| i as &dyn Wakeable));
        all
    }

    /// Converts and serves everything queued.
    pub fn drain<O: Output>(&self, view: &mut Recording<O>) -> Result<()> {
        drain(&self.scans, |m| view.scan(m))?;
        drain(&self.poses, |m| view.pose(m))?;
        drain(&self.features, |m| view.features(m))?;
        drain(&self.maps, |m| view.map(m))?;
        drain(&self.path, |m| view.path_chunk(m))?;
        if let Some(particles) = &self.particles {
            drain(particles, |m| view.particles(m))?;
        }
        if let Some(graph_path) = &self.graph_path {
            drain(graph_path, |m| view.graph_path_chunk(m))?;
        }
        if let Some(graph_grid) = &self.graph_grid {
            drain(graph_grid, |m| view.graph_grid_cells(m))?;
        }
        Ok(())
    }
}

/// Subscribes lossy to `topic` when `wanted` (its publisher runs in this pipeline).
fn open_if<T: Message>(
    wanted: bool,
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<Option<Inlet<T>>> {
    Ok(if wanted {
        Some(Inlet::open_lossy(node, topic)?)
    } else {
        None
    })
}

/// Serves every message queued on `inlet` with `serve`.
fn drain<T: Message>(
    inlet: &Inlet<T>,
    mut serve: impl FnMut(&T) -> Result<(), RecordError>,
) -> Result<()> {
    while let Some(sample) = inlet.receive()? {
        serve(&sample)?;
    }
    Ok(())
}
