//! Which stage has stalled, from the counts every stage reports (`ipc_types::progress`).
//!
//! map-sink's status line only says that the pipeline as a whole stopped moving, and in
//! lockstep it always stops as a whole: every publisher waits until each of its
//! subscribers has taken the previous message (a queue of one), so when one stage freezes,
//! the stages upstream of it block in `publish` and the stages downstream of it wait for
//! input. Every stage then makes no progress; only one of them is the cause.
//!
//! The counts tell them apart. A stage has *pending input* when a topic it reads has had
//! more messages sent than it has received: a message sits in its queue. Downstream of a
//! frozen stage nothing is pending (it sent them nothing more). The frozen stage has its
//! input pending (its upstream put the next message in its queue before blocking on the
//! one after). Upstream of it the stages have input pending too, but only because they
//! are blocked in `publish` to a stage that has input pending from them: they are waiting,
//! not stalled. So the stalled stage is the one that has input pending and sends to no
//! stage that has input pending from it. When no stage has input pending, the source is
//! the one not moving: the next scan is its to send.
//!
//! In real time nothing blocks and messages may be dropped (a subscriber's queue keeps the
//! newest), so sent > received proves nothing by itself there: a stage counts as having
//! input pending only when its input has been sent to since it last moved. The source is
//! not judged in real time: a live sensor may be silent for its own reasons (it says so
//! itself) and a slow rate is silent by design.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use ipc_types::progress::{self, Direction};

/// When a stage that makes no progress is reported, and when it fails the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StallLimits {
    /// Reported on the console once a stage has made no progress for this long.
    pub warning: Duration,
    /// The run fails once a stage has made no progress for this long.
    pub limit: Duration,
    /// Lossless delivery: every publisher waits for its subscribers.
    pub lockstep: bool,
}

/// What the watch found.
#[derive(Debug, Clone, PartialEq)]
pub enum StallReport {
    /// A stage has made no progress for the warning time.
    Stalled { stage: String, message: String },
    /// A stage reported as stalled moved again.
    Resumed { stage: String, after: Duration },
    /// A stage has made no progress for the limit: the run fails with `message`.
    Failed { stage: String, message: String },
}

/// One stage as the watch sees it.
#[derive(Debug, Clone)]
struct Watched {
    name: String,
    counts: BTreeMap<(Direction, String), u64>,
    /// When a count of this stage last changed.
    moved: Instant,
    /// Since when the stage has been the one to move (input pending, or the source with
    /// nothing pending anywhere); `None` while it is not.
    due_since: Option<Instant>,
    /// Reported as stalled, and not moved since.
    warned: bool,
}

impl Watched {
    fn count(&self, direction: Direction, topic: &str) -> Option<u64> {
        self.counts.get(&(direction, topic.to_owned())).copied()
    }

    fn topics(&self, direction: Direction) -> impl Iterator<Item = &str> {
        self.counts
            .keys()
            .filter(move |(d, _)| *d == direction)
            .map(|(_, topic)| topic.as_str())
    }
}

/// Watches every stage's counts for a stage that stopped moving.
#[derive(Debug, Clone)]
pub struct StallWatch {
    stages: Vec<Watched>,
    source: usize,
    limits: StallLimits,
}

impl StallWatch {
    /// For stages called `names`, `source` being the index of the scan source.
    pub fn new(names: &[String], source: usize, limits: StallLimits, now: Instant) -> Self {
        Self {
            stages: names
                .iter()
                .map(|name| Watched {
                    name: name.clone(),
                    counts: BTreeMap::new(),
                    moved: now,
                    due_since: None,
                    warned: false,
                })
                .collect(),
            source,
            limits,
        }
    }

    /// Starts every clock afresh: nothing counts as a stall before every stage is ready.
    pub fn restart(&mut self, now: Instant) {
        for stage in &mut self.stages {
            stage.moved = now;
            stage.due_since = None;
        }
    }

    /// Takes in a progress line of stage `index` (without its first word).
    pub fn update(&mut self, index: usize, rest: &str, now: Instant) -> Option<StallReport> {
        let stage = self.stages.get_mut(index)?;
        let mut moved = false;
        for (direction, topic, count) in progress::parse(rest) {
            let old = stage.counts.insert((direction, topic), count);
            moved |= old != Some(count);
        }
        if !moved {
            return None;
        }
        let stalled_for = stage.due_since.map(|due| now - due.max(stage.moved));
        stage.moved = now;
        if std::mem::take(&mut stage.warned) {
            return Some(StallReport::Resumed {
                stage: stage.name.clone(),
                after: stalled_for.unwrap_or_default(),
            });
        }
        None
    }

