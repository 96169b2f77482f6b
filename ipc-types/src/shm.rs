//! The shared memory a run's services take in /dev/shm, and whether the file system has it.
//!
//! iceoryx2 gives every publisher a data segment, a file in /dev/shm with a slot for every
//! sample the service could ever hold at once (each of [`crate::transport`]'s 16 possible
//! subscribers' queue and the samples it may hold while reading, the history, the samples
//! the publisher may loan). The file is sparse: a page is taken from the tmpfs when it is
//! first written, and a process that writes one when the tmpfs is full dies of SIGBUS,
//! wherever it happens to be. Freed slots are handed out again last in, first out, so the
//! slots ever written are at most the most ever in use together: the queues and borrowed
//! samples of the subscribers a run really has, the history and the loans. That is the
//! figure a run is checked against before it starts (the sparse files' full size, sixteen
//! subscribers' worth, would refuse runs that fit: a lockstep office run that makes 54 MB of
//! files runs in a 3 MiB /dev/shm).

use std::path::Path;

use crate::topic::{self, Topic};
use crate::transport::{Delivery, MAX_SUBSCRIBERS, lossy_queue, subscriber_queue};

/// Where iceoryx2 keeps its shared memory.
pub const SHM_DIR: &str = "/dev/shm";

/// Samples a subscriber may hold while it reads them (iceoryx2 0.10's default, which the
/// transport keeps).
const SUBSCRIBER_MAX_BORROWED: usize = 2;
/// Samples a publisher may loan before it sends (iceoryx2 0.10's default, kept).
const PUBLISHER_MAX_LOANED: usize = 2;
/// Bytes iceoryx2 adds to each sample: its header before the payload and the padding to the
/// payload's alignment. Measured from the segment files' sizes (LaserScan: 65 687 bytes a
/// slot for a 65 632-byte message), rounded up.
const SAMPLE_OVERHEAD: u64 = 64;
/// Every file of a run that is not a data segment (service descriptions, port and
/// connection management, events): a few hundred of at most a few KiB each, rounded up.
const MANAGEMENT_BYTES: u64 = 2 << 20;

/// Sample slots of one publisher's data segment that `subscribers` subscribers can have in
/// use together (iceoryx2's `required_amount_of_samples_per_data_segment` for the service
/// the transport creates, with `subscribers` in place of its maximum; with the maximum it is
/// the segment file's slot count).
pub fn sample_slots(delivery: Delivery, history: usize, subscribers: usize) -> u64 {
    let per_subscriber = subscriber_queue(delivery, history) + SUBSCRIBER_MAX_BORROWED;
    (subscribers.min(MAX_SUBSCRIBERS) * per_subscriber + history + PUBLISHER_MAX_LOANED) as u64
}

/// Sample slots `lossy` lossy subscribers of a topic of `T` can have in use together,
/// each with its deeper queue ([`crate::Inlet::open_lossy`]).
pub fn lossy_slots<T>(delivery: Delivery, history: usize, lossy: usize) -> u64 {
    (lossy * (lossy_queue::<T>(delivery, history) + SUBSCRIBER_MAX_BORROWED)) as u64
}

/// Bytes of one publisher's data segment on a topic of `T` that `subscribers` pipeline
/// subscribers and `lossy` lossy ones can have written.
pub fn segment_bytes<T>(delivery: Delivery, history: usize, readers: Readers) -> u64 {
    let slot = std::mem::size_of::<T>() as u64 + SAMPLE_OVERHEAD;
    (sample_slots(delivery, history, readers.pipeline)
        + lossy_slots::<T>(delivery, history, readers.lossy))
        * slot
}

/// The subscribers of one topic in a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Readers {
    /// Stages of the pipeline.
    pub pipeline: usize,
    /// Lossy readers (the live view).
    pub lossy: usize,
}

impl Readers {
    /// `n` stages of the pipeline and no lossy reader.
    pub const fn stages(n: usize) -> Self {
        Self {
            pipeline: n,
            lossy: 0,
        }
    }
}

/// One service of a run and the bytes its publisher's segment takes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceSize {
    pub topic: &'static str,
    pub bytes: u64,
}

fn service<T>(
    topic: Topic<T>,
    delivery: Delivery,
    history: usize,
    readers: Readers,
) -> ServiceSize {
    ServiceSize {
        topic: topic.name(),
        bytes: segment_bytes::<T>(delivery, history, readers),
    }
}

/// What decides which services a run has: the source's delivery, which every stage passes
/// on, and each topic the run publishes with the number of stages that read it (the
/// launcher's topology table, `launch::topology`, counts them).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunShape {
    pub delivery: Delivery,
    pub topics: Vec<(&'static str, Readers)>,
}

