//! The pipeline's topology as data: every stage, the topics it publishes and the topics it
//! reads. slam-launch takes from this table which stages a run starts, how many subscribers
//! each publisher waits for (`--subscribers`, a source's `--odometry-subscribers`) and how many readers each service is sized for
//! in /dev/shm ([`crate::shm_room`]); docs/ARCHITECTURE.md's topic table is checked against
//! it. A stage's own main opens the same topics; the table is what the launcher knows of it.

use ipc_types::shm::Readers;
use ipc_types::topic;

use crate::config::{RunConfig, SourceKind};

/// What the topology of a run depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunKind {
    pub source: SourceKind,
    /// The source publishes odometry.
    pub odometry: bool,
    /// slam-proc localizes on a saved map, weighting its particles by the scans' beams.
    pub localize: bool,
    /// The run has a saved map (`--map DIR`), to localize on or to map on top of.
    pub saved_map: bool,
    /// slam-record records every topic (`--record`).
    pub recorded: bool,
    /// slam-view serves the run live to Foxglove (`--foxglove`).
    pub viewed: bool,
}

impl RunKind {
    /// The kind of run `config` describes.
    pub fn of(config: &RunConfig) -> Self {
        Self {
            source: config.source,
            odometry: match config.source {
                SourceKind::Sim => config.sim.odometry,
                // The log may have none; a replay that publishes none only needs less.
                SourceKind::Replay => config.replay.odometry,
                SourceKind::Hokuyo => false,
            },
            localize: config.localize,
            saved_map: config.map.is_some(),
            recorded: config.record.enabled,
            viewed: config.foxglove.enabled,
        }
    }
}

/// A condition on the run under which a stage runs, publishes or reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    Always,
    /// The run's scans come from this source.
    Source(SourceKind),
    /// The source publishes odometry.
    Odometry,
    /// slam-proc localizes on a saved map.
    Localize,
    /// slam-proc maps (on a saved map or not): the run does not `--localize`.
    Mapping,
    /// The run has a saved map (`--map DIR`), localizing on it or mapping on top of it.
    SavedMap,
    /// The run is recorded.
    Recorded,
    /// The run is served live to Foxglove.
    Viewed,
    /// The run is recorded or served live: someone will look at it.
    Watched,
}

impl When {
    pub fn holds(self, run: &RunKind) -> bool {
        match self {
            When::Always => true,
            When::Source(source) => run.source == source,
            When::Odometry => run.odometry,
            When::Localize => run.localize,
            When::Mapping => !run.localize,
            When::SavedMap => run.saved_map,
            When::Recorded => run.recorded,
            When::Viewed => run.viewed,
            When::Watched => run.recorded || run.viewed,
        }
    }
}

/// What a stage does in the pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Publishes the scans (a simulator, a replay or a live driver).
    Source,
    /// Scans to features, and the scan-matching front end.
    Perception,
    /// The particle filter: poses and maps.
    Filter,
    /// Global SLAM: submaps, verified loop closures, the pose graph's path.
    Graph,
    /// Writes the run's results.
    Sink,
    /// Records every topic into `run.mcap`.
    Recorder,
    /// Serves the run live to Foxglove; reads lossy (`Inlet::open_lossy`).
    View,
}

impl Role {
    /// The stage reads lossy: no publisher waits for it, and none counts it among the
    /// subscribers it waits for. It still takes room in the shared memory.
    pub fn reads_lossy(self) -> bool {
        self == Role::View
    }
}

/// A topic a stage publishes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Publication {
    pub topic: &'static str,
    pub when: When,
}

/// A topic a stage reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reading {
    pub topic: &'static str,
    pub when: When,
    /// The stage reads the topic if some stage publishes it, and does without otherwise
    /// (`Inlet::try_open`): ground truth, odometry.
    pub if_published: bool,
}

