//! The block a replay prints at its end: what was published and everything that was not,
//! with why.
//!
//! It is written for a person, and for slam-launch, which shows a stage's last block that
//! starts with `<stage>: summary` (and the indented lines after it) when the run ends.

use std::collections::BTreeMap;
use std::fmt;

use crate::degradation::Degradation;
use crate::error::LineError;
use crate::reorder::{Records, ReorderConfig, ReorderCounts};

/// First words of the block, which slam-launch looks for.
pub const SUMMARY_HEAD: &str = "lidar-replay: summary";

/// Everything a replay counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReplaySummary {
    /// The log, as given.
    pub file: String,
    /// A recording (`run.mcap`) rather than a text log: what was read are messages, and
    /// what was not replayed are topics.
    pub recording: bool,
    /// Lines read, or a recording's messages.
    pub lines_read: u64,
    /// Where a recording could not be read on (cut short, damaged), if it could not.
    pub cut: Option<String>,
    pub published: Records,
    /// Odometry poses read but not published (`--no-odometry`).
    pub odometry_unpublished: u64,
    /// What the replay left out of the log on request (`--every`, `--max-range`).
    pub degradation: Degradation,
    /// Scans left out by `--every`.
    pub scans_left_out: u64,
    /// Beams made no-returns by `--max-range`.
    pub beams_shortened: u64,
    /// Why the replay ended before the log did, if it did (`--frames`, Ctrl-C).
    pub stopped: Option<String>,
    /// The reordering window and what it did; `None` for a format read in line order.
    pub reordering: Option<(ReorderConfig, ReorderCounts)>,
    /// Malformed lines skipped, by [`LineError::category`].
    pub malformed: BTreeMap<String, u64>,
    /// Record types read but not replayed (`PARAM`, `SYNC`, ...) and their line counts.
    pub not_replayed: Vec<(String, u64)>,
}

impl ReplaySummary {
    /// Counts a skipped line.
    pub fn malformed_line(&mut self, error: &LineError) {
        *self.malformed.entry(error.category()).or_default() += 1;
    }

    pub fn malformed_total(&self) -> u64 {
        self.malformed.values().sum()
    }

    /// What the replay could not publish, or not in order, as counts for the launcher
    /// (`ipc_types::losses`). Reordered records were published in order; lines of record
    /// types the pipeline has no use for (`PARAM`, ...) and odometry left out on request are
    /// no loss.
    pub fn losses(&self) -> Vec<(&'static str, u64)> {
        let mut counts = vec![("malformed_lines", self.malformed_total())];
        if self.recording {
            counts.push(("recording_cut_short", u64::from(self.cut.is_some())));
        }
        if let Some((_, c)) = &self.reordering {
            counts.extend([
                ("late_scans", c.late.scans),
                ("late_odometry", c.late.odometry),
                ("repeated_scans", c.duplicate.scans),
                ("repeated_odometry", c.duplicate.odometry),
                ("scans_let_out_unordered", c.forced_out.scans),
                ("odometry_let_out_unordered", c.forced_out.odometry),
            ]);
        }
        counts
    }
}

/// `3 scans, 2 odometry poses`, or `none`.
struct Counted(Records);

impl fmt::Display for Counted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Records { scans, odometry } = self.0;
        match (scans, odometry) {
            (0, 0) => f.write_str("none"),
            (scans, 0) => write!(f, "{scans} scans"),
            (0, odometry) => write!(f, "{odometry} odometry poses"),
            (scans, odometry) => write!(f, "{scans} scans, {odometry} odometry poses"),
        }
    }
}

