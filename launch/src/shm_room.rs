//! Room in /dev/shm: the run's shared memory is checked against it before anything starts,
//! and a stage killed by SIGBUS is explained with it.

use std::path::Path;

use ipc_types::Delivery;
use ipc_types::shm::{self, RunShape, SHM_DIR, ShmError};

use crate::config::{RunConfig, SourceKind};

/// Environment variable that replaces the free space of /dev/shm in the start check, in
/// bytes; for tests, which cannot always mount a small tmpfs. A SIGBUS is still explained
/// with the real figure.
pub const FREE_OVERRIDE_ENV: &str = "SLAM_LAUNCH_SHM_FREE";

/// Which services the run will have.
pub fn run_shape(config: &RunConfig) -> RunShape {
    RunShape {
        delivery: if config.lockstep() {
            Delivery::Lossless
        } else {
            Delivery::Latest
        },
        simulated: config.source == SourceKind::Sim,
        odometry: match config.source {
            SourceKind::Sim => config.sim.odometry,
            // The log may have none; a replay that publishes none only needs less.
            SourceKind::Replay => config.replay.odometry,
            SourceKind::Hokuyo => false,
        },
        recorded: config.record.enabled,
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
    shm::check_room(run_shape(config), free)
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

    #[test]
    fn the_shape_follows_the_source_and_its_rate() {
        let mut config = RunConfig::default();
        assert_eq!(
            run_shape(&config),
            RunShape {
                delivery: Delivery::Lossless,
                simulated: true,
                odometry: false,
                recorded: false,
            }
        );
        config.source = SourceKind::Hokuyo;
        assert_eq!(
            run_shape(&config),
            RunShape {
                delivery: Delivery::Latest,
                simulated: false,
                odometry: false,
                recorded: false,
            }
        );
        config.source = SourceKind::Replay;
        config.replay.rate = 1.0;
        assert_eq!(
            run_shape(&config),
            RunShape {
                delivery: Delivery::Latest,
                simulated: false,
                odometry: true,
                recorded: false,
            }
        );
        config.record.enabled = true;
        assert!(run_shape(&config).recorded);
    }

    #[test]
    fn a_sigbus_names_the_free_space() {
        assert!(
            sigbus_explanation()
                .starts_with("killed by SIGBUS: shared memory exhausted? /dev/shm has "),
        );
    }
}