/// One process of the pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stage {
    /// The executable, which is also the stage's name on the console.
    pub binary: &'static str,
    pub role: Role,
    /// When the run has this stage.
    pub runs: When,
    pub publishes: &'static [Publication],
    pub reads: &'static [Reading],
    /// The topics whose subscribers the stage waits for before it publishes on them, each
    /// with the option that gives it their count.
    pub waits_for: &'static [Wait],
    /// When the run has a saved map (`--map DIR`), whether the stage is given it (as
    /// `--map DIR`): `None` never.
    pub saved_map: Option<When>,
}

/// A topic whose readers a stage waits for before it publishes on it, so that none of them
/// misses the first messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Wait {
    pub topic: &'static str,
    /// The stage's option that takes the number of readers.
    pub option: &'static str,
}

const fn waits(topic: &'static str) -> Wait {
    Wait {
        topic,
        option: "--subscribers",
    }
}

/// A source waits for its odometry's readers too (`stage_kit::SourceArgs`): they look for
/// the odometry once they have found the scans.
const SOURCE_WAITS: &[Wait] = &[
    waits(SCAN),
    Wait {
        topic: ODOMETRY,
        option: "--odometry-subscribers",
    },
];

const fn publishes(topic: &'static str) -> Publication {
    Publication {
        topic,
        when: When::Always,
    }
}

const fn reads(topic: &'static str) -> Reading {
    Reading {
        topic,
        when: When::Always,
        if_published: false,
    }
}

const fn reads_if_published(topic: &'static str) -> Reading {
    Reading {
        topic,
        when: When::Always,
        if_published: true,
    }
}

const SCAN: &str = topic::SCAN.name();
const ODOMETRY: &str = topic::ODOMETRY.name();
const GROUND_TRUTH: &str = topic::GROUND_TRUTH.name();
const WORLD_CORNERS: &str = topic::WORLD_CORNERS.name();
const FEATURES: &str = topic::FEATURES.name();
const POSE: &str = topic::POSE.name();
const PATH: &str = topic::PATH.name();
const MAP: &str = topic::MAP.name();
const GRAPH_PATH: &str = topic::GRAPH_PATH.name();
const GRAPH_GRID: &str = topic::GRAPH_GRID.name();
const PARTICLES: &str = topic::PARTICLES.name();
const MAP_PATH: &str = topic::MAP_PATH.name();
const MAP_GRID: &str = topic::MAP_GRID.name();

/// A topic published only for the recorder: a run without it does no work for it.
const fn for_the_recording(topic: &'static str) -> Publication {
    Publication {
        topic,
        when: When::Recorded,
    }
}

/// A topic published only for the recorder and the live view: a run with neither does no
/// work for it.
const fn for_the_eye(topic: &'static str) -> Publication {
    Publication {
        topic,
        when: When::Watched,
    }
}

/// A source's odometry, when the robot has some (and a replay is not told to drop it).
const SOURCE_ODOMETRY: Publication = Publication {
    topic: ODOMETRY,
    when: When::Odometry,
};

