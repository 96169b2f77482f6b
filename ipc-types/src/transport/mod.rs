//! Typed publishers and subscribers over a run's [`Domain`], with a wake-up event per topic.
//!
//! An [`Outlet`] publishes a [`Message`] on its [`Topic`] and notifies the topic's event
//! service; an [`Inlet`] subscribes and sleeps on that event through [`wait_any`]. The
//! [`Delivery`] mode belongs to the service, chosen by whoever creates it (the source of the
//! data), and travels downstream: a stage reads its input's mode and creates its output with
//! the same one. The same event tells each end when the other arrives (see `discovery`).

mod discovery;
mod error;
mod inlet;
mod outlet;
mod wait;

use iceoryx2::prelude::*;

pub use error::{OpenError, OpenFailure, PublishError, PublishFailure, ReceiveError, WaitError};
pub use inlet::{Inlet, wait_for_topic};
pub use outlet::Outlet;
pub use wait::{Wake, Wakeable, wait_any, wait_loop};

/// How a topic treats a subscriber whose queue is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// The publisher waits until every subscriber has room: nothing is lost and a run is
    /// deterministic (lockstep).
    Lossless,
    /// The oldest queued message is dropped: a slow subscriber never blocks the sensor
    /// (real time).
    Latest,
}

/// The port name of a lossy subscriber (see the module).
pub const LOSSY_READER: &str = "lossy-reader";

/// Queue depth of a subscriber in [`Delivery::Lossless`] mode: one message in flight per
/// stage, so the publisher sends the next only when the previous has been taken.
pub const LOSSLESS_QUEUE: usize = 1;
/// Queue depth of a subscriber in [`Delivery::Latest`] mode: a second of scans at 40 Hz.
pub const LATEST_QUEUE: usize = 40;
/// Subscribers a topic may have at once. iceoryx2 preallocates queue slots for each in the
/// publisher's shared memory (see [`crate::shm`]), so this is not free: the pipeline needs
/// two on the scans and one elsewhere, and the rest is room for tools and tests.
pub(crate) const MAX_SUBSCRIBERS: usize = 16;
/// Publishers a topic may have at once: one in the pipeline, the rest for tools and tests.
pub(crate) const MAX_PUBLISHERS: usize = 4;

/// Bytes a lossy reader's queue may hold on one topic. A grid, a path or a particle cloud
/// comes in pieces, and a piece lost loses the whole: this much lets the live view take the
/// pieces that come while it encodes something else.
const LOSSY_QUEUE_BYTES: usize = 2 << 20;
/// The deepest queue of a lossy reader, for small messages: a few seconds of poses.
const MAX_LOSSY_QUEUE: usize = 64;

/// The queue depth of each pipeline subscriber of a topic with this delivery and history.
pub(crate) fn subscriber_queue(delivery: Delivery, history: usize) -> usize {
    match delivery {
        Delivery::Lossless => LOSSLESS_QUEUE.max(history),
        Delivery::Latest => LATEST_QUEUE.max(history),
    }
}

/// The queue depth of a lossy subscriber ([`Inlet::open_lossy`]) of a topic of `T`: what
/// fits in [`LOSSY_QUEUE_BYTES`], at most [`MAX_LOSSY_QUEUE`], no less than a pipeline
/// subscriber's. It is the service's largest queue: every topic's service allows it.
pub(crate) fn lossy_queue<T>(delivery: Delivery, history: usize) -> usize {
    (LOSSY_QUEUE_BYTES / std::mem::size_of::<T>().max(1))
        .clamp(1, MAX_LOSSY_QUEUE)
        .max(subscriber_queue(delivery, history))
}

/// Whether a subscriber of the service is lossy (see the module), from its details.
fn is_lossy(
    details: &iceoryx2::service::dynamic_config::publish_subscribe::SubscriberDetails,
) -> bool {
    details.subscriber_name.as_str() == LOSSY_READER
}

fn service_name(name: &str) -> Result<ServiceName, OpenError> {
    ServiceName::new(name).map_err(|_| OpenError::BadServiceName(name.to_owned()))
}
