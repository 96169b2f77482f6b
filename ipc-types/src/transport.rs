//! Typed publishers and subscribers over a run's [`Domain`], with a wake-up event per topic.
//!
//! An [`Outlet`] publishes a [`Message`] on its [`Topic`] and notifies the topic's event
//! service; an [`Inlet`] subscribes and sleeps on that event through [`wait_any`]. The
//! [`Delivery`] mode belongs to the service, chosen by whoever creates it (the source of the
//! data), and travels downstream: a stage reads its input's mode and creates its output with
//! the same one.

use std::io::Write as _;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use crate::domain::Domain;
use crate::header::{FLAG_END_OF_STREAM, now_ns};
use crate::message::Message;
use crate::progress::{self, Direction};
use crate::shutdown;
use crate::topic::Topic;

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

/// Queue depth of a subscriber in [`Delivery::Lossless`] mode: one message in flight per
/// stage, so the publisher sends the next only when the previous has been taken.
pub const LOSSLESS_QUEUE: usize = 1;
/// Queue depth of a subscriber in [`Delivery::Latest`] mode: a second of scans at 40 Hz.
pub const LATEST_QUEUE: usize = 40;
/// Subscribers a topic may have at once. iceoryx2 preallocates queue slots for each in the
/// publisher's shared memory (see [`crate::shm`]), so this is not free: the pipeline needs
/// two on the scans and one elsewhere, and the rest is room for tools and tests.
pub(crate) const MAX_SUBSCRIBERS: usize = 16;

/// The queue depth of each subscriber of a topic with this delivery and history.
pub(crate) fn subscriber_queue(delivery: Delivery, history: usize) -> usize {
    match delivery {
        Delivery::Lossless => LOSSLESS_QUEUE.max(history),
        Delivery::Latest => LATEST_QUEUE.max(history),
    }
}

/// How long an outlet blocked on a full subscriber waits between sweeps for dead nodes.
const DEAD_NODE_SWEEP: Duration = Duration::from_millis(500);

/// Why a topic could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    #[error("'{0}' is not a valid service name")]
    BadServiceName(String),
    #[error("cannot open or create service '{service}': {cause}")]
    Service { service: String, cause: String },
    #[error("cannot create a port on '{service}': {cause}")]
    Port { service: String, cause: String },
    #[error("stopped by a signal while waiting for service '{0}'")]
    Stopped(String),
}

/// Why a message could not be published.
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    #[error("cannot loan a sample on '{service}': {cause}")]
    Loan { service: String, cause: String },
    #[error("cannot send on '{service}': {cause}")]
    Send { service: String, cause: String },
    #[error("stopped by a signal while waiting on '{0}'")]
    Stopped(String),
}

/// Why a message could not be received.
#[derive(Debug, thiserror::Error)]
#[error("cannot receive on '{service}': {cause}")]
pub struct ReceiveError {
    service: String,
    cause: String,
}

/// Why waiting failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot wait for messages: {0}")]
pub struct WaitError(String);

fn service_name(name: &str) -> Result<ServiceName, OpenError> {
    ServiceName::new(name).map_err(|_| OpenError::BadServiceName(name.to_owned()))
}