/// The service of the topic named `topic_name` with `readers`, as the stages
/// create it: the histories of their `Outlet::create` calls, the paths and the grid (sent
/// once, at the end) always lossless.
/// `None` for a name that is no topic of [`crate::topic`].
pub fn service_size(topic_name: &str, delivery: Delivery, readers: Readers) -> Option<ServiceSize> {
    let (d, n) = (delivery, readers);
    Some(match topic_name {
        t if t == topic::SCAN.name() => service(topic::SCAN, d, 0, n),
        t if t == topic::ODOMETRY.name() => service(topic::ODOMETRY, d, 0, n),
        t if t == topic::GROUND_TRUTH.name() => service(topic::GROUND_TRUTH, d, 0, n),
        t if t == topic::WORLD_CORNERS.name() => service(topic::WORLD_CORNERS, d, 1, n),
        t if t == topic::FEATURES.name() => service(topic::FEATURES, d, 0, n),
        t if t == topic::POSE.name() => service(topic::POSE, d, 0, n),
        t if t == topic::MAP.name() => service(topic::MAP, d, 1, n),
        t if t == topic::PATH.name() => service(topic::PATH, Delivery::Lossless, 0, n),
        t if t == topic::GRAPH_PATH.name() => service(topic::GRAPH_PATH, Delivery::Lossless, 0, n),
        t if t == topic::GRAPH_GRID.name() => service(topic::GRAPH_GRID, Delivery::Lossless, 0, n),
        t if t == topic::PARTICLES.name() => service(topic::PARTICLES, d, 0, n),
        t if t == topic::MAP_PATH.name() => service(topic::MAP_PATH, Delivery::Lossless, 0, n),
        t if t == topic::MAP_GRID.name() => service(topic::MAP_GRID, Delivery::Lossless, 0, n),
        _ => return None,
    })
}

/// The services of a pipeline run and what they can take.
pub fn pipeline_services(shape: &RunShape) -> Vec<ServiceSize> {
    shape
        .topics
        .iter()
        .filter_map(|&(name, readers)| service_size(name, shape.delivery, readers))
        .collect()
}

/// The bytes of /dev/shm a run of `shape` may take.
pub fn pipeline_bytes(shape: &RunShape) -> u64 {
    pipeline_services(shape)
        .iter()
        .map(|s| s.bytes)
        .sum::<u64>()
        + MANAGEMENT_BYTES
}

/// Not enough shared memory for a run, or no way to tell.
#[derive(Debug, thiserror::Error)]
pub enum ShmError {
    #[error(
        "{dir} has {} MiB free, but the run's shared memory may take {} MiB ({}); free some \
         or make it larger (docker run --shm-size, or mount -o remount,size=... {dir})",
        *free >> 20,
        mib(*need),
        largest(services)
    )]
    TooSmall {
        dir: String,
        free: u64,
        need: u64,
        services: Vec<ServiceSize>,
    },
    #[error("cannot read the free space of {dir}: {source}")]
    Statvfs { dir: String, source: std::io::Error },
}

/// Bytes as whole MiB, rounded up so a need is never understated (a free space is rounded
/// down).
pub fn mib(bytes: u64) -> u64 {
    bytes.div_ceil(1 << 20)
}

