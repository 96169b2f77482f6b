//! A stage's closing summary: the block a stage writes to stderr as it ends, shown on the
//! console when the run ends.
//!
//! A stage's stderr goes to its log file, and to the console only when it dies; what it has
//! to say at the end of a good run (lidar-replay: what it could not publish, and why) would
//! stay in a file nobody opens. So a stderr line that starts with `<stage>: summary` opens a
//! block, the lines indented by two spaces after it belong to it, and the last such block of
//! each stage is printed after the run.

/// Collects the last summary block from a stage's stderr lines, as they come.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClosingSummary {
    head: String,
    lines: Vec<String>,
    open: bool,
}

impl ClosingSummary {
    /// For the stage called `stage` (its stderr lines start with `stage: `).
    pub fn new(stage: &str) -> Self {
        Self {
            head: format!("{stage}: summary"),
            lines: Vec::new(),
            open: false,
        }
    }

    /// Takes in the next stderr line.
    pub fn take(&mut self, line: &str) {
        if line.starts_with(&self.head) {
            self.lines = vec![line.to_owned()];
            self.open = true;
        } else if self.open && line.starts_with("  ") {
            self.lines.push(line.to_owned());
        } else {
            self.open = false;
        }
    }

    /// The last block, head first; empty when the stage wrote none.
    pub fn lines(&self) -> &[String] {
        &self.lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_indented_block_after_the_head_is_kept() {
        let mut summary = ClosingSummary::new("lidar-replay");
        for line in [
            "lidar-replay: log.clf: line 7: FLASER: fields missing (skipped)",
            "lidar-replay: summary of a.clf (3 lines read)",
            "  published:       1 scans",
            "lidar-replay: something else",
            "  not part of it",
            "other-stage: summary of nothing",
            "lidar-replay: summary of b.clf (9 lines read)",
            "  published:       2 scans",
            "    FLASER: fields missing: 1",
        ] {
            summary.take(line);
        }
        assert_eq!(
            summary.lines(),
            [
                "lidar-replay: summary of b.clf (9 lines read)",
                "  published:       2 scans",
                "    FLASER: fields missing: 1",
            ]
        );
        assert!(ClosingSummary::new("map-sink").lines().is_empty());
    }
}