fn open_event(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, OpenError> {
    node.service_builder(&service_name(name)?)
        .event()
        .open_or_create()
        .map_err(|e| OpenError::Service {
            service: name.to_owned(),
            cause: format!("{e:?}"),
        })
}

/// Publishes one message type on one topic.
pub struct Outlet<T: Message> {
    name: &'static str,
    service: PubSubFactory<ipc::Service, T, ()>,
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
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
        let queue = subscriber_queue(delivery, history);
        let service = node
            .service_builder(&service_name(name)?)
            .publish_subscribe::<T>()
            .enable_safe_overflow(delivery == Delivery::Latest)
            .subscriber_max_buffer_size(queue)
            .history_size(history)
            .max_subscribers(MAX_SUBSCRIBERS)
            .max_publishers(4)
            .open_or_create()
            .map_err(|e| OpenError::Service {
                service: name.to_owned(),
                cause: format!(
                    "{e:?} (all processes of a run must agree on lockstep or real time)"
                ),
            })?;
        let sweep_domain = domain.clone();
        let publisher = service
            .publisher_builder()
            .backpressure_strategy(match delivery {
                Delivery::Lossless => BackpressureStrategy::RetryUntilDelivered,
                Delivery::Latest => BackpressureStrategy::DiscardData,
            })
            .set_backpressure_handler(move |info: &BackpressureInfo| {
                on_backpressure(&sweep_domain, info)
            })
            .create()
            .map_err(|e| OpenError::Port {
                service: name.to_owned(),
                cause: format!("{e:?}"),
            })?;
        let notifier = open_event(node, &topic.event_name())?
            .notifier_builder()
            .create()
            .map_err(|e| OpenError::Port {
                service: topic.event_name(),
                cause: format!("{e:?}"),
            })?;
        Ok(Self {
            name,
            service,
            publisher,
            notifier,
            sent: progress::counter(Direction::Out, name),
        })
    }

    /// Subscribers connected to the topic now.
    pub fn subscriber_count(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }

    /// Waits until at least `count` subscribers are connected, so a lossless stream loses
    /// nothing to late starters. Returns `false` if `timeout` passed first.
    pub fn wait_for_subscribers(
        &self,
        count: usize,
        timeout: Option<Duration>,
    ) -> Result<bool, PublishError> {
        let start = Instant::now();
        while self.subscriber_count() < count {
            if shutdown::requested() {
                return Err(PublishError::Stopped(self.name.to_owned()));
            }
            if timeout.is_some_and(|t| start.elapsed() >= t) {
                return Ok(false);
            }
            std::thread::sleep(Duration::from_millis(5));
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
            .map_err(|e| PublishError::Send {
                service: self.name.to_owned(),
                cause: format!("{e:?}"),
            })
    }

    /// Loans shared memory, zeroes it, lets `fill` write the message in place, stamps
    /// `sent_ns` and sends it. Returns the number of subscribers it reached.
    pub fn publish(&self, fill: impl FnOnce(&mut T)) -> Result<usize, PublishError> {
        let mut sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| PublishError::Loan {
                service: self.name.to_owned(),
                cause: format!("{e:?}"),
            })?;
        let message = T::zero_in_place(sample.payload_mut());
        fill(message);
        message.header_mut().sent_ns = now_ns();
        // SAFETY: `zero_in_place` initialised the whole payload.
        let sample = unsafe { sample.assume_init() };
        let reached = sample.send().map_err(|e| {
            if shutdown::requested() {
                PublishError::Stopped(self.name.to_owned())
            } else {
                PublishError::Send {
                    service: self.name.to_owned(),
                    cause: format!("{e:?}"),
                }
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

/// A lossless publisher blocked on a full subscriber: give up on Ctrl-C, and every so often
/// remove dead nodes, since a killed subscriber would otherwise block us for ever.
fn on_backpressure(domain: &Domain, info: &BackpressureInfo) -> BackpressureAction {
    if shutdown::requested() {
        return BackpressureAction::DiscardDataAndFail;
    }
    let sweeps_due = info.elapsed_time.as_millis() / DEAD_NODE_SWEEP.as_millis();
    if sweeps_due > 0 && info.retries.is_multiple_of(64) {
        domain.cleanup_dead_nodes();
    }
    BackpressureAction::Retry
}

/// Waits until a publisher has created `topic`, without subscribing to it. Logs every few
/// seconds while it waits; stops on a signal.
pub fn wait_for_topic<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<(), OpenError> {
    wait_for_service(node, topic).map(drop)
}

/// How long [`Inlet::try_open`] waits for the publisher of a topic that exists without one:
/// its creator makes the publisher right after the service.
const PUBLISHER_WAIT: Duration = Duration::from_secs(2);

/// Opens `topic` once it exists and has a publisher, waiting for both. Logs every few
/// seconds while it waits; stops on a signal.
fn wait_for_service<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<PubSubFactory<ipc::Service, T, ()>, OpenError> {
    let name = topic.name();
    let service_name = service_name(name)?;
    let start = Instant::now();
    let mut next_log = Duration::from_secs(5);
    loop {
        match node
            .service_builder(&service_name)
            .publish_subscribe::<T>()
            .open()
        {
            Ok(service) => {
                wait_for_publisher(&service, name, None)?;
                return Ok(service);
            }
            Err(PublishSubscribeOpenError::DoesNotExist) => {}
            Err(e) => {
                return Err(OpenError::Service {
                    service: name.to_owned(),
                    cause: format!("{e:?}"),
                });
            }
        }
        if shutdown::requested() {
            return Err(OpenError::Stopped(name.to_owned()));
        }
        if start.elapsed() >= next_log {
            // Not eprintln!: it panics on a closed pipe (a launcher that has gone).
            let _ = writeln!(
                std::io::stderr(),
                "waiting for a publisher to create '{name}'"
            );
            next_log += Duration::from_secs(5);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Waits until `service` has a publisher (at most `timeout`, when given). A subscriber
/// made before the publisher is connected to it only by its next receive, and until then
/// a lossless publisher that finds the one-message queue full drops the message for it
/// instead of waiting (iceoryx2 does not block on a receiver that is not there yet): a
/// stage that subscribes and then waits for its own subscribers before it receives would
/// lose its second message. Made after the publisher, a subscriber is connected at once.
fn wait_for_publisher<T: Message>(
    service: &PubSubFactory<ipc::Service, T, ()>,
    name: &str,
    timeout: Option<Duration>,
) -> Result<(), OpenError> {
    let start = Instant::now();
    let mut next_log = Duration::from_secs(5);
    while service.dynamic_config().number_of_publishers() == 0 {
        if shutdown::requested() {
            return Err(OpenError::Stopped(name.to_owned()));
        }
        if timeout.is_some_and(|t| start.elapsed() >= t) {
            return Ok(());
        }
        if start.elapsed() >= next_log {
            let _ = writeln!(std::io::stderr(), "waiting for a publisher on '{name}'");
            next_log += Duration::from_secs(5);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    Ok(())
}

/// Subscribes to one message type on one topic.
pub struct Inlet<T: Message> {
    name: &'static str,
    delivery: Delivery,
    subscriber: Subscriber<ipc::Service, T, ()>,
    listener: Listener<ipc::Service>,
    /// Messages received, for the launcher (see [`crate::progress`]).
    received: Arc<AtomicU64>,
}

impl<T: Message> std::fmt::Debug for Inlet<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Inlet")
            .field("topic", &self.name)
            .field("delivery", &self.delivery)
            .finish()
    }
}

impl<T: Message> Inlet<T> {
    /// Subscribes to `topic`, waiting until its publisher has created it (so the publisher
    /// chooses the delivery). Logs every few seconds while it waits; stops on a signal.
    pub fn open(node: &Node<ipc::Service>, topic: Topic<T>) -> Result<Self, OpenError> {
        let service = wait_for_service(node, topic)?;
        Self::from_service(node, topic, &service)
    }

    /// Subscribes to `topic` if a publisher has created it; `None` when nobody publishes it.
    /// A topic that exists without a publisher gets a moment for it to appear.
    pub fn try_open(node: &Node<ipc::Service>, topic: Topic<T>) -> Result<Option<Self>, OpenError> {
        match node
            .service_builder(&service_name(topic.name())?)
            .publish_subscribe::<T>()
            .open()
        {
            Ok(service) => {
                wait_for_publisher(&service, topic.name(), Some(PUBLISHER_WAIT))?;
                Self::from_service(node, topic, &service).map(Some)
            }
            Err(PublishSubscribeOpenError::DoesNotExist) => Ok(None),
            Err(e) => Err(OpenError::Service {
                service: topic.name().to_owned(),
                cause: format!("{e:?}"),
            }),
        }
    }

    fn from_service(
        node: &Node<ipc::Service>,
        topic: Topic<T>,
        service: &PubSubFactory<ipc::Service, T, ()>,
    ) -> Result<Self, OpenError> {
        let name = topic.name();
        let delivery = if service.static_config().has_safe_overflow() {
            Delivery::Latest
        } else {
            Delivery::Lossless
        };
        let subscriber = service
            .subscriber_builder()
            .create()
            .map_err(|e| OpenError::Port {
                service: name.to_owned(),
                cause: format!("{e:?}"),
            })?;
        let listener = open_event(node, &topic.event_name())?
            .listener_builder()
            .create()
            .map_err(|e| OpenError::Port {
                service: topic.event_name(),
                cause: format!("{e:?}"),
            })?;
        Ok(Self {
            name,
            delivery,
            subscriber,
            listener,
            received: progress::counter(Direction::In, name),
        })
    }

    /// The topic's delivery mode, as its creator chose it.
    pub fn delivery(&self) -> Delivery {
        self.delivery
    }

    /// The next queued message, if any.
    pub fn receive(&self) -> Result<Option<Sample<ipc::Service, T, ()>>, ReceiveError> {
        let sample = self.subscriber.receive().map_err(|e| ReceiveError {
            service: self.name.to_owned(),
            cause: format!("{e:?}"),
        })?;
        if sample.is_some() {
            self.received.fetch_add(1, Ordering::Relaxed);
        }
        Ok(sample)
    }

    fn listener(&self) -> &Listener<ipc::Service> {
        &self.listener
    }
}

/// Something [`wait_any`] can sleep on.
pub trait Wakeable {
    #[doc(hidden)]
    fn wake_listener(&self) -> &Listener<ipc::Service>;
}

impl<T: Message> Wakeable for Inlet<T> {
    fn wake_listener(&self) -> &Listener<ipc::Service> {
        self.listener()
    }
}

/// What ended a wait.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// A publisher notified (there may be data) or the timeout passed: drain the inlets.
    Poll,
    /// SIGINT or SIGTERM arrived.
    Shutdown,
}

/// Sleeps until one of `inlets` is notified or `timeout` passes. Always drain every inlet
/// after it returns [`Wake::Poll`], timeout included: a wake-up can be missed under load.
pub fn wait_any(inlets: &[&dyn Wakeable], timeout: Duration) -> Result<Wake, WaitError> {
    if shutdown::requested() {
        return Ok(Wake::Shutdown);
    }
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| WaitError(format!("{e:?}")))?;
    let mut guards = Vec::with_capacity(inlets.len());
    for inlet in inlets {
        guards.push(
            waitset
                .attach_notification(inlet.wake_listener())
                .map_err(|e| WaitError(format!("{e:?}")))?,
        );
    }
    // A signal interrupting the wait surfaces as an error or an early return; the flag below
    // tells them apart.
    let result =
        waitset.wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, timeout);
    drop(guards);
    for inlet in inlets {
        // Consume the notifications so the next wait sleeps again.
        let _ = inlet.wake_listener().try_wait(|_| {});
    }
    if shutdown::requested() {
        return Ok(Wake::Shutdown);
    }
    result.map_err(|e| WaitError(format!("{e:?}")))?;
    Ok(Wake::Poll)
}
