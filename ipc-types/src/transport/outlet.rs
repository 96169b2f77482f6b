//! The publishing end of a topic.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use super::discovery::{self, Unmet};
use super::error::{open_failed, publish_failed};
use super::{
    Delivery, MAX_PUBLISHERS, MAX_SUBSCRIBERS, OpenError, PublishError, is_lossy, lossy_queue,
    service_name,
};
use crate::domain::Domain;
use crate::header::{FLAG_END_OF_STREAM, now_ns};
use crate::message::Message;
use crate::progress::{self, Direction};
use crate::shutdown;
use crate::topic::Topic;

/// How long an outlet blocked on a full subscriber waits between sweeps for dead nodes.
const DEAD_NODE_SWEEP: Duration = Duration::from_millis(500);

/// Publishes one message type on one topic.
pub struct Outlet<T: Message> {
    name: &'static str,
    /// Shared with the backpressure handler, which looks up who a full queue belongs to.
    service: Arc<PubSubFactory<ipc::Service, T, ()>>,
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    /// Woken when a subscriber arrives (see [`Outlet::wait_for_subscribers`]).
    arrivals: Listener<ipc::Service>,
    /// Messages sent, for the launcher (see [`crate::progress`]).
    sent: Arc<AtomicU64>,
}

impl<T: Message> std::fmt::Debug for Outlet<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Outlet").field("topic", &self.name).finish()
    }
}

impl<T: Message> Outlet<T> {
    /// Creates (or opens) `topic` with the given delivery. `history` messages are kept for
    /// subscribers that connect late (e.g. 1 for data published once).
    pub fn create(
        domain: &Domain,
        node: &Node<ipc::Service>,
        topic: Topic<T>,
        delivery: Delivery,
        history: usize,
    ) -> Result<Self, OpenError> {
        let name = topic.name();
        // Pipeline subscribers ask for their queue; a lossy one may take a deeper one.
        let queue = lossy_queue::<T>(delivery, history);
        let service = node
            .service_builder(&service_name(name)?)
            .publish_subscribe::<T>()
            .enable_safe_overflow(delivery == Delivery::Latest)
            .subscriber_max_buffer_size(queue)
            .history_size(history)
            .max_subscribers(MAX_SUBSCRIBERS)
            .max_publishers(MAX_PUBLISHERS)
            .open_or_create()
            .map_err(open_failed(name))?;
        let service = Arc::new(service);
        let readers = Arc::clone(&service);
        let sweep_domain = domain.clone();
        let publisher = service
            .publisher_builder()
            .backpressure_strategy(match delivery {
                Delivery::Lossless => BackpressureStrategy::RetryUntilDelivered,
                Delivery::Latest => BackpressureStrategy::DiscardData,
            })
            .set_backpressure_handler(move |info: &BackpressureInfo| {
                if is_lossy_receiver(&readers, info.receiver_port_id) {
                    // A reader for the eye: it gets what fits, and nobody waits for it.
                    return BackpressureAction::DiscardData;
                }
                on_backpressure(&sweep_domain, info)
            })
            .create()
            .map_err(open_failed(name))?;
        let arrivals = discovery::listener(node, topic)?;
        // Wakes the subscribers waiting for this publisher.
        let notifier = discovery::announce(node, topic)?;
        Ok(Self {
            name,
            service,
            publisher,
            notifier,
            arrivals,
            sent: progress::counter(Direction::Out, name),
        })
    }

    /// Subscribers connected to the topic now, not counting lossy ones
    /// ([`crate::Inlet::open_lossy`]): the pipeline's readers.
    pub fn subscriber_count(&self) -> usize {
        let mut count = 0;
        self.service.dynamic_config().list_subscribers(|details| {
            count += usize::from(!is_lossy(details));
            CallbackProgression::Continue
        });
        count
    }

    /// Waits until at least `count` subscribers are connected, so a lossless stream loses
    /// nothing to late starters. Returns `false` if `timeout` passed first.
    pub fn wait_for_subscribers(
        &self,
        count: usize,
        timeout: Option<Duration>,
    ) -> Result<bool, PublishError> {
        match discovery::wait_until(&self.arrivals, timeout, None, || {
            self.subscriber_count() >= count
        }) {
            Ok(()) => {}
            Err(Unmet::TimedOut) => return Ok(false),
            Err(Unmet::Stopped) => return Err(PublishError::Stopped(self.name.to_owned())),
            Err(Unmet::Failed(source)) => return Err(publish_failed(self.name)(source)),
        }
        // Connect to them now rather than on the first send.
        self.update_connections()?;
        Ok(true)
    }

