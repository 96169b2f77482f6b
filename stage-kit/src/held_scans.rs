//! The scans a stage keeps until the features of each come: a stage that reads both the scans
//! and feature-proc's features (slam-proc on a saved map, graph-proc) pairs them by sequence
//! number. A scan goes to each subscriber in turn, so the features may overtake it.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use ipc_types::prelude::*;
use ipc_types::{ReceiveError, WaitError, shutdown};
use slam_geom::ScanGeometry;

/// Scans held at most: feature-proc is never further behind than its queues hold.
const HELD_SCANS: usize = 256;
/// How long a features message waits for its scan in lockstep, where the scan cannot be
/// lost (a bound all the same: a source that died must not hang the stage) ...
const SCAN_WAIT_LOCKSTEP: Duration = Duration::from_secs(10);
/// ... and in real time, where it may have been.
const SCAN_WAIT_REAL_TIME: Duration = Duration::from_millis(5);

/// One scan's beams.
#[derive(Debug, Clone)]
pub struct HeldScan {
    pub seq: u64,
    pub geometry: ScanGeometry,
    pub ranges: Vec<f32>,
}

/// The scans taken from the scan topic and not yet paired.
#[derive(Debug, Default)]
pub struct HeldScans {
    held: VecDeque<HeldScan>,
}

impl HeldScans {
    /// Takes the scans that have come, keeping their beams for the features to come.
    pub fn hold(&mut self, scans: &Inlet<LaserScan>) -> Result<(), ReceiveError> {
        while let Some(scan) = scans.receive()? {
            if scan.header.is_end_of_stream() {
                continue;
            }
            if self.held.len() == HELD_SCANS {
                self.held.pop_front();
            }
            self.held.push_back(HeldScan {
                seq: scan.header.seq,
                geometry: scan.geometry(),
                ranges: scan.ranges().to_vec(),
            });
        }
        Ok(())
    }

    /// The scan numbered `seq`, once it has come (waiting for it as `delivery` allows), or
    /// `None` when it was lost; older held scans are dropped.
    pub fn wait_for(
        &mut self,
        scans: &Inlet<LaserScan>,
        seq: u64,
        delivery: Delivery,
    ) -> Result<Option<&HeldScan>, WaitForScanError> {
        let patience = match delivery {
            Delivery::Lossless => SCAN_WAIT_LOCKSTEP,
            Delivery::Latest => SCAN_WAIT_REAL_TIME,
        };
        let since = Instant::now();
        while self.held.back().is_none_or(|s| s.seq < seq) && since.elapsed() < patience {
            if shutdown::requested() {
                break;
            }
            wait_any(&[scans], Duration::from_millis(10))?;
            self.hold(scans)?;
        }
        while self.held.front().is_some_and(|s| s.seq < seq) {
            self.held.pop_front();
        }
        Ok(self.held.front().filter(|s| s.seq == seq))
    }
}

/// Why waiting for a scan failed: the transport's own errors.
#[derive(Debug, thiserror::Error)]
pub enum WaitForScanError {
    #[error(transparent)]
    Receive(#[from] ReceiveError),
    #[error(transparent)]
    Wait(#[from] WaitError),
}
