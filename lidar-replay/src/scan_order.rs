//! In which order a log's scans are replayed when their stamps are not in the log's order,
//! judged by the scans before the replay starts.
//!
//! A log whose scans go back in time may have been written in the order the scans were
//! taken, some of them stamped late (a logger that stamps a scan when it gets round to it,
//! up to a second later), or its lines may have been written out of order, each stamped
//! right. The scans tell which: a moving robot's consecutive scans differ little, so the
//! order in which they were taken is the one along which they change least. Each stretch
//! of the log whose order differs from its stamps' (the smallest run of scans that the
//! stamps only permute) is judged by both orders' path through the scans, from the scan
//! before the stretch to the one after it: the sum of the differences between consecutive
//! scans. The log's order is kept when it is the shorter path in [`MIN_STRETCHES`] stretches
//! at least and [`MAJORITY`] times as many as the stamps' order; otherwise scans go in stamp
//! order, as everything else does ([`crate::reorder`]).

use crate::record::ScanRecord;
use crate::reorder::ScanOrder;
use crate::start::LogStart;

/// Beams of a scan kept for comparing it with another, at most (evenly spaced).
const PROFILE_BEAMS: usize = 181;

/// A beam's difference counts at most this much, metres: a beam that sees past a door in
/// one scan and the door in the other is one beam, not a verdict.
const MAX_BEAM_DIFFERENCE: f32 = 1.0;

/// Beams valid in both scans needed to compare them.
const MIN_COMMON_BEAMS: usize = 10;

/// Scans in a stretch judged at most: a longer one is not a few late stamps.
pub const MAX_STRETCH: usize = 64;

/// The two orders' paths must differ by this share of their mean for a stretch to count:
/// a robot standing still cannot tell them apart.
const TIE: f64 = 0.05;

/// Stretches in which the log's order must be the shorter at least.
pub const MIN_STRETCHES: usize = 5;

/// ... and how many times as often as the stamps' order.
pub const MAJORITY: usize = 3;

/// A scan's ranges, thinned to at most [`PROFILE_BEAMS`], invalid ones NaN, with what it
/// takes to know that two scans' beams point the same way.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    beams: usize,
    angle_min: f64,
    angle_increment: f64,
    ranges: Vec<f32>,
}

/// The profile of `scan`.
pub fn profile(scan: &ScanRecord) -> Profile {
    let g = &scan.geometry;
    let step = scan.ranges.len().div_ceil(PROFILE_BEAMS).max(1);
    let ranges = scan
        .ranges
        .iter()
        .step_by(step)
        .map(|&r| {
            let valid = r.is_finite() && f64::from(r) >= g.range_min && f64::from(r) <= g.range_max;
            if valid { r } else { f32::NAN }
        })
        .collect();
    Profile {
        beams: scan.ranges.len(),
        angle_min: g.angle_min,
        angle_increment: g.angle_increment,
        ranges,
    }
}

/// How far apart two scans are: the mean over the beams valid in both of their (clipped)
/// difference in range, metres; `None` for scans of different geometries or too few such
/// beams.
fn difference(a: &Profile, b: &Profile) -> Option<f64> {
    if a.beams != b.beams
        || (a.angle_min - b.angle_min).abs() > 1e-6
        || (a.angle_increment - b.angle_increment).abs() > 1e-9
    {
        return None;
    }
    let (mut sum, mut count) = (0.0, 0usize);
    for (x, y) in a.ranges.iter().zip(&b.ranges) {
        if x.is_finite() && y.is_finite() {
            sum += f64::from((x - y).abs().min(MAX_BEAM_DIFFERENCE));
            count += 1;
        }
    }
    (count >= MIN_COMMON_BEAMS).then(|| sum / count as f64)
}

/// What the judgement found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OrderVerdict {
    pub order: ScanOrder,
    /// Scans judged: the log's first ones.
    pub scans: usize,
    /// Stretches of them whose order differs from their stamps'.
    pub stretches: usize,
    /// Stretches along which the scans change less in the log's order, and in the stamps'.
    pub file_shorter: usize,
    pub stamps_shorter: usize,
}

impl OrderVerdict {
    /// One line for the console, when there was something to judge.
    pub fn describe(&self) -> Option<String> {
        if self.stretches == 0 {
            return None;
        }
        let found = format!(
            "scan order: {} stretches of the first {} scans are not in stamp order; the scans \
             change least in the log's order in {} of them, in the stamps' in {}",
            self.stretches, self.scans, self.file_shorter, self.stamps_shorter
        );
        Some(match self.order {
            ScanOrder::File => format!(
                "{found}: replayed in the log's order, a scan stamped late re-stamped between \
                 its neighbours (its own stamp kept for the results)"
            ),
            ScanOrder::Stamps => format!("{found}: replayed in stamp order"),
        })
    }
}