    /// The most any stage has sent on `topic`, and who sent it.
    fn sent(&self, topic: &str) -> Option<(u64, &Watched)> {
        self.stages
            .iter()
            .filter_map(|s| Some((s.count(Direction::Out, topic)?, s)))
            .max_by_key(|(count, _)| *count)
    }

    /// The topics stage `index` has input pending on.
    fn pending(&self, index: usize) -> Vec<String> {
        let stage = &self.stages[index];
        stage
            .topics(Direction::In)
            .filter(|topic| {
                let (Some(received), Some((sent, sender))) =
                    (stage.count(Direction::In, topic), self.sent(topic))
                else {
                    return false;
                };
                sent > received && (self.limits.lockstep || sender.moved > stage.moved)
            })
            .map(str::to_owned)
            .collect()
    }

    /// Looks for a stalled stage; `running[i]` is false once stage `i` has exited.
    pub fn check(&mut self, running: &[bool], now: Instant) -> Vec<StallReport> {
        let is_running = |i: usize| running.get(i).copied().unwrap_or(false);
        let pending: Vec<Vec<String>> = (0..self.stages.len())
            .map(|i| {
                if is_running(i) {
                    self.pending(i)
                } else {
                    Vec::new()
                }
            })
            .collect();
        // Input pending only because it is blocked sending to a stage that has input
        // pending from it: it waits, the other one is stuck (see the module's text).
        let waits_on_another = |i: usize| {
            self.stages[i].topics(Direction::Out).any(|topic| {
                pending
                    .iter()
                    .enumerate()
                    .any(|(j, topics)| j != i && topics.iter().any(|t| t == topic))
            })
        };
        let nothing_pending = pending.iter().all(Vec::is_empty);
        let due: Vec<Option<String>> = (0..self.stages.len())
            .map(|i| {
                if i == self.source {
                    let judged = self.limits.lockstep && is_running(i) && nothing_pending;
                    judged.then(|| "the next scan is its to send".to_owned())
                } else if waits_on_another(i) {
                    None
                } else {
                    let topic = pending[i].first()?;
                    Some(format!("a message waits for it on '{topic}'"))
                }
            })
            .collect();

        let mut reports = Vec::new();
        for (stage, why) in self.stages.iter_mut().zip(due) {
            let Some(why) = why else {
                stage.due_since = None;
                continue;
            };
            let since = *stage.due_since.get_or_insert(now);
            let stalled_for = now - since.max(stage.moved);
            // The configured times, not the measured ones: the supervisor looks every 50 ms.
            if stalled_for >= self.limits.limit {
                reports.push(StallReport::Failed {
                    stage: stage.name.clone(),
                    message: format!(
                        "{} stalled: no progress for {} s ({why})",
                        stage.name,
                        self.limits.limit.as_secs_f64()
                    ),
                });
            } else if stalled_for >= self.limits.warning && !stage.warned {
                stage.warned = true;
                reports.push(StallReport::Stalled {
                    stage: stage.name.clone(),
                    message: format!(
                        "{} has made no progress for {} s ({why})",
                        stage.name,
                        self.limits.warning.as_secs_f64()
                    ),
                });
            }
        }
        reports
    }