impl fmt::Display for ReplaySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let read = if self.recording { "messages" } else { "lines" };
        writeln!(
            f,
            "{SUMMARY_HEAD} of {} ({} {read} read)",
            self.file, self.lines_read
        )?;
        write!(f, "  published:       {}", Counted(self.published))?;
        if let Some(cut) = &self.cut {
            write!(f, "\n  cut short:       {cut}")?;
        }
        if let Some(reason) = &self.stopped {
            write!(f, "\n  stopped early:   {reason}")?;
        }
        if let Some((config, counts)) = &self.reordering {
            let window = config.window_ns as f64 * 1e-9;
            write!(
                f,
                "\n  reordered:       {} (read after newer ones, put in time order; \
                 window {window} s)",
                Counted(counts.reordered)
            )?;
            write!(
                f,
                "\n  dropped late:    {} (older than records already published)",
                Counted(counts.late)
            )?;
            write!(
                f,
                "\n  dropped repeats: {} (stamp already published)",
                Counted(counts.duplicate)
            )?;
            if counts.restamped > 0 {
                write!(
                    f,
                    "\n  restamped:       {} scans (stamped after scans the log has after them: \
                     replayed in the log's order, their own stamps kept for the results)",
                    counts.restamped
                )?;
            }
            if counts.forced_out.total() > 0 {
                write!(
                    f,
                    "\n  let out early:   {} (more than {} lines held; may be out of order)",
                    Counted(counts.forced_out),
                    config.max_held
                )?;
            }
        }
        let malformed = if self.recording {
            "bad messages:   "
        } else {
            "malformed lines:"
        };
        write!(f, "\n  {malformed} {}", self.malformed_total())?;
        if !self.malformed.is_empty() {
            write!(f, " skipped, by reason:")?;
        }
        for (category, count) in &self.malformed {
            write!(f, "\n    {category}: {count}")?;
        }
        if !self.not_replayed.is_empty() {
            let list: Vec<String> = self
                .not_replayed
                .iter()
                .map(|(name, count)| format!("{name} x{count}"))
                .collect();
            write!(f, "\n  not replayed:    {}", list.join(", "))?;
        }
        if self.odometry_unpublished > 0 {
            write!(
                f,
                "\n  not published:   {} odometry poses (--no-odometry)",
                self.odometry_unpublished
            )?;
        }
        if self.degradation.every.get() > 1 {
            write!(
                f,
                "\n  left out:        {} scans (--every {}: {})",
                self.scans_left_out, self.degradation.every, self.degradation
            )?;
        }
        if let Some(max) = self.degradation.max_range_m {
            write!(
                f,
                "\n  shortened:       {} beams beyond {max} m made no-returns (--max-range)",
                self.beams_shortened
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Malformation;

    #[test]
    fn a_summary_is_one_block_naming_every_loss() {
        let mut summary = ReplaySummary {
            file: "aces.clf".into(),
            lines_read: 14_762,
            published: Records {
                scans: 7374,
                odometry: 14_693,
            },
            reordering: Some((
                ReorderConfig::default(),
                ReorderCounts {
                    reordered: Records {
                        scans: 107,
                        odometry: 108,
                    },
                    duplicate: Records {
                        scans: 0,
                        odometry: 55,
                    },
                    restamped: 12,
                    ..ReorderCounts::default()
                },
            )),
            not_replayed: vec![("PARAM".into(), 4)],
            ..ReplaySummary::default()
        };
        for kind in [Malformation::MissingFields, Malformation::MissingFields] {
            summary.malformed_line(&LineError::new(7, kind, "FLASER: ...").in_record("FLASER"));
        }
        summary.malformed_line(&LineError::new(9, Malformation::NotARecord, "?"));
        assert_eq!(
            summary.to_string(),
            "lidar-replay: summary of aces.clf (14762 lines read)\n\
             \x20 published:       7374 scans, 14693 odometry poses\n\
             \x20 reordered:       107 scans, 108 odometry poses (read after newer ones, put \
             in time order; window 2 s)\n\
             \x20 dropped late:    none (older than records already published)\n\
             \x20 dropped repeats: 55 odometry poses (stamp already published)\n\
             \x20 restamped:       12 scans (stamped after scans the log has after them: \
             replayed in the log's order, their own stamps kept for the results)\n\
             \x20 malformed lines: 3 skipped, by reason:\n\
             \x20   FLASER: fields missing: 2\n\
             \x20   not a record of the format: 1\n\
             \x20 not replayed:    PARAM x4"
        );
    }

    #[test]
    fn a_log_in_line_order_has_no_reordering_lines() {
        let summary = ReplaySummary {
            file: "scans.csv".into(),
            lines_read: 400,
            published: Records {
                scans: 400,
                odometry: 0,
            },
            ..ReplaySummary::default()
        };
        assert_eq!(
            summary.to_string(),
            "lidar-replay: summary of scans.csv (400 lines read)\n\
             \x20 published:       400 scans\n\
             \x20 malformed lines: 0"
        );
    }

    #[test]
    fn what_a_degradation_left_out_is_said_and_not_counted_as_lost() {
        let summary = ReplaySummary {
            file: "aces.clf".into(),
            lines_read: 14_762,
            published: Records {
                scans: 2458,
                odometry: 14_693,
            },
            degradation: Degradation::new(3, Some(5.0)).unwrap(),
            scans_left_out: 4916,
            beams_shortened: 120_000,
            ..ReplaySummary::default()
        };
        assert_eq!(
            summary.to_string(),
            "lidar-replay: summary of aces.clf (14762 lines read)\n\
             \x20 published:       2458 scans, 14693 odometry poses\n\
             \x20 malformed lines: 0\n\
             \x20 left out:        4916 scans (--every 3: every 3rd scan, ranges to 5 m)\n\
             \x20 shortened:       120000 beams beyond 5 m made no-returns (--max-range)"
        );
        assert!(summary.losses().iter().all(|(_, n)| *n == 0));
    }
}
