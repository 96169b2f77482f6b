//! The subscribing end of a topic.

use std::cell::RefCell;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use super::discovery::{self, Unmet};
use super::error::open_failed;
use super::{
    Delivery, LOSSY_READER, OpenError, ReceiveError, Wakeable, lossy_queue, service_name,
    subscriber_queue,
};
use crate::message::Message;
use crate::progress::{self, Direction};
use crate::topic::Topic;

/// How long [`Inlet::try_open`] waits for the publisher of a topic that exists without one:
/// its creator makes the publisher right after the service.
const PUBLISHER_WAIT: Duration = Duration::from_secs(2);

/// Who a subscriber is to the topic's publishers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reader {
    /// A stage of the pipeline: on a lossless topic the publisher waits for it.
    Pipeline,
    /// For the eye only: never waited for (see the transport's module).
    Lossy,
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

/// Waits until a publisher has created `topic`, without subscribing to it. Logs every few
/// seconds while it waits; stops on a signal.
pub fn wait_for_topic<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<(), OpenError> {
    let listener = discovery::listener(node, topic)?;
    wait_for_service(node, topic, &listener).map(drop)
}

/// The topic's service if it exists.
fn open_service<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<Option<PubSubFactory<ipc::Service, T, ()>>, OpenError> {
    match node
        .service_builder(&service_name(topic.name())?)
        .publish_subscribe::<T>()
        .open()
    {
        Ok(service) => Ok(Some(service)),
        Err(PublishSubscribeOpenError::DoesNotExist) => Ok(None),
        Err(source) => Err(open_failed(topic.name())(source)),
    }
}

fn has_publisher<T: Message>(service: &PubSubFactory<ipc::Service, T, ()>) -> bool {
    service.dynamic_config().number_of_publishers() > 0
}

/// Opens `topic` once it exists and has a publisher, waiting for both on `listener`. Logs
/// every few seconds while it waits; stops on a signal.
///
/// A subscriber made before the publisher is connected to it only by its next receive, and
/// until then a lossless publisher that finds the one-message queue full drops the message
/// for it instead of waiting (iceoryx2 does not block on a receiver that is not there yet):
/// a stage that subscribes and then waits for its own subscribers before it receives would
/// lose its second message. Made after the publisher, a subscriber is connected at once.
fn wait_for_service<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
    listener: &Listener<ipc::Service>,
) -> Result<PubSubFactory<ipc::Service, T, ()>, OpenError> {
    let name = topic.name();
    let service = RefCell::new(None);
    let waiting = || {
        if service.borrow().is_some() {
            format!("waiting for a publisher on '{name}'")
        } else {
            format!("waiting for a publisher to create '{name}'")
        }
    };
    let mut failure = None;
    let found = discovery::wait_until(listener, None, Some(&waiting), || {
        let mut service = service.borrow_mut();
        if service.is_none() {
            match open_service(node, topic) {
                Ok(opened) => *service = opened,
                Err(e) => {
                    failure = Some(e);
                    return true;
                }
            }
        }
        service.as_ref().is_some_and(has_publisher)
    });
    if let Some(e) = failure {
        return Err(e);
    }
    match (found, service.into_inner()) {
        (Ok(()), Some(service)) => Ok(service),
        (Err(Unmet::Failed(source)), _) => Err(open_failed(name)(source)),
        // Stopped; a wait without a timeout ends otherwise only with the service found.
        _ => Err(OpenError::Stopped(name.to_owned())),
    }
}

impl<T: Message> Inlet<T> {
    /// Subscribes to `topic`, waiting until its publisher has created it (so the publisher
    /// chooses the delivery). Logs every few seconds while it waits; stops on a signal.
    pub fn open(node: &Node<ipc::Service>, topic: Topic<T>) -> Result<Self, OpenError> {
        Self::open_as(node, topic, Reader::Pipeline)
    }

    /// As [`Inlet::open`], for a reader that may lose messages and that no publisher waits
    /// for: on a lossless topic a message that finds its queue full is not delivered to it
    /// (to it alone; the pipeline's readers get every one). Its receipts are not counted
    /// for the launcher. For a live view, never for a stage of the pipeline.
    pub fn open_lossy(node: &Node<ipc::Service>, topic: Topic<T>) -> Result<Self, OpenError> {
        Self::open_as(node, topic, Reader::Lossy)
    }