    /// When any stage last moved.
    pub fn last_moved(&self) -> Option<Instant> {
        self.stages.iter().map(|s| s.moved).max()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIM: usize = 3;

    /// The pipeline's stages in slam-launch's order, the source last, with `counts` reported
    /// at `now` (see [`report`]).
    fn watch(lockstep: bool, now: Instant, counts: [(u64, u64); 4]) -> StallWatch {
        let names: Vec<String> = ["map-sink", "slam-proc", "feature-proc", "lidar-sim"]
            .map(String::from)
            .to_vec();
        let limits = StallLimits {
            warning: Duration::from_secs(10),
            limit: Duration::from_secs(60),
            lockstep,
        };
        let mut w = StallWatch::new(&names, SIM, limits, now);
        report(&mut w, now, counts);
        w
    }

    /// Counts as the stages report them: `(received, sent)` of map-sink, slam-proc,
    /// feature-proc and the simulator (map-sink takes every scan the simulator sent).
    fn report(w: &mut StallWatch, now: Instant, counts: [(u64, u64); 4]) {
        let [
            (sink_in, _),
            (slam_in, slam_out),
            (features_in, features_out),
            (_, sim_out),
        ] = counts;
        w.update(
            0,
            &format!("in:lidar/scan={sim_out} in:slam/pose={sink_in}"),
            now,
        );
        w.update(
            1,
            &format!("in:perception/features={slam_in} out:slam/pose={slam_out}"),
            now,
        );
        w.update(
            2,
            &format!("in:lidar/scan={features_in} out:perception/features={features_out}"),
            now,
        );
        w.update(3, &format!("out:lidar/scan={sim_out}"), now);
    }

    fn names(reports: &[StallReport]) -> Vec<String> {
        reports
            .iter()
            .map(|r| match r {
                StallReport::Stalled { stage, .. }
                | StallReport::Resumed { stage, .. }
                | StallReport::Failed { stage, .. } => stage.clone(),
            })
            .collect()
    }

    #[test]
    fn in_lockstep_the_stage_holding_the_message_is_named_not_those_waiting_on_it() {
        let t0 = Instant::now();
        let running = [true; 4];
        let s = Duration::from_secs;
        // slam-proc froze after taking feature 100: feature-proc sent 101 and is blocked
        // sending 102 (it took scan 102), the simulator sent 103 and is blocked on 104.
        // feature-proc has input pending too, but only because slam-proc does.
        let mut w = watch(true, t0, [(100, 0), (100, 100), (102, 101), (0, 103)]);
        assert!(w.check(&running, t0).is_empty());
        assert!(w.check(&running, t0 + s(9)).is_empty());
        let reports = w.check(&running, t0 + s(10));
        assert_eq!(names(&reports), ["slam-proc"]);
        assert!(
            matches!(&reports[0], StallReport::Stalled { message, .. }
                if message == "slam-proc has made no progress for 10 s (a message waits for \
                               it on 'perception/features')"),
            "{reports:?}"
        );
        // Reported once, failed at the limit.
        assert!(w.check(&running, t0 + s(30)).is_empty());
        assert!(matches!(
            &w.check(&running, t0 + s(60))[..],
            [StallReport::Failed { stage, .. }] if stage == "slam-proc"
        ));

        // map-sink froze: everyone upstream waits on it.
        // It had taken pose 99; slam-proc sent pose 100 and took feature 101, feature-proc
        // sent feature 102 and took scan 103, the simulator sent scan 104.
        let mut w = watch(true, t0, [(99, 0), (101, 100), (103, 102), (0, 104)]);
        assert!(w.check(&running, t0).is_empty());
        assert_eq!(names(&w.check(&running, t0 + s(10))), ["map-sink"]);

        // The simulator froze: nothing is pending anywhere.
        let mut w = watch(true, t0, [(100, 0), (100, 100), (100, 100), (0, 100)]);
        assert!(w.check(&running, t0).is_empty());
        let reports = w.check(&running, t0 + s(10));
        assert_eq!(names(&reports), ["lidar-sim"]);
    }

    #[test]
    fn a_stage_that_moves_again_is_reported_as_resumed() {
        let t0 = Instant::now();
        let running = [true; 4];
        let s = Duration::from_secs;
        let mut w = watch(true, t0, [(100, 0), (100, 100), (100, 100), (0, 101)]);
        assert!(w.check(&running, t0).is_empty());
        assert_eq!(names(&w.check(&running, t0 + s(12))), ["feature-proc"]);
        let resumed = w.update(
            2,
            "in:lidar/scan=101 out:perception/features=101",
            t0 + s(13),
        );
        assert_eq!(
            resumed,
            Some(StallReport::Resumed {
                stage: "feature-proc".into(),
                after: s(13)
            })
        );
    }

    #[test]
    fn waiting_for_input_is_no_stall() {
        let t0 = Instant::now();
        let s = Duration::from_secs;
        // Everything went through and the source has ended: the stages wait for nothing.
        let mut w = watch(true, t0, [(100, 0), (100, 100), (100, 100), (0, 100)]);
        assert!(w.check(&[true, true, true, false], t0 + s(100)).is_empty());

        // Real time: drops left sent > received, but nothing was sent since; a slow or
        // silent source is not judged.
        let mut w = watch(false, t0, [(90, 0), (90, 90), (95, 90), (0, 100)]);
        assert!(w.check(&[true; 4], t0 + s(100)).is_empty());
        // A scan arrives after a long quiet spell and is taken at once: no stall.
        w.update(3, "out:lidar/scan=101", t0 + s(100));
        assert!(w.check(&[true; 4], t0 + s(100)).is_empty());
        w.update(
            2,
            "in:lidar/scan=96 out:perception/features=90",
            t0 + s(100),
        );
        assert!(w.check(&[true; 4], t0 + s(101)).is_empty());
        // Scans keep coming and feature-proc takes none: it is stalled.
        w.update(3, "out:lidar/scan=150", t0 + s(105));
        w.update(0, "in:lidar/scan=150", t0 + s(105));
        assert!(w.check(&[true; 4], t0 + s(106)).is_empty());
        assert_eq!(names(&w.check(&[true; 4], t0 + s(116))), ["feature-proc"]);
    }
}
