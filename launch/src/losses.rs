//! Every count of skipped or lost data, per stage, for one block at the end of a run.
//!
//! Each stage prints its counts on stdout as it ends (`losses key=count ...`, see
//! [`ipc_types::losses`]); map-sink's are its metrics (`frames_dropped`), which the launcher
//! reads anyway. The block lists the nonzero counts by stage, says "nothing lost" when every
//! stage reported and none lost anything, and names the stages that did not report (one
//! that died, or was killed, before its end).

/// The counts reported by each stage of a run.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Losses {
    stages: Vec<StageLosses>,
}

#[derive(Debug, Clone, PartialEq)]
struct StageLosses {
    name: String,
    reported: bool,
    counts: Vec<(String, u64)>,
}

impl Losses {
    /// For the stages called `names`, in the order they are listed.
    pub fn new(names: &[String]) -> Self {
        Self {
            stages: names
                .iter()
                .map(|name| StageLosses {
                    name: name.clone(),
                    reported: false,
                    counts: Vec::new(),
                })
                .collect(),
        }
    }

    /// Stage `index` reported `counts` (a later report replaces an earlier one).
    pub fn record(&mut self, index: usize, counts: Vec<(String, u64)>) {
        if let Some(stage) = self.stages.get_mut(index) {
            stage.reported = true;
            stage.counts = counts;
        }
    }

    /// Stage `name` counted `count` of `key` (map-sink's metrics); marks it reported.
    pub fn add(&mut self, name: &str, key: &str, count: u64) {
        if let Some(stage) = self.stages.iter_mut().find(|s| s.name == name) {
            stage.reported = true;
            stage.counts.push((key.to_owned(), count));
        }
    }

    /// The block: a head line and one indented line per stage with something to say.
    pub fn lines(&self) -> Vec<String> {
        let lost: Vec<String> = self
            .stages
            .iter()
            .filter_map(|stage| {
                let nonzero: Vec<String> = stage
                    .counts
                    .iter()
                    .filter(|(_, count)| *count > 0)
                    .map(|(key, count)| format!("{key}={count}"))
                    .collect();
                (!nonzero.is_empty()).then(|| format!("  {}: {}", stage.name, nonzero.join(" ")))
            })
            .collect();
        let silent: Vec<&str> = self
            .stages
            .iter()
            .filter(|s| !s.reported)
            .map(|s| s.name.as_str())
            .collect();
        let mut lines = Vec::new();
        if lost.is_empty() {
            lines.push(if silent.is_empty() {
                "slam-launch: nothing lost (every stage counted no skipped or lost data)".to_owned()
            } else {
                "slam-launch: nothing lost by the stages that reported".to_owned()
            });
        } else {
            lines.push(
                "slam-launch: data lost or skipped, per stage (why: logs/<stage>.log)".to_owned(),
            );
            lines.extend(lost);
        }
        if !silent.is_empty() {
            lines.push(format!(
                "  no counts from {} (ended before reporting)",
                silent.join(", ")
            ));
        }
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        ["map-sink", "slam-proc", "feature-proc", "lidar-replay"]
            .map(String::from)
            .to_vec()
    }

    #[test]
    fn nonzero_counts_are_listed_by_stage() {
        let mut losses = Losses::new(&names());
        losses.record(
            3,
            vec![("malformed_lines".into(), 2), ("late_scans".into(), 0)],
        );
        losses.record(2, vec![("skipped_scans".into(), 1)]);
        losses.record(1, Vec::new());
        losses.add("map-sink", "frames_dropped", 0);
        assert_eq!(
            losses.lines(),
            [
                "slam-launch: data lost or skipped, per stage (why: logs/<stage>.log)",
                "  feature-proc: skipped_scans=1",
                "  lidar-replay: malformed_lines=2",
            ]
        );
    }

    #[test]
    fn nothing_lost_is_said_only_when_every_stage_reported() {
        let mut losses = Losses::new(&names());
        for index in 1..4 {
            losses.record(index, vec![("anything".into(), 0)]);
        }
        assert_eq!(
            losses.lines(),
            [
                "slam-launch: nothing lost by the stages that reported",
                "  no counts from map-sink (ended before reporting)",
            ]
        );
        losses.add("map-sink", "frames_dropped", 0);
        assert_eq!(
            losses.lines(),
            ["slam-launch: nothing lost (every stage counted no skipped or lost data)"]
        );
    }
}
