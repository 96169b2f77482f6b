//! Room in /dev/shm: the run's shared memory is checked against it before anything starts,
//! and a stage killed by SIGBUS is explained with it.

use std::path::Path;

use ipc_types::Delivery;
use ipc_types::shm::{self, RunShape, SHM_DIR, ShmError};

use crate::config::RunConfig;
use crate::topology::{self, RunKind};

/// Environment variable that replaces the free space of /dev/shm in the start check, in
/// bytes; for tests, which cannot always mount a small tmpfs. A SIGBUS is still explained
/// with the real figure.
pub const FREE_OVERRIDE_ENV: &str = "SLAM_LAUNCH_SHM_FREE";

/// Which services the run will have: its delivery, and each topic published with its
/// readers, from the topology table.
pub fn run_shape(config: &RunConfig) -> RunShape {
    RunShape {
        delivery: if config.lockstep() {
            Delivery::Lossless
        } else {
            Delivery::Latest
        },
        topics: topology::services(&RunKind::of(config)),
    }
}

/// Refuses the run when /dev/shm cannot hold its shared memory (see [`ipc_types::shm`]).
pub fn check(config: &RunConfig) -> Result<(), ShmError> {
    let free = match std::env::var(FREE_OVERRIDE_ENV)
        .ok()
        .and_then(|v| v.trim().parse().ok())
    {
        Some(bytes) => bytes,
        None => shm::free_bytes(Path::new(SHM_DIR)).map_err(|source| ShmError::Statvfs {
            dir: SHM_DIR.to_owned(),
            source,
        })?,
    };
    shm::check_room(&run_shape(config), free)
}

/// How a death by SIGBUS reads: in a pipeline over shared memory it is almost always a page
/// of a full /dev/shm being written.
pub fn sigbus_explanation() -> String {
    match shm::free_bytes(Path::new(SHM_DIR)) {
        Ok(free) => format!(
            "killed by SIGBUS: shared memory exhausted? {SHM_DIR} has {} MiB free",
            free >> 20
        ),
        Err(e) => format!("killed by SIGBUS: shared memory exhausted? ({SHM_DIR}: {e})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use ipc_types::shm::Readers;

    use crate::config::SourceKind;

    fn topics(shape: &RunShape) -> Vec<&str> {
        shape.topics.iter().map(|t| t.0).collect()
    }

    #[test]
    fn the_shape_follows_the_source_and_its_rate() {
        let mut config = RunConfig::default();
        let shape = run_shape(&config);
        assert_eq!(shape.delivery, Delivery::Lossless);
        assert_eq!(
            topics(&shape),
            [
                "lidar/scan",
                "sim/ground_truth",
                "sim/world_corners",
                "perception/features",
                "slam/pose",
                "slam/map",
                "slam/path",
                "graph/path",
                "graph/grid"
            ]
        );
        config.source = SourceKind::Hokuyo;
        let shape = run_shape(&config);
        assert_eq!(shape.delivery, Delivery::Latest);
        assert!(!topics(&shape).contains(&"robot/odometry"));
        assert!(!topics(&shape).contains(&"sim/ground_truth"));
        config.source = SourceKind::Replay;
        config.replay.rate = 1.0;
        let shape = run_shape(&config);
        assert_eq!(shape.delivery, Delivery::Latest);
        assert!(
            shape
                .topics
                .contains(&("robot/odometry", Readers::stages(1)))
        );
        config.record.enabled = true;
        assert!(
            run_shape(&config)
                .topics
                .contains(&("robot/odometry", Readers::stages(2)))
        );
        // On a saved map, slam-proc reads the scans too (and mapping, so does graph-proc).
        config.map = Some("runs/office".into());
        assert_eq!(
            run_shape(&config).topics[0],
            ("lidar/scan", Readers::stages(5))
        );
    }

    #[test]
    fn a_recording_s_own_topics_take_little_shared_memory() {
        // The cloud and the grid travel in pieces the size of a scan (the path in chunks
        // twice that), so they add a few MiB at most, in lockstep and in real time, to what
        // one more reader of every topic (the recorder) takes.
        for rate in [0.0, 40.0] {
            let mut config = RunConfig::default();
            config.sim.rate = rate;
            let plain = shm::pipeline_bytes(&run_shape(&config));
            config.record.enabled = true;
            let shape = run_shape(&config);
            for topic in ["slam/particles", "map/path", "map/grid"] {
                assert!(
                    shape.topics.contains(&(topic, Readers::stages(1))),
                    "{topic}"
                );
            }
            let own: u64 = shm::pipeline_services(&shape)
                .iter()
                .filter(|s| ["slam/particles", "map/path", "map/grid"].contains(&s.topic))
                .map(|s| s.bytes)
                .sum();
            assert!(own < 4 << 20, "{own} bytes for the recording's own topics");
            assert!(shm::pipeline_bytes(&shape) < plain * 2, "{rate}");
        }
    }

    #[test]
    fn the_live_view_reads_lossy_with_room_for_its_deeper_queues() {
        for rate in [0.0, 40.0] {
            let mut config = RunConfig::default();
            config.sim.rate = rate;
            let plain = run_shape(&config);
            let mut viewed = config.clone();
            viewed.foxglove.enabled = true;
            let viewed = run_shape(&viewed);
            let scans = &viewed.topics[0];
            assert_eq!(scans.0, "lidar/scan");
            assert_eq!(scans.1.lossy, 1);
            assert_eq!(scans.1.pipeline, plain.topics[0].1.pipeline);
            config.record.enabled = true;
            let recorded = run_shape(&config);
            let more = |shape| shm::pipeline_bytes(shape) - shm::pipeline_bytes(&plain);
            if rate == 0.0 {
                // About 2 MiB for each of the topics it reads, where a stage has one message.
                assert!(
                    (4 << 20..24 << 20).contains(&more(&viewed)),
                    "{}",
                    more(&viewed)
                );
            } else {
                // In real time a stage's queue is as deep: no more than the recorder takes.
                assert!(more(&viewed) <= more(&recorded));
            }
        }
    }

    #[test]
    fn a_sigbus_names_the_free_space() {
        assert!(
            sigbus_explanation()
                .starts_with("killed by SIGBUS: shared memory exhausted? /dev/shm has "),
        );
    }
}
