//! Puts the records of a log that is not quite in time order back in order, within a bounded
//! window of log time.
//!
//! Some published CARMEN logs write a line up to about a second after lines stamped later
//! (an `ODOM` line before the `FLASER` taken just before it). The pipeline
//! wants stamps that only move forward, so records are held in a window sorted by stamp and
//! let out once the newest stamp read is more than the window past them. What is still out of
//! order after that (a line later than the window allows) or repeats a stamp already let out
//! cannot be placed and is dropped; everything is counted for the replay's summary.
//!
//! Scans may also keep the log's order among themselves ([`ScanOrder::File`], when the
//! scans show that the log wrote them in the order they were taken and stamped some late:
//! [`crate::scan_order`]). A scan read before scans stamped earlier than it was taken no
//! later than they were: it is re-stamped, evenly between the scan before it and the first
//! of them, and keeps its own stamp beside the new one ([`ScanRecord::log_stamp_ns`]) for
//! what the run writes. Odometry is still put in stamp order around the scans.

use std::collections::{BTreeMap, BTreeSet};

use crate::record::{OdometryRecord, ScanRecord};

/// How long records wait for older ones by default: twice the largest step back seen in
/// published logs.
pub const DEFAULT_REORDER_WINDOW_NS: u64 = 2_000_000_000;
/// Lines held at most by default. Two seconds of a 40 Hz lidar with 100 Hz odometry are 280
/// lines; a full window of the largest scans (8192 beams with intensities, 64 KiB) stays
/// under 64 MiB.
pub const DEFAULT_REORDER_CAP: usize = 1024;

/// How scans are ordered among themselves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ScanOrder {
    /// By stamp, as every other record.
    #[default]
    Stamps,
    /// In the log's order; a scan stamped after scans that follow it is re-stamped.
    File,
}

/// How far back records are put in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReorderConfig {
    /// A record is let out once a record more than this much newer (log time) has been read.
    /// With 0 the newest record is still held, so a line may go back behind it, no further.
    pub window_ns: u64,
    /// Lines held at most; beyond it the oldest is let out before its window has passed, so
    /// memory stays bounded whatever the log's stamps do.
    pub max_held: usize,
}

impl Default for ReorderConfig {
    fn default() -> Self {
        Self {
            window_ns: DEFAULT_REORDER_WINDOW_NS,
            max_held: DEFAULT_REORDER_CAP,
        }
    }
}

/// What one log line yields. A `FLASER`'s odometry and scan are one entry, so the odometry
/// still comes right before its scan after sorting.
#[derive(Debug, Clone, PartialEq)]
pub enum Entry {
    Odometry(OdometryRecord),
    Scan(ScanRecord),
    OdometryAndScan(OdometryRecord, ScanRecord),
}

impl Entry {
    fn stamp_ns(&self) -> u64 {
        match self {
            Self::Odometry(odometry) | Self::OdometryAndScan(odometry, _) => odometry.stamp_ns,
            Self::Scan(scan) => scan.stamp_ns,
        }
    }

    /// Order among entries of one stamp: odometry first, so a consumer has the pose before
    /// the scan it goes with.
    fn rank(&self) -> u8 {
        match self {
            Self::Odometry(_) | Self::OdometryAndScan(..) => 0,
            Self::Scan(_) => 1,
        }
    }

    /// The log's own stamp of the entry's scan, if it has one.
    fn scan_log_stamp(&self) -> Option<u64> {
        match self {
            Self::Odometry(_) => None,
            Self::Scan(scan) | Self::OdometryAndScan(_, scan) => Some(scan.log_stamp_ns),
        }
    }

    /// Whether the entry's scan goes out under another stamp than the log's.
    fn restamped(&self) -> bool {
        match self {
            Self::Odometry(_) => false,
            Self::Scan(scan) | Self::OdometryAndScan(_, scan) => scan.stamp_ns != scan.log_stamp_ns,
        }
    }