    /// Connects subscribers that arrived since the last send and hands them the history.
    /// A publisher that sends once and then idles (e.g. the world corners) calls this in its
    /// loop, since iceoryx2 delivers history only when the publisher updates connections.
    pub fn update_connections(&self) -> Result<(), PublishError> {
        self.publisher
            .update_connections()
            .map_err(publish_failed(self.name))
    }

    /// Loans shared memory, zeroes it, lets `fill` write the message in place, stamps
    /// `sent_ns` and sends it. Returns the number of subscribers it reached.
    pub fn publish(&self, fill: impl FnOnce(&mut T)) -> Result<usize, PublishError> {
        let mut sample = self
            .publisher
            .loan_uninit()
            .map_err(publish_failed(self.name))?;
        let message = T::zero_in_place(sample.payload_mut());
        fill(message);
        message.header_mut().sent_ns = now_ns();
        // SAFETY: `zero_in_place` initialised the whole payload. iceoryx2 offers no safe way
        // to mark a loaned sample initialised other than moving a whole value in, which
        // would build the message on the stack first.
        let sample = unsafe { sample.assume_init() };
        let reached = sample.send().map_err(|source| {
            if shutdown::requested() {
                PublishError::Stopped(self.name.to_owned())
            } else {
                publish_failed(self.name)(source)
            }
        })?;
        self.sent.fetch_add(1, Ordering::Relaxed);
        // A subscriber that misses a wake-up still drains its queue on its wait timeout.
        let _ = self.notifier.notify();
        Ok(reached)
    }

    /// Publishes the end-of-stream marker: no data, `seq` = the number of messages sent.
    pub fn publish_end_of_stream(&self, seq: u64, stamp_ns: u64) -> Result<usize, PublishError> {
        self.publish(|message| {
            let header = message.header_mut();
            header.seq = seq;
            header.stamp_ns = stamp_ns;
            header.flags |= FLAG_END_OF_STREAM;
        })
    }
}

/// How long a lossless send blocked on a full subscriber still waits once a stop was asked
/// for. A stage's last messages go out as it stops (slam-proc's final path, several chunks
/// of it on a long run), and their reader (map-sink) still drains its queue for a moment
/// after the stop; a reader that does not costs this once, then the send fails.
const STOP_PATIENCE: Duration = Duration::from_secs(1);

/// Retries of a blocked send before it sleeps between them, and how long.
const SPIN_RETRIES: u64 = 64;
const BACKOFF: Duration = Duration::from_micros(100);

/// Whether the subscriber with port id `receiver` is lossy (see the transport's module).
/// Looked up only when its queue is full, so a send that finds room costs nothing more.
fn is_lossy_receiver<T: Message>(
    service: &PubSubFactory<ipc::Service, T, ()>,
    receiver: u128,
) -> bool {
    let mut lossy = false;
    service.dynamic_config().list_subscribers(|details| {
        if details.subscriber_id.value() == receiver {
            lossy = is_lossy(details);
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    });
    lossy
}

/// A lossless publisher blocked on a full subscriber: give up once stopped (after
/// [`STOP_PATIENCE`]), and every so often remove dead nodes, since a killed subscriber would
/// otherwise block us for ever.
fn on_backpressure(domain: &Domain, info: &BackpressureInfo) -> BackpressureAction {
    if shutdown::requested() && info.elapsed_time >= STOP_PATIENCE {
        return BackpressureAction::DiscardDataAndFail;
    }
    // A reader a scan behind frees a slot within microseconds; one that is busy for longer
    // should not have the waiting publisher spin on a core it needs.
    if info.retries >= SPIN_RETRIES {
        std::thread::sleep(BACKOFF);
    }
    let sweeps_due = info.elapsed_time.as_millis() / DEAD_NODE_SWEEP.as_millis();
    if sweeps_due > 0 && info.retries.is_multiple_of(64) {
        domain.cleanup_dead_nodes();
    }
    BackpressureAction::Retry
}