/// Judges the order of a log's scans by its start.
pub(crate) fn judge_start(start: &LogStart) -> OrderVerdict {
    let stamps: Vec<u64> = start.scans.iter().map(|s| s.stamp_ns).collect();
    let profiles: Vec<&Profile> = start.scans.iter().map(|s| &s.profile).collect();
    judge(&stamps, &profiles)
}

/// Judges scans with these `stamps` and `profiles`, in the log's order.
fn judge(stamps: &[u64], profiles: &[&Profile]) -> OrderVerdict {
    let n = stamps.len();
    // The scans' indices in stamp order; a repeated stamp keeps the log's order.
    let mut by_stamp: Vec<usize> = (0..n).collect();
    by_stamp.sort_by_key(|&i| (stamps[i], i));
    let mut verdict = OrderVerdict {
        scans: n,
        ..OrderVerdict::default()
    };
    let path = |order: &mut dyn Iterator<Item = usize>| -> Option<f64> {
        let mut previous: Option<usize> = None;
        let mut sum = 0.0;
        for i in order {
            if let Some(p) = previous {
                sum += difference(profiles[p], profiles[i])?;
            }
            previous = Some(i);
        }
        Some(sum)
    };
    let mut first = 0;
    while first < n {
        if by_stamp[first] == first {
            first += 1;
            continue;
        }
        // The smallest stretch from `first` that the stamps only permute.
        let mut last = first;
        let mut reach = by_stamp[first];
        while reach > last {
            last += 1;
            reach = reach.max(by_stamp[last]);
        }
        verdict.stretches += 1;
        let judged = last - first < MAX_STRETCH && first > 0 && last + 1 < n;
        if judged {
            let ends = [first - 1, last + 1];
            let file = path(
                &mut std::iter::once(ends[0])
                    .chain(first..=last)
                    .chain([ends[1]]),
            );
            let stamp = path(
                &mut std::iter::once(ends[0])
                    .chain(by_stamp[first..=last].iter().copied())
                    .chain([ends[1]]),
            );
            if let (Some(file), Some(stamp)) = (file, stamp)
                && (file - stamp).abs() > TIE * 0.5 * (file + stamp)
            {
                if file < stamp {
                    verdict.file_shorter += 1;
                } else {
                    verdict.stamps_shorter += 1;
                }
            }
        }
        first = last + 1;
    }
    if verdict.file_shorter >= MIN_STRETCHES
        && verdict.file_shorter >= MAJORITY * verdict.stamps_shorter
    {
        verdict.order = ScanOrder::File;
    }
    verdict
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reorder::Records;
    use crate::test_log::{flaser, pose};

    /// The log's scans, a tenth of a second apart along [`pose`]; `stamp` gives each its
    /// stamp from its index and true time.
    fn log(scans: usize, stamp: impl Fn(usize, f64) -> f64) -> String {
        (0..scans)
            .map(|k| {
                let t = 100.0 + 0.1 * k as f64;
                flaser(stamp(k, t), pose(t), pose(t))
            })
            .collect()
    }

    fn verdict(log: &str) -> OrderVerdict {
        judge_start(&crate::start::read(log.as_bytes(), crate::lines::never))
    }

    #[test]
    fn scans_stamped_late_keep_the_logs_order() {
        // Every seventh scan stamped 0.15 to 0.45 s late, in its place in the log.
        let verdict = verdict(&log(300, |k, t| {
            if k % 7 == 3 {
                t + 0.15 + 0.1 * (k % 4) as f64
            } else {
                t
            }
        }));
        assert_eq!(verdict.order, ScanOrder::File, "{verdict:?}");
        assert!(verdict.stretches >= 40, "{verdict:?}");
        assert!(
            verdict
                .describe()
                .is_some_and(|d| d.contains("the log's order"))
        );
    }

    #[test]
    fn lines_written_out_of_order_go_in_stamp_order() {
        // Every seventh scan written one to four lines after where it was taken, stamped
        // right.
        let mut lines: Vec<String> = log(300, |_, t| t).lines().map(str::to_owned).collect();
        for k in (3..290).step_by(7) {
            let moved = lines.remove(k);
            lines.insert(k + 1 + k % 4, moved);
        }
        let verdict = verdict(&(lines.join("\n") + "\n"));
        assert_eq!(verdict.order, ScanOrder::Stamps, "{verdict:?}");
        assert!(verdict.stamps_shorter >= 30, "{verdict:?}");
        assert!(
            verdict
                .describe()
                .is_some_and(|d| d.ends_with("stamp order"))
        );
    }

    /// What the replay publishes of `log`, its scans' order judged first as
    /// [`crate::open_log`] does.
    fn replayed(log: &str) -> (Vec<crate::LogRecord>, crate::ReorderCounts) {
        let verdict = verdict(log);
        let mut reader = crate::LogReader::new(crate::LogFormat::Carmen, log.as_bytes())
            .with_order_verdict(verdict);
        let records = reader.by_ref().map(|r| r.expect("a good line")).collect();
        let counts = reader
            .reordering()
            .map(|(_, counts)| counts)
            .unwrap_or_default();
        (records, counts)
    }

    #[test]
    fn scans_stamped_late_are_replayed_in_the_logs_order_under_new_stamps() {
        // Every seventh scan stamped late, and odometry every 50 ms stamped right.
        let late = |k: usize| k % 7 == 3;
        let mut log = String::new();
        for k in 0..300 {
            let t = 100.0 + 0.1 * k as f64;
            let stamp = if late(k) {
                t + 0.15 + 0.1 * (k % 4) as f64
            } else {
                t
            };
            log += &flaser(stamp, pose(t), pose(t));
            log += &crate::test_log::odom(t + 0.05, pose(t + 0.05));
        }
        let (records, counts) = replayed(&log);
        let scans: Vec<&ScanRecord> = records
            .iter()
            .filter_map(|r| match r {
                crate::LogRecord::Scan(scan) => Some(scan),
                crate::LogRecord::Odometry(_) => None,
            })
            .collect();
        assert_eq!(scans.len(), 300);
        // In the log's order, under the log's own stamps.
        assert!(scans.windows(2).all(|w| w[0].line < w[1].line));
        for (k, scan) in scans.iter().enumerate() {
            let t = 100.0 + 0.1 * k as f64;
            let own = scan.log_stamp_ns as f64 * 1e-9;
            assert!((own - t).abs() < 0.5, "{k}: {own}");
            assert_eq!(scan.stamp_ns != scan.log_stamp_ns, late(k), "{k}");
        }
        // A late scan goes out between its neighbours in the log.
        for w in scans
            .windows(3)
            .filter(|w| w[1].stamp_ns != w[1].log_stamp_ns)
        {
            assert!(w[0].stamp_ns < w[1].stamp_ns && w[1].stamp_ns < w[2].stamp_ns);
        }
        // Everything goes out in time order, odometry among the scans by its stamps.
        assert!(
            records
                .windows(2)
                .all(|w| w[0].stamp_ns() <= w[1].stamp_ns())
        );
        assert_eq!(
            counts.restamped,
            scans
                .iter()
                .filter(|s| s.stamp_ns != s.log_stamp_ns)
                .count() as u64
        );
        assert_eq!(counts.late, Records::default());
        assert_eq!(counts.duplicate, Records::default());
        assert_eq!(counts.reordered.scans, 0);
    }

    #[test]
    fn lines_written_out_of_order_are_replayed_in_stamp_order() {
        let mut lines: Vec<String> = log(300, |_, t| t).lines().map(str::to_owned).collect();
        for k in (3..290).step_by(7) {
            let moved = lines.remove(k);
            lines.insert(k + 1 + k % 4, moved);
        }
        let (records, counts) = replayed(&(lines.join("\n") + "\n"));
        assert_eq!(records.len(), 600, "every scan with its line's odometry");
        assert!(
            records
                .windows(2)
                .all(|w| w[0].stamp_ns() <= w[1].stamp_ns())
        );
        assert!(records.iter().all(|r| match r {
            crate::LogRecord::Scan(scan) => scan.stamp_ns == scan.log_stamp_ns,
            crate::LogRecord::Odometry(_) => true,
        }));
        assert_eq!(counts.restamped, 0);
        assert!(counts.reordered.scans >= 40, "{counts:?}");
    }

    #[test]
    fn scans_in_order_have_nothing_to_judge() {
        let verdict = verdict(&log(100, |_, t| t));
        assert_eq!(verdict.order, ScanOrder::Stamps);
        assert_eq!(verdict.stretches, 0);
        assert_eq!(verdict.describe(), None);
    }

    #[test]
    fn a_few_late_stamps_are_not_enough_to_judge_by() {
        let verdict = verdict(&log(300, |k, t| if k % 100 == 50 { t + 0.3 } else { t }));
        assert_eq!(verdict.stretches, 3);
        assert_eq!(verdict.order, ScanOrder::Stamps, "{verdict:?}");
    }
}