    /// Moves the entry to `stamp_ns`; a scan line's odometry keeps its place against the
    /// scan (a clock corrected by a lead).
    fn restamp(&mut self, stamp_ns: u64) {
        let shift = stamp_ns.wrapping_sub(self.stamp_ns());
        match self {
            Self::Odometry(odometry) => odometry.stamp_ns = odometry.stamp_ns.wrapping_add(shift),
            Self::Scan(scan) => scan.stamp_ns = scan.stamp_ns.wrapping_add(shift),
            Self::OdometryAndScan(odometry, scan) => {
                odometry.stamp_ns = odometry.stamp_ns.wrapping_add(shift);
                scan.stamp_ns = scan.stamp_ns.wrapping_add(shift);
            }
        }
    }

    fn records(&self) -> Records {
        match self {
            Self::Odometry(_) => Records {
                scans: 0,
                odometry: 1,
            },
            Self::Scan(_) => Records {
                scans: 1,
                odometry: 0,
            },
            Self::OdometryAndScan(..) => Records {
                scans: 1,
                odometry: 1,
            },
        }
    }
}

/// A number of scans and of odometry poses.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Records {
    pub scans: u64,
    pub odometry: u64,
}

impl Records {
    pub fn total(&self) -> u64 {
        self.scans + self.odometry
    }

    fn add(&mut self, other: Records) {
        self.scans += other.scans;
        self.odometry += other.odometry;
    }
}

/// What the window did to a log's records.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReorderCounts {
    /// Read after a newer record and put back in its place.
    pub reordered: Records,
    /// Dropped: older than a record already let out, i.e. later than the window allows.
    pub late: Records,
    /// Dropped: the stamp of a scan (or odometry pose) already let out. A `FLASER` whose scan
    /// repeats a stamp goes with its odometry; one whose odometry alone repeats one (an
    /// `ODOM` line of the same instant came first) keeps its scan.
    pub duplicate: Records,
    /// Let out before their window had passed because [`ReorderConfig::max_held`] lines were
    /// held (they may come out of order with a record read later).
    pub forced_out: Records,
    /// Scans kept in the log's order ([`ScanOrder::File`]) and published under a new stamp,
    /// being stamped after scans that follow them.
    pub restamped: u64,
}

/// A record held in the window.
#[derive(Debug)]
struct Held {
    entry: Entry,
    /// Read after a newer record.
    went_back: bool,
}

/// Log lines in, the same sorted by stamp out, as soon as their window has passed.
#[derive(Debug)]
pub struct ReorderWindow {
    config: ReorderConfig,
    scan_order: ScanOrder,
    /// With [`ScanOrder::File`]: the log's stamps of the scans read, from the last stamp let
    /// out on (an older scan is dropped anyway), to find a repeated one.
    scan_stamps: BTreeSet<u64>,
    /// By (stamp, rank, order read): equal stamps keep the log's order.
    held: BTreeMap<(u64, u8, u64), Held>,
    read: u64,
    newest: Option<u64>,
    last_out: Option<u64>,
    last_scan_out: Option<u64>,
    last_odometry_out: Option<u64>,
    counts: ReorderCounts,
}

impl ReorderWindow {
    pub fn new(config: ReorderConfig) -> Self {
        Self {
            config,
            scan_order: ScanOrder::Stamps,
            scan_stamps: BTreeSet::new(),
            held: BTreeMap::new(),
            read: 0,
            newest: None,
            last_out: None,
            last_scan_out: None,
            last_odometry_out: None,
            counts: ReorderCounts::default(),
        }
    }

    pub fn config(&self) -> ReorderConfig {
        self.config
    }

    /// Orders scans among themselves by `order` from now on.
    pub fn set_scan_order(&mut self, order: ScanOrder) {
        self.scan_order = order;
    }

    pub fn scan_order(&self) -> ScanOrder {
        self.scan_order
    }

    pub fn counts(&self) -> &ReorderCounts {
        &self.counts
    }