/// Every stage, in the order they start: consumers first, so that nothing a source
/// publishes finds no reader, and the source last.
pub const STAGES: &[Stage] = &[
    Stage {
        binary: "slam-view",
        role: Role::View,
        runs: When::Viewed,
        publishes: &[],
        reads: &[
            reads(SCAN),
            reads(FEATURES),
            reads(POSE),
            reads(MAP),
            reads(PATH),
            reads_if_published(GRAPH_PATH),
            reads_if_published(GRAPH_GRID),
            reads(PARTICLES),
        ],
        waits_for: &[],
        saved_map: None,
    },
    Stage {
        binary: "slam-record",
        role: Role::Recorder,
        runs: When::Recorded,
        publishes: &[],
        reads: &[
            reads(SCAN),
            reads_if_published(GROUND_TRUTH),
            reads_if_published(WORLD_CORNERS),
            reads_if_published(ODOMETRY),
            reads(FEATURES),
            reads(POSE),
            reads(MAP),
            reads(PATH),
            reads_if_published(GRAPH_PATH),
            reads_if_published(GRAPH_GRID),
            reads(PARTICLES),
            reads(MAP_PATH),
            reads(MAP_GRID),
        ],
        waits_for: &[],
        saved_map: None,
    },
    Stage {
        binary: "map-sink",
        role: Role::Sink,
        runs: When::Always,
        // The final path and grid as written, once they are: the recorder's last messages.
        publishes: &[for_the_recording(MAP_PATH), for_the_recording(MAP_GRID)],
        reads: &[
            reads(SCAN),
            reads_if_published(GROUND_TRUTH),
            reads_if_published(WORLD_CORNERS),
            reads(MAP),
            reads(POSE),
            reads(PATH),
            // The back end's path and grid are the final ones where the run has them.
            reads_if_published(GRAPH_PATH),
            reads_if_published(GRAPH_GRID),
        ],
        waits_for: &[],
        saved_map: Some(When::Mapping),
    },
    Stage {
        binary: "graph-proc",
        role: Role::Graph,
        // Its graph starts at the first scan; on a saved map, map-sink moves its path into
        // the map's frame, which the filter finds.
        runs: When::Mapping,
        // Its path and grid as they grow (its grid only for a recording) and at the end.
        publishes: &[publishes(GRAPH_PATH), publishes(GRAPH_GRID)],
        reads: &[reads(FEATURES), reads(SCAN)],
        waits_for: &[waits(GRAPH_PATH)],
        saved_map: None,
    },
    Stage {
        binary: "slam-proc",
        role: Role::Filter,
        runs: When::Always,
        publishes: &[
            publishes(POSE),
            publishes(MAP),
            publishes(PATH),
            for_the_eye(PARTICLES),
        ],
        reads: &[
            reads(FEATURES),
            // The beams fit the particles to a saved map's grid.
            Reading {
                topic: SCAN,
                when: When::SavedMap,
                if_published: false,
            },
        ],
        waits_for: &[waits(POSE)],
        saved_map: Some(When::Always),
    },
    Stage {
        binary: "feature-proc",
        role: Role::Perception,
        runs: When::Always,
        publishes: &[publishes(FEATURES)],
        reads: &[reads(SCAN), reads_if_published(ODOMETRY)],
        waits_for: &[waits(FEATURES)],
        saved_map: None,
    },
    Stage {
        binary: "lidar-sim",
        role: Role::Source,
        runs: When::Source(SourceKind::Sim),
        publishes: &[
            publishes(SCAN),
            publishes(GROUND_TRUTH),
            publishes(WORLD_CORNERS),
            SOURCE_ODOMETRY,
        ],
        reads: &[],
        waits_for: SOURCE_WAITS,
        saved_map: None,
    },
    Stage {
        binary: "lidar-replay",
        role: Role::Source,
        runs: When::Source(SourceKind::Replay),
        publishes: &[publishes(SCAN), SOURCE_ODOMETRY],
        reads: &[],
        waits_for: SOURCE_WAITS,
        saved_map: None,
    },
    Stage {
        binary: "lidar-hokuyo",
        role: Role::Source,
        runs: When::Source(SourceKind::Hokuyo),
        publishes: &[publishes(SCAN)],
        reads: &[],
        waits_for: &[waits(SCAN)],
        saved_map: None,
    },
];

/// Every topic of the pipeline, in the order of the services' table.
pub const TOPICS: &[&str] = &[
    SCAN,
    ODOMETRY,
    GROUND_TRUTH,
    WORLD_CORNERS,
    FEATURES,
    POSE,
    MAP,
    PATH,
    GRAPH_PATH,
    GRAPH_GRID,
    PARTICLES,
    MAP_PATH,
    MAP_GRID,
];

/// The stages a run of `run` starts, in their start order.
pub fn stages(run: &RunKind) -> impl Iterator<Item = &'static Stage> + '_ {
    STAGES.iter().filter(|stage| stage.runs.holds(run))
}