    fn open_as(
        node: &Node<ipc::Service>,
        topic: Topic<T>,
        reader: Reader,
    ) -> Result<Self, OpenError> {
        let listener = discovery::listener(node, topic)?;
        let service = wait_for_service(node, topic, &listener)?;
        Self::subscribe(node, topic, &service, listener, reader)
    }

    /// Subscribes to `topic` if a publisher has created it; `None` when nobody publishes it.
    /// A topic that exists without a publisher gets a moment for it to appear.
    pub fn try_open(node: &Node<ipc::Service>, topic: Topic<T>) -> Result<Option<Self>, OpenError> {
        Self::try_open_as(node, topic, Reader::Pipeline)
    }

    /// As [`Inlet::try_open`], lossy (see [`Inlet::open_lossy`]).
    pub fn try_open_lossy(
        node: &Node<ipc::Service>,
        topic: Topic<T>,
    ) -> Result<Option<Self>, OpenError> {
        Self::try_open_as(node, topic, Reader::Lossy)
    }

    fn try_open_as(
        node: &Node<ipc::Service>,
        topic: Topic<T>,
        reader: Reader,
    ) -> Result<Option<Self>, OpenError> {
        let Some(service) = open_service(node, topic)? else {
            return Ok(None);
        };
        let listener = discovery::listener(node, topic)?;
        match discovery::wait_until(&listener, Some(PUBLISHER_WAIT), None, || {
            has_publisher(&service)
        }) {
            // Without a publisher after the wait, the subscriber waits for one as before.
            Ok(()) | Err(Unmet::TimedOut) => {}
            Err(Unmet::Stopped) => return Err(OpenError::Stopped(topic.name().to_owned())),
            Err(Unmet::Failed(source)) => return Err(open_failed(topic.name())(source)),
        }
        Self::subscribe(node, topic, &service, listener, reader).map(Some)
    }

    /// Subscribes and tells the topic's outlets, which may be waiting for their subscribers.
    fn subscribe(
        node: &Node<ipc::Service>,
        topic: Topic<T>,
        service: &PubSubFactory<ipc::Service, T, ()>,
        listener: Listener<ipc::Service>,
        reader: Reader,
    ) -> Result<Self, OpenError> {
        let name = topic.name();
        let delivery = if service.static_config().has_safe_overflow() {
            Delivery::Latest
        } else {
            Delivery::Lossless
        };
        let history = service.static_config().history_size();
        let mut builder = service.subscriber_builder();
        if reader == Reader::Lossy {
            let port = PortName::new(LOSSY_READER)
                .map_err(|_| OpenError::BadPortName(LOSSY_READER.to_owned()))?;
            builder = builder
                .name(&port)
                .buffer_size(lossy_queue::<T>(delivery, history));
        } else {
            builder = builder.buffer_size(subscriber_queue(delivery, history));
        }
        let subscriber = builder.create().map_err(open_failed(name))?;
        // Wakes the outlets waiting for their subscribers; the notifier has done its job.
        drop(discovery::announce(node, topic)?);
        Ok(Self {
            name,
            delivery,
            subscriber,
            listener,
            received: match reader {
                Reader::Pipeline => progress::counter(Direction::In, name),
                // Counted for no one: the launcher would take what it loses for a stall.
                Reader::Lossy => Arc::default(),
            },
        })
    }

    /// The topic's delivery mode, as its creator chose it.
    pub fn delivery(&self) -> Delivery {
        self.delivery
    }

    /// The next queued message, if any.
    pub fn receive(&self) -> Result<Option<Sample<ipc::Service, T, ()>>, ReceiveError> {
        let sample = self.subscriber.receive().map_err(|source| ReceiveError {
            service: self.name.to_owned(),
            source,
        })?;
        if sample.is_some() {
            self.received.fetch_add(1, Ordering::Relaxed);
        }
        Ok(sample)
    }
}

impl<T: Message> Wakeable for Inlet<T> {
    fn wake_listener(&self) -> &Listener<ipc::Service> {
        &self.listener
    }
}