    /// Takes the next line's entry; one older than what has been let out is dropped at once.
    pub fn push(&mut self, entry: Entry) {
        let stamp = entry.stamp_ns();
        if self.last_out.is_some_and(|last| stamp < last) {
            self.counts.late.add(entry.records());
            return;
        }
        let went_back = match (self.scan_order, entry.scan_log_stamp()) {
            (ScanOrder::File, Some(log_stamp)) => {
                if self.scan_stamps.contains(&log_stamp) {
                    self.counts.duplicate.add(entry.records());
                    return;
                }
                if !self.put_late_scans_before(stamp) {
                    self.counts.late.add(entry.records());
                    return;
                }
                self.scan_stamps.insert(log_stamp);
                // Among scans it keeps the log's place; around odometry it goes by stamp.
                false
            }
            _ => self.newest.is_some_and(|newest| stamp < newest),
        };
        self.newest = Some(self.newest.map_or(stamp, |newest| newest.max(stamp)));
        self.held
            .insert((stamp, entry.rank(), self.read), Held { entry, went_back });
        self.read += 1;
    }

    /// With [`ScanOrder::File`], before a scan stamped `stamp` is taken: the scans held
    /// (read before it) stamped at or after it were taken before it, so they are re-stamped
    /// evenly between the scan before them (or the last record let out) and `stamp`, in the
    /// order read. `false` when there is no room between (nanoseconds run out): the new scan
    /// cannot be placed.
    fn put_late_scans_before(&mut self, stamp: u64) -> bool {
        let is_scan = |held: &Held| held.entry.scan_log_stamp().is_some();
        let late: Vec<(u64, u8, u64)> = self
            .held
            .range((stamp, 0, 0)..)
            .filter(|(_, held)| is_scan(held))
            .map(|(key, _)| *key)
            .collect();
        if late.is_empty() {
            return true;
        }
        let before = self
            .held
            .range(..(stamp, 0, 0))
            .rev()
            .find(|(_, held)| is_scan(held))
            .map(|((key, _, _), _)| *key);
        let count = late.len() as u64;
        // Without a scan before them (the log's first scans), as late as they can be.
        let low = before
            .max(self.last_out)
            .unwrap_or_else(|| stamp.saturating_sub(count + 1));
        if stamp.saturating_sub(low) <= count {
            return false;
        }
        let mut moved: Vec<((u64, u8, u64), Held)> = late
            .iter()
            .filter_map(|key| self.held.remove_entry(key))
            .collect();
        // In the order read.
        moved.sort_by_key(|((_, _, read), _)| *read);
        let span = u128::from(stamp - low);
        for (k, ((_, rank, read), mut held)) in moved.into_iter().enumerate() {
            let offset = span * (k as u128 + 1) / (u128::from(count) + 1);
            // Below `span`, so within u64.
            let new_stamp = low + offset as u64;
            held.entry.restamp(new_stamp);
            self.held.insert((new_stamp, rank, read), held);
        }
        true
    }

    /// The oldest entry whose window has passed (or that the cap pushes out), if any.
    pub fn pop_ready(&mut self) -> Option<Entry> {
        loop {
            let (&(stamp, _, _), _) = self.held.first_key_value()?;
            let newest = self.newest.unwrap_or(stamp);
            let due = newest.saturating_sub(stamp) > self.config.window_ns;
            let full = self.held.len() > self.config.max_held;
            if !due && !full {
                return None;
            }
            let (_, held) = self.held.pop_first()?;
            if !due {
                self.counts.forced_out.add(held.entry.records());
            }
            if let Some(entry) = self.release(held) {
                return Some(entry);
            }
        }
    }

    /// The oldest entry held, window or not: for the end of the log.
    pub fn pop_any(&mut self) -> Option<Entry> {
        loop {
            let (_, held) = self.held.pop_first()?;
            if let Some(entry) = self.release(held) {
                return Some(entry);
            }
        }
    }