/// Whether a stage of the run publishes `topic`.
pub fn published(run: &RunKind, topic: &str) -> bool {
    stages(run).any(|stage| {
        stage
            .publishes
            .iter()
            .any(|p| p.topic == topic && p.when.holds(run))
    })
}

/// How many stages of the run read `topic` (when it is published) and are waited for:
/// every reader but a lossy one ([`Role::reads_lossy`]).
pub fn subscribers(run: &RunKind, topic: &str) -> usize {
    readers(run, topic)
        .filter(|stage| !stage.role.reads_lossy())
        .count()
}

/// The stages of the run that read `topic` (when it is published).
fn readers<'a>(run: &'a RunKind, topic: &'a str) -> impl Iterator<Item = &'static Stage> + 'a {
    stages(run).filter(move |stage| {
        stage
            .reads
            .iter()
            .any(|r| r.topic == topic && r.when.holds(run))
    })
}

/// The topics the run publishes, each with its readers, lossy ones too (each takes room in
/// the publisher's shared memory): the services it has.
pub fn services(run: &RunKind) -> Vec<(&'static str, Readers)> {
    TOPICS
        .iter()
        .filter(|topic| published(run, topic))
        .map(|&topic| {
            let lossy = readers(run, topic)
                .filter(|stage| stage.role.reads_lossy())
                .count();
            let all = readers(run, topic).count();
            let pipeline = all - lossy;
            (topic, Readers { pipeline, lossy })
        })
        .collect()
}

/// The stage's options that say how many subscribers it waits for in a run of `run`, each
/// with the readers of its topic, for the topics the stage publishes in that run.
pub fn waits_for_subscribers(stage: &Stage, run: &RunKind) -> Vec<(&'static str, usize)> {
    stage
        .waits_for
        .iter()
        .filter(|wait| {
            stage
                .publishes
                .iter()
                .any(|p| p.topic == wait.topic && p.when.holds(run))
        })
        .map(|wait| (wait.option, subscribers(run, wait.topic)))
        .collect()
}

/// Whether `stage` is given the run's saved map (`--map DIR`), when it has one: slam-proc
/// starts from its landmarks or localizes on it, map-sink starts its grid from the saved
/// grid when mapping on it.
pub fn takes_saved_map(stage: &Stage, run: &RunKind) -> bool {
    stage.saved_map.is_some_and(|when| when.holds(run))
}

/// The stages of every kind of run that read `topic`, as `binary` or `binary (condition)`,
/// for the documentation's table.
pub fn readers_text(topic: &str) -> Vec<String> {
    // Downstream order: the source's readers first.
    STAGES
        .iter()
        .rev()
        .flat_map(|stage| {
            stage
                .reads
                .iter()
                .filter(move |r| r.topic == topic)
                .map(move |r| {
                    let mut conditions = Vec::new();
                    if let Some(text) = condition_text(stage.runs) {
                        conditions.push(text);
                    }
                    if let Some(text) = condition_text(r.when) {
                        conditions.push(text);
                    }
                    if r.if_published {
                        conditions.push("if published");
                    }
                    if stage.role.reads_lossy() {
                        conditions.push("lossy");
                    }
                    if conditions.is_empty() {
                        stage.binary.to_owned()
                    } else {
                        format!("{} ({})", stage.binary, conditions.join(", "))
                    }
                })
        })
        .collect()
}

/// The stages that publish `topic`, as `binary` or `binary (condition)`.
pub fn publishers_text(topic: &str) -> Vec<String> {
    STAGES
        .iter()
        .flat_map(|stage| {
            stage
                .publishes
                .iter()
                .filter(move |p| p.topic == topic)
                .map(move |p| match condition_text(p.when) {
                    Some(text) => format!("{} ({text})", stage.binary),
                    None => stage.binary.to_owned(),
                })
        })
        .collect()
}