/// The largest services, for the message: where the memory goes.
fn largest(services: &[ServiceSize]) -> String {
    let mut sorted: Vec<&ServiceSize> = services.iter().collect();
    sorted.sort_by_key(|s| std::cmp::Reverse(s.bytes));
    sorted
        .iter()
        .take(3)
        .map(|s| format!("'{}' {} MiB", s.topic, mib(s.bytes)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Bytes free to an unprivileged writer on the file system of `dir` (statvfs).
pub fn free_bytes(dir: &Path) -> std::io::Result<u64> {
    let stat = nix::sys::statvfs::statvfs(dir).map_err(std::io::Error::from)?;
    // Both are 64-bit here, narrower on some targets.
    #[allow(clippy::useless_conversion)]
    let (blocks, size) = (
        u64::from(stat.blocks_available()),
        u64::from(stat.fragment_size()),
    );
    Ok(blocks.saturating_mul(size))
}

/// Refuses a run of `shape` when `free` bytes of /dev/shm cannot hold its services.
pub fn check_room(shape: &RunShape, free: u64) -> Result<(), ShmError> {
    let need = pipeline_bytes(shape);
    if need <= free {
        return Ok(());
    }
    Err(ShmError::TooSmall {
        dir: SHM_DIR.to_owned(),
        free,
        need,
        services: pipeline_services(shape),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_follow_the_transport_s_queues() {
        // Every possible subscriber: the segment file's slots (16 subscribers of a queue of
        // one and two borrowed samples, plus two loaned).
        assert_eq!(
            sample_slots(Delivery::Lossless, 0, MAX_SUBSCRIBERS),
            16 * 3 + 2
        );
        // The two scan subscribers of a run.
        assert_eq!(sample_slots(Delivery::Lossless, 0, 2), 2 * 3 + 2);
        // A history of one is kept besides the queue.
        assert_eq!(sample_slots(Delivery::Lossless, 1, 1), 3 + 1 + 2);
        // Real time: 40 queued per subscriber.
        assert_eq!(sample_slots(Delivery::Latest, 0, 2), 2 * 42 + 2);
        assert_eq!(sample_slots(Delivery::Latest, 0, 99), 16 * 42 + 2);
    }

    use crate::messages::LaserScan;

    const TOPICS: [&str; 8] = [
        topic::SCAN.name(),
        topic::ODOMETRY.name(),
        topic::GROUND_TRUTH.name(),
        topic::WORLD_CORNERS.name(),
        topic::FEATURES.name(),
        topic::POSE.name(),
        topic::MAP.name(),
        topic::PATH.name(),
    ];

    /// A lockstep simulated run's services: the scans read by feature-proc and map-sink,
    /// every other topic by one stage; `extra` more readers on every topic (a recorder).
    fn simulated(delivery: Delivery, extra: usize) -> RunShape {
        RunShape {
            delivery,
            topics: TOPICS
                .into_iter()
                .filter(|&t| t != topic::ODOMETRY.name())
                .map(|t| {
                    let n = 1 + usize::from(t == topic::SCAN.name()) + extra;
                    (t, Readers::stages(n))
                })
                .collect(),
        }
    }

    #[test]
    fn a_run_s_need_is_the_sum_of_its_segments() {
        let lockstep = simulated(Delivery::Lossless, 0);
        let services = pipeline_services(&lockstep);
        assert_eq!(services.len(), 7);
        let scan = &services[0];
        assert_eq!(scan.topic, "lidar/scan");
        assert_eq!(
            scan.bytes,
            8 * (std::mem::size_of::<LaserScan>() as u64 + SAMPLE_OVERHEAD)
        );
        let need = pipeline_bytes(&lockstep);
        assert_eq!(
            need,
            services.iter().map(|s| s.bytes).sum::<u64>() + MANAGEMENT_BYTES
        );
        // Measured: a lockstep office run dies of SIGBUS in a 1 MiB /dev/shm and runs in
        // 3 MiB; the bound is above what it used, and far below the files' 54 MB.
        assert!((3 << 20..16 << 20).contains(&need), "{need}");
        // Real time queues 40 messages per subscriber: several times more, still within a
        // container's default 64 MiB.
        let live = simulated(Delivery::Latest, 0);
        assert!((4 * need..64 << 20).contains(&pipeline_bytes(&live)));
        // A recorder reads every topic: one more subscriber's slots on each.
        let recorded = simulated(Delivery::Lossless, 1);
        assert!(pipeline_bytes(&recorded) > need);
        assert_eq!(pipeline_services(&recorded).len(), services.len());
    }

    #[test]
    fn a_lossy_reader_takes_room_for_its_deeper_queue() {
        let plain = Readers::stages(2);
        let viewed = Readers { lossy: 1, ..plain };
        let scans = |readers| segment_bytes::<LaserScan>(Delivery::Lossless, 0, readers);
        let slot = std::mem::size_of::<LaserScan>() as u64 + SAMPLE_OVERHEAD;
        let queue = lossy_queue::<LaserScan>(Delivery::Lossless, 0);
        assert!(queue > 1, "{queue}");
        assert_eq!(scans(viewed) - scans(plain), (queue as u64 + 2) * slot);
        // About 2 MiB a topic, whatever its message's size.
        assert!((1 << 20..3 << 20).contains(&(queue as u64 * slot)));
    }

    #[test]
    fn every_topic_has_a_size_and_nothing_else_has() {
        for name in TOPICS {
            let size = service_size(name, Delivery::Lossless, Readers::stages(1)).expect("a topic");
            assert_eq!(size.topic, name);
        }
        assert_eq!(
            service_size("lidar/scans", Delivery::Lossless, Readers::stages(1)),
            None
        );
    }

    #[test]
    fn too_little_room_is_refused_with_both_figures_and_the_largest_services() {
        let shape = RunShape {
            delivery: Delivery::Lossless,
            topics: vec![
                (topic::SCAN.name(), Readers::stages(2)),
                (topic::ODOMETRY.name(), Readers::stages(1)),
                (topic::FEATURES.name(), Readers::stages(1)),
                (topic::POSE.name(), Readers::stages(1)),
                (topic::MAP.name(), Readers::stages(1)),
                (topic::PATH.name(), Readers::stages(1)),
            ],
        };
        let need = pipeline_bytes(&shape);
        assert!(check_room(&shape, need).is_ok());
        let error = check_room(&shape, 1 << 20).unwrap_err().to_string();
        assert!(
            error.starts_with(&format!(
                "/dev/shm has 1 MiB free, but the run's shared memory may take {} MiB \
                 ('slam/map' ",
                mib(need)
            )),
            "{error}"
        );
    }

    #[test]
    fn the_free_space_of_a_directory_is_read() {
        assert!(free_bytes(Path::new("/")).is_ok());
        assert!(free_bytes(Path::new("/no/such/dir")).is_err());
    }
}
