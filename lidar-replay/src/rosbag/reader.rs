//! The reader of a surveyed bag: its messages decoded, put in stamp order by the
//! reordering window, scans paired with the odometry at their stamps, out as log records.

use std::collections::{BTreeMap, VecDeque};

use super::decode::{Decoded, Plan};
use super::info::BagInfo;
use super::pairing::Pairing;
use super::storage::{Damaged, RawMessage};
use super::stream::Messages;
use crate::error::{LineError, ReadError};
use crate::lines::StopFlag;
use crate::record::{LogRecord, ScanRecord};
use crate::reorder::{Entry, ReorderConfig, ReorderCounts, ReorderWindow};

/// A scan waits for the odometry after its stamp behind at most this many others; beyond
/// it (odometry that stopped) the oldest goes out with the pose the readings held give.
const MAX_SCANS_WAITING: usize = 256;

/// The scans and odometry of a bag, in publishing order: a [`crate::LogReader`] of
/// [`crate::LogFormat::Rosbag`].
#[derive(Debug)]
pub struct BagReader {
    messages: Messages,
    plan: Plan,
    window: ReorderWindow,
    /// Pairs each scan with its odometry; `None` without odometry.
    pairing: Option<Pairing>,
    ready: VecDeque<LogRecord>,
    /// Messages of topics not replayed, by topic.
    passed_over: BTreeMap<String, u64>,
    last_scan: Option<u64>,
    stop: StopFlag,
    ended: bool,
    pairing_ended: bool,
    stopped: bool,
}

impl BagReader {
    pub(super) fn new(info: &BagInfo, reorder: ReorderConfig, stop: StopFlag) -> Self {
        let plan = Plan::of(info);
        Self {
            messages: Messages::new(info.storage, info.files.clone()),
            pairing: plan.odometry.is_some().then(Pairing::default),
            plan,
            window: ReorderWindow::new(reorder),
            ready: VecDeque::new(),
            passed_over: BTreeMap::new(),
            last_scan: None,
            stop,
            ended: false,
            pairing_ended: false,
            stopped: false,
        }
    }

    /// Messages read so far, of every topic.
    pub fn messages_read(&self) -> u64 {
        self.messages.read()
    }

    /// Topics read but not replayed, with their message counts.
    pub fn passed_over(&self) -> &BTreeMap<String, u64> {
        &self.passed_over
    }

    /// The reordering window and what it did so far.
    pub fn reordering(&self) -> (ReorderConfig, ReorderCounts) {
        (self.window.config(), *self.window.counts())
    }

    /// Odometry readings refused as not later than the one before (stamped alike).
    pub fn odometry_refused(&self) -> u64 {
        self.pairing.as_ref().map_or(0, |pairing| pairing.refused)
    }

    /// A record ready to go out: one that needs no pairing first, else one paired.
    fn pending(&mut self) -> Option<LogRecord> {
        self.ready
            .pop_front()
            .or_else(|| self.pairing.as_mut().and_then(Pairing::next))
    }

    /// Sets the time since the previous scan where the message gave none.
    fn out(&mut self, record: LogRecord) -> LogRecord {
        match record {
            LogRecord::Scan(mut scan) => {
                if scan.geometry.scan_time == 0.0
                    && let Some(previous) = self.last_scan
                {
                    scan.geometry.scan_time = scan.stamp_ns.saturating_sub(previous) as f64 * 1e-9;
                }
                self.last_scan = Some(scan.stamp_ns);
                LogRecord::Scan(scan)
            }
            odometry => odometry,
        }
    }

    /// Moves on what the window lets out (all it holds once the bag has ended); whether
    /// anything came out.
    fn release_from_window(&mut self) -> bool {
        let released = if self.ended {
            self.window.pop_any()
        } else {
            self.window.pop_ready()
        };
        match released {
            Some(entry) => {
                self.released(entry);
                true
            }
            None => false,
        }
    }

    /// Takes what the window let out: to the pairing, or straight out.
    fn released(&mut self, entry: Entry) {
        let records = match entry {
            Entry::Odometry(odometry) => vec![LogRecord::Odometry(odometry)],
            Entry::Scan(scan) => vec![LogRecord::Scan(scan)],
            Entry::OdometryAndScan(odometry, scan) => {
                vec![LogRecord::Odometry(odometry), LogRecord::Scan(scan)]
            }
        };
        for record in records {
            match (&mut self.pairing, record) {
                (Some(pairing), LogRecord::Odometry(odometry)) => pairing.odometry(odometry),
                (Some(pairing), LogRecord::Scan(scan)) => {
                    pairing.scan(scan);
                    pairing.limit_waiting(MAX_SCANS_WAITING);
                }
                (None, record) => self.ready.push_back(record),
            }
        }
    }

    /// Ends the pairing, once, after the bag's last message: whether it was still going.
    fn end_pairing(&mut self) -> bool {
        match &mut self.pairing {
            Some(pairing) if !self.pairing_ended => {
                self.pairing_ended = true;
                pairing.end();
                true
            }
            _ => false,
        }
    }

    /// Reads the bag's next message into the window; `Some` for what the reader must say.
    fn read_message(&mut self) -> Option<ReadError> {
        match self.messages.next() {
            None => {
                self.ended = true;
                None
            }
            Some(Err(Damaged(cause))) => {
                // What the window holds still comes out after the error.
                self.ended = true;
                Some(ReadError::Cut {
                    messages: self.messages.read(),
                    cause,
                })
            }
            Some(Ok(message)) => {
                let index = self.messages.read();
                self.take(index, &message).err().map(ReadError::from)
            }
        }
    }

    /// Puts a message's records into the window.
    fn take(&mut self, index: u64, message: &RawMessage) -> Result<(), LineError> {
        match self.plan.decode(index, message)? {
            Decoded::Scan(scan) => self.window.push(Entry::Scan(ScanRecord {
                line: index,
                stamp_ns: scan.header.stamp_ns,
                log_stamp_ns: scan.header.stamp_ns,
                geometry: scan.geometry,
                ranges: scan.ranges,
                intensities: scan.intensities,
                robot_from_sensor: self.plan.mount,
            })),
            Decoded::Odometry(odometry) => self.window.push(Entry::Odometry(odometry)),
            Decoded::Tf(poses) => {
                for pose in poses {
                    self.window.push(Entry::Odometry(pose));
                }
            }
            Decoded::PassedOver => {
                *self
                    .passed_over
                    .entry(message.channel.topic.clone())
                    .or_default() += 1;
            }
        }
        Ok(())
    }
}

impl Iterator for BagReader {
    type Item = Result<LogRecord, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.stopped {
            return None;
        }
        loop {
            if let Some(record) = self.pending() {
                return Some(Ok(self.out(record)));
            }
            if self.release_from_window() {
                continue;
            }
            if self.ended {
                if self.end_pairing() {
                    continue;
                }
                return None;
            }
            if (self.stop)() {
                self.stopped = true;
                return Some(Err(ReadError::Stopped));
            }
            if let Some(error) = self.read_message() {
                return Some(Err(error));
            }
        }
    }
}