fn condition_text(when: When) -> Option<&'static str> {
    match when {
        When::Always | When::Source(_) => None,
        When::Odometry => Some("with odometry"),
        When::Localize => Some("--localize"),
        When::Mapping => Some("without --localize"),
        When::SavedMap => Some("--map"),
        When::Recorded => Some("--record"),
        When::Viewed => Some("--foxglove"),
        When::Watched => Some("--record or --foxglove"),
    }
}

/// The topic table of docs/ARCHITECTURE.md: each topic, who publishes it, who reads it.
pub fn markdown_table() -> String {
    let mut text = String::from("| topic | published by | read by |\n|---|---|---|\n");
    for topic in TOPICS {
        text.push_str(&format!(
            "| `{topic}` | {} | {} |\n",
            publishers_text(topic).join(", "),
            readers_text(topic).join(", ")
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every_run() -> Vec<RunKind> {
        let mut runs = Vec::new();
        for source in [SourceKind::Sim, SourceKind::Replay, SourceKind::Hokuyo] {
            for odometry in [false, true] {
                for (localize, saved_map) in [(false, false), (false, true), (true, true)] {
                    for (recorded, viewed) in
                        [(false, false), (true, false), (false, true), (true, true)]
                    {
                        runs.push(RunKind {
                            source,
                            odometry: odometry && source != SourceKind::Hokuyo,
                            localize,
                            saved_map,
                            recorded,
                            viewed,
                        });
                    }
                }
            }
        }
        runs
    }

    const PLAIN: RunKind = RunKind {
        source: SourceKind::Sim,
        odometry: false,
        localize: false,
        saved_map: false,
        recorded: false,
        viewed: false,
    };

    #[test]
    fn every_topic_read_has_exactly_one_publisher() {
        for run in every_run() {
            for stage in stages(&run) {
                for reading in stage.reads.iter().filter(|r| r.when.holds(&run)) {
                    let publishers = stages(&run)
                        .flat_map(|s| s.publishes)
                        .filter(|p| p.topic == reading.topic && p.when.holds(&run))
                        .count();
                    let expected = if reading.if_published { 0..=1 } else { 1..=1 };
                    assert!(
                        expected.contains(&publishers),
                        "{} reads {} with {publishers} publishers in {run:?}",
                        stage.binary,
                        reading.topic
                    );
                }
            }
        }
        for topic in TOPICS {
            assert_eq!(
                STAGES
                    .iter()
                    .filter(|s| s.role != Role::Source)
                    .flat_map(|s| s.publishes)
                    .filter(|p| p.topic == *topic)
                    .count()
                    + usize::from(
                        STAGES.iter().any(|s| s.role == Role::Source
                            && s.publishes.iter().any(|p| p.topic == *topic))
                    ),
                1,
                "{topic}: one stage, or the sources, publish it"
            );
        }
    }

    #[test]
    fn every_run_has_one_source_and_every_stage_publishing_is_read() {
        for run in every_run() {
            assert_eq!(
                stages(&run).filter(|s| s.role == Role::Source).count(),
                1,
                "{run:?}"
            );
            assert_eq!(
                stages(&run).last().map(|s| s.role),
                Some(Role::Source),
                "the source starts last"
            );
            for (topic, readers) in services(&run) {
                assert!(
                    readers.pipeline + readers.lossy > 0,
                    "{topic} has no reader in {run:?}"
                );
            }
        }
    }

    /// [`services`] with the number of (pipeline) readers of each topic.
    fn readers_of(run: &RunKind) -> Vec<(&'static str, usize)> {
        services(run)
            .into_iter()
            .map(|(topic, readers)| {
                assert_eq!(readers.lossy, 0, "{topic}");
                (topic, readers.pipeline)
            })
            .collect()
    }

    #[test]
    fn subscriber_counts_per_configuration() {
        // The scans' readers (and the features' and the poses'), as `--subscribers`.
        let counts = |run: &RunKind| -> Vec<(&str, usize)> {
            stages(run)
                .flat_map(|s| {
                    waits_for_subscribers(s, run)
                        .into_iter()
                        .filter(|(option, _)| *option == "--subscribers")
                        .map(|(_, n)| (s.binary, n))
                })
                .collect()
        };
        assert_eq!(
            counts(&PLAIN),
            [
                ("graph-proc", 1),
                ("slam-proc", 1),
                ("feature-proc", 2),
                ("lidar-sim", 3)
            ]
        );
        assert_eq!(
            readers_of(&PLAIN),
            [
                (SCAN, 3),
                (GROUND_TRUTH, 1),
                (WORLD_CORNERS, 1),
                (FEATURES, 2),
                (POSE, 1),
                (MAP, 1),
                (PATH, 1),
                (GRAPH_PATH, 1),
                (GRAPH_GRID, 1)
            ]
        );
        let recorded = RunKind {
            recorded: true,
            ..PLAIN
        };
        assert_eq!(
            counts(&recorded),
            [
                ("graph-proc", 2),
                ("slam-proc", 2),
                ("feature-proc", 3),
                ("lidar-sim", 4)
            ]
        );
        assert!(
            readers_of(&recorded)
                .iter()
                .zip(readers_of(&PLAIN))
                .all(|(with, without)| with.0 == without.0 && with.1 == without.1 + 1),
            "the recorder reads every topic"
        );
        let localize = RunKind {
            source: SourceKind::Replay,
            localize: true,
            saved_map: true,
            ..PLAIN
        };
        assert_eq!(
            counts(&localize),
            [("slam-proc", 1), ("feature-proc", 1), ("lidar-replay", 3)]
        );
        assert_eq!(
            readers_of(&localize),
            [(SCAN, 3), (FEATURES, 1), (POSE, 1), (MAP, 1), (PATH, 1)]
        );
        let odometry = RunKind {
            odometry: true,
            ..PLAIN
        };
        assert_eq!(counts(&odometry), counts(&PLAIN));
        let with: Vec<_> = readers_of(&odometry);
        assert_eq!(with.len(), readers_of(&PLAIN).len() + 1);
        assert!(with.contains(&(ODOMETRY, 1)), "feature-proc reads it");
        let recorded_odometry = RunKind {
            recorded: true,
            ..odometry
        };
        assert!(readers_of(&recorded_odometry).contains(&(ODOMETRY, 2)));
    }

    #[test]
    fn a_source_waits_for_every_reader_of_its_odometry() {
        let source_waits = |run: &RunKind| {
            let source = stages(run)
                .find(|s| s.role == Role::Source)
                .expect("one source");
            waits_for_subscribers(source, run)
        };
        // Without odometry there is none to wait for; with it, feature-proc reads it, and
        // slam-record too when the run is recorded.
        type Waits = &'static [(&'static str, usize)];
        let expected: [(bool, bool, Waits); 4] = [
            (false, false, &[("--subscribers", 3)]),
            (false, true, &[("--subscribers", 4)]),
            (
                true,
                false,
                &[("--subscribers", 3), ("--odometry-subscribers", 1)],
            ),
            (
                true,
                true,
                &[("--subscribers", 4), ("--odometry-subscribers", 2)],
            ),
        ];
        for source in [SourceKind::Sim, SourceKind::Replay] {
            for (odometry, recorded, waits) in expected {
                let run = RunKind {
                    source,
                    odometry,
                    recorded,
                    ..PLAIN
                };
                assert_eq!(source_waits(&run), waits, "{run:?}");
            }
        }
        let hokuyo = RunKind {
            source: SourceKind::Hokuyo,
            ..PLAIN
        };
        assert_eq!(source_waits(&hokuyo), [("--subscribers", 3)]);
        for run in every_run() {
            for stage in stages(&run) {
                for (option, readers) in waits_for_subscribers(stage, &run) {
                    assert!(readers > 0, "{} {option} 0 in {run:?}", stage.binary);
                }
            }
        }
    }

    #[test]
    fn the_recording_s_own_topics_exist_only_when_recorded() {
        let own = [MAP_PATH, MAP_GRID];
        for run in every_run() {
            for topic in own {
                assert_eq!(published(&run, topic), run.recorded, "{topic} in {run:?}");
                assert_eq!(
                    subscribers(&run, topic),
                    usize::from(run.recorded),
                    "{topic}"
                );
            }
            // The cloud is for the recording and for the live view.
            let watched = run.recorded || run.viewed;
            assert_eq!(published(&run, PARTICLES), watched, "{run:?}");
        }
        let recorded = RunKind {
            recorded: true,
            ..PLAIN
        };
        let publisher = |topic: &str| {
            stages(&recorded)
                .find(|s| s.publishes.iter().any(|p| p.topic == topic))
                .map(|s| s.binary)
        };
        assert_eq!(publisher(PARTICLES), Some("slam-proc"));
        assert_eq!(publisher(MAP_PATH), Some("map-sink"));
        assert_eq!(publisher(MAP_GRID), Some("map-sink"));
    }

    #[test]
    fn hokuyo_publishes_scans_only() {
        let run = RunKind {
            source: SourceKind::Hokuyo,
            ..PLAIN
        };
        assert_eq!(
            services(&run).iter().map(|s| s.0).collect::<Vec<_>>(),
            [SCAN, FEATURES, POSE, MAP, PATH, GRAPH_PATH, GRAPH_GRID]
        );
    }

    #[test]
    fn the_saved_map_goes_to_the_filter_and_when_mapping_to_the_sink() {
        for run in every_run() {
            let given: Vec<&str> = stages(&run)
                .filter(|s| takes_saved_map(s, &run))
                .map(|s| s.binary)
                .collect();
            let expected: &[&str] = if run.localize {
                &["slam-proc"]
            } else {
                &["map-sink", "slam-proc"]
            };
            assert_eq!(given, expected, "{run:?}");
        }
    }

    #[test]
    fn every_topic_has_a_service_size() {
        for topic in TOPICS {
            assert!(
                ipc_types::shm::service_size(
                    topic,
                    ipc_types::Delivery::Lossless,
                    Readers::stages(1)
                )
                .is_some(),
                "{topic}"
            );
        }
    }

    #[test]
    fn the_architecture_doc_shows_this_table() {
        let doc = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../docs/ARCHITECTURE.md"
        ));
        let table = markdown_table();
        assert!(
            doc.contains(&table),
            "docs/ARCHITECTURE.md's topic table is not the topology's; it should read:\n{table}"
        );
    }

    #[test]
    fn the_live_view_is_never_waited_for_but_takes_its_room() {
        for run in every_run().into_iter().filter(|r| r.viewed) {
            let unviewed = RunKind {
                viewed: false,
                ..run
            };
            let waits = |run: &RunKind| -> Vec<Vec<(&str, usize)>> {
                stages(run)
                    .filter(|s| s.role != Role::View)
                    .map(|s| waits_for_subscribers(s, run))
                    .collect()
            };
            // The cloud is published for the view alone when the run is not recorded.
            if run.recorded {
                assert_eq!(waits(&run), waits(&unviewed), "{run:?}");
            }
            let view = stages(&run)
                .find(|s| s.role == Role::View)
                .expect("a viewed run has the view");
            for (topic, readers) in services(&run) {
                let viewed = view.reads.iter().any(|r| r.topic == topic);
                let expected = Readers {
                    pipeline: subscribers(&run, topic),
                    lossy: usize::from(viewed),
                };
                assert_eq!(readers, expected, "{topic} in {run:?}");
            }
        }
        let viewed = RunKind {
            viewed: true,
            ..PLAIN
        };
        assert!(published(&viewed, PARTICLES));
        assert_eq!(subscribers(&viewed, PARTICLES), 0, "only the view reads it");
        assert_eq!(
            stages(&viewed).map(|s| s.binary).next(),
            Some("slam-view"),
            "it starts first, the source last"
        );
    }
}