    /// Lets `held` out unless it repeats a stamp already let out.
    fn release(&mut self, held: Held) -> Option<Entry> {
        let stamp = held.entry.stamp_ns();
        let scan_repeats = self.last_scan_out == Some(stamp);
        let odometry_repeats = self.last_odometry_out == Some(stamp);
        let all = held.entry.records();
        let entry = match held.entry {
            Entry::Odometry(_) if odometry_repeats => None,
            Entry::Scan(_) | Entry::OdometryAndScan(..) if scan_repeats => None,
            Entry::OdometryAndScan(_, scan) if odometry_repeats => Some(Entry::Scan(scan)),
            entry => Some(entry),
        };
        let Some(entry) = entry else {
            self.counts.duplicate.add(all);
            return None;
        };
        let records = entry.records();
        self.counts.duplicate.odometry += all.odometry - records.odometry;
        if held.went_back {
            self.counts.reordered.add(records);
        }
        if entry.restamped() {
            self.counts.restamped += 1;
        }
        self.last_out = Some(stamp);
        // A scan stamped before what is let out is dropped as late before its stamp is
        // looked up.
        while self.scan_stamps.first().is_some_and(|&first| first < stamp) {
            self.scan_stamps.pop_first();
        }
        if records.scans > 0 {
            self.last_scan_out = Some(stamp);
        }
        if records.odometry > 0 {
            self.last_odometry_out = Some(stamp);
        }
        Some(entry)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::seed_csv::GEOMETRY;

    const MS: u64 = 1_000_000;

    fn odometry(line: u64, stamp_ns: u64) -> OdometryRecord {
        OdometryRecord {
            line,
            stamp_ns,
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            linear_velocity: 0.0,
            angular_velocity: 0.0,
            log_covariance: [0.0; 9],
        }
    }

    fn scan(line: u64, stamp_ns: u64) -> ScanRecord {
        ScanRecord {
            line,
            stamp_ns,
            log_stamp_ns: stamp_ns,
            geometry: GEOMETRY,
            ranges: vec![1.0],
            intensities: Vec::new(),
            robot_from_sensor: slam_geom::Pose2::IDENTITY,
        }
    }

    /// (line, stamp) of every record in `entries`.
    fn lines(entries: &[Entry]) -> Vec<(u64, u64)> {
        entries
            .iter()
            .flat_map(|entry| match entry {
                Entry::Odometry(o) => vec![(o.line, o.stamp_ns)],
                Entry::Scan(s) => vec![(s.line, s.stamp_ns)],
                Entry::OdometryAndScan(o, s) => vec![(o.line, o.stamp_ns), (s.line, s.stamp_ns)],
            })
            .collect()
    }

    fn drain_ready(window: &mut ReorderWindow) -> Vec<Entry> {
        std::iter::from_fn(|| window.pop_ready()).collect()
    }

    #[test]
    fn a_record_waits_until_something_more_than_the_window_newer_is_read() {
        let mut window = ReorderWindow::new(ReorderConfig {
            window_ns: 100 * MS,
            max_held: 10,
        });
        window.push(Entry::Scan(scan(1, 1000 * MS)));
        window.push(Entry::Scan(scan(2, 1100 * MS)));
        assert!(
            drain_ready(&mut window).is_empty(),
            "exactly the window: held"
        );
        window.push(Entry::Scan(scan(3, 1100 * MS + 1)));
        assert_eq!(lines(&drain_ready(&mut window)), vec![(1, 1000 * MS)]);
        window.push(Entry::Scan(scan(4, 1050 * MS)));
        assert_eq!(
            lines(&std::iter::from_fn(|| window.pop_any()).collect::<Vec<_>>()),
            vec![(4, 1050 * MS), (2, 1100 * MS), (3, 1100 * MS + 1)]
        );
        assert_eq!(window.counts().reordered.scans, 1);
    }

    #[test]
    fn odometry_goes_before_a_scan_of_its_stamp_whatever_the_order_read() {
        let mut window = ReorderWindow::new(ReorderConfig::default());
        window.push(Entry::Scan(scan(1, 5 * MS)));
        window.push(Entry::Odometry(odometry(2, 5 * MS)));
        window.push(Entry::Odometry(odometry(3, 4 * MS)));
        let out: Vec<Entry> = std::iter::from_fn(|| window.pop_any()).collect();
        assert_eq!(lines(&out), vec![(3, 4 * MS), (2, 5 * MS), (1, 5 * MS)]);
        // The odometry read after the scan of its stamp went back in time; the scan did not
        // move back, it only waited.
        assert_eq!(
            window.counts().reordered,
            Records {
                scans: 0,
                odometry: 1
            }
        );
    }

    #[test]
    fn in_the_logs_order_late_scans_are_restamped_between_their_neighbours() {
        let mut window = ReorderWindow::new(ReorderConfig {
            window_ns: 500 * MS,
            max_held: 100,
        });
        window.set_scan_order(ScanOrder::File);
        // Scans 2 and 3 stamped after scan 4; odometry in time order; scan 6 repeats scan
        // 3's stamp; scan 8 is older than what has gone out by then.
        for (line, stamp) in [(1, 100), (2, 390), (3, 420), (4, 300), (5, 400)] {
            window.push(Entry::Scan(scan(line, stamp * MS)));
        }
        window.push(Entry::Odometry(odometry(10, 250 * MS)));
        window.push(Entry::Scan(scan(6, 420 * MS)));
        window.push(Entry::Scan(scan(7, 1000 * MS)));
        let mut out = drain_ready(&mut window);
        window.push(Entry::Scan(scan(8, 350 * MS)));
        out.extend(std::iter::from_fn(|| window.pop_any()));
        let scans: Vec<(u64, u64, u64)> = out
            .iter()
            .filter_map(|entry| match entry {
                Entry::Scan(s) => Some((s.line, s.stamp_ns / MS, s.log_stamp_ns / MS)),
                _ => None,
            })
            .collect();
        // 2 and 3 evenly between 1 and 4, in the log's order.
        assert_eq!(
            scans,
            [
                (1, 100, 100),
                (2, 166, 390),
                (3, 233, 420),
                (4, 300, 300),
                (5, 400, 400),
                (7, 1000, 1000)
            ]
        );
        assert_eq!(
            lines(&out)
                .iter()
                .map(|(line, _)| *line)
                .collect::<Vec<_>>(),
            [1, 2, 3, 10, 4, 5, 7],
            "the odometry by its stamp"
        );
        let counts = window.counts();
        assert_eq!(counts.restamped, 2);
        assert_eq!(counts.duplicate.scans, 1);
        assert_eq!(counts.late.scans, 1);
        // Scans keep the log's order; the odometry read after newer scans went back.
        assert_eq!(
            counts.reordered,
            Records {
                scans: 0,
                odometry: 1
            }
        );
    }

    #[test]
    fn a_window_of_zero_still_places_a_record_before_the_newest() {
        // The newest record is always held (something newer might share its stamp), so
        // even without a window a line may go back behind it, but no further.
        let mut window = ReorderWindow::new(ReorderConfig {
            window_ns: 0,
            max_held: 10,
        });
        let mut out = Vec::new();
        for (line, stamp) in [(1, 10), (2, 20), (3, 15), (4, 20), (5, 12), (6, 30)] {
            window.push(Entry::OdometryAndScan(
                odometry(line, stamp),
                scan(line, stamp),
            ));
            out.extend(drain_ready(&mut window));
        }
        out.extend(std::iter::from_fn(|| window.pop_any()));
        assert_eq!(
            lines(&out),
            vec![
                (1, 10),
                (1, 10),
                (3, 15),
                (3, 15),
                (2, 20),
                (2, 20),
                (6, 30),
                (6, 30)
            ]
        );
        let counts = window.counts();
        assert_eq!(
            counts.reordered,
            Records {
                scans: 1,
                odometry: 1
            }
        );
        assert_eq!(
            counts.late,
            Records {
                scans: 1,
                odometry: 1
            },
            "12 after 15"
        );
        assert_eq!(
            counts.duplicate,
            Records {
                scans: 1,
                odometry: 1
            },
            "20 again"
        );
    }
}
