//! How the ends of a topic find each other: by the topic's event service, not by polling.
//!
//! Each topic has one event service (`Topic::event_name`). Its publisher notifies it after
//! each send and once when it is created; each subscriber notifies it once when it has
//! subscribed. Every outlet and inlet listens on it, so a stage waiting for its publisher or
//! for its subscribers sleeps until one of them arrives. A wake-up that is about something
//! else (data, another subscriber) only makes the waiter look again, as does a tenth of a
//! second without one: the waiter then looks at the shutdown flag.

use std::io::Write as _;
use std::time::{Duration, Instant};

use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;

use super::error::open_failed;
use super::{MAX_PUBLISHERS, MAX_SUBSCRIBERS, OpenError, OpenFailure};
use crate::message::Message;
use crate::shutdown;
use crate::topic::Topic;

/// The longest a discovery wait sleeps before it looks at the shutdown flag: a signal does
/// not end the listener's wait by itself.
const SHUTDOWN_CHECK: Duration = Duration::from_millis(100);
/// How often a wait without a deadline says on stderr what it waits for.
const LOG_EVERY: Duration = Duration::from_secs(5);

/// Opens (or creates) `topic`'s event service with room for every publisher and subscriber
/// of the topic, each of which listens on it and notifies it.
fn open_event<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<EventFactory<ipc::Service>, OpenError> {
    node.service_builder(&super::service_name(&topic.event_name())?)
        .event()
        .max_listeners(MAX_PUBLISHERS + MAX_SUBSCRIBERS)
        .max_notifiers(MAX_PUBLISHERS + MAX_SUBSCRIBERS)
        .open_or_create()
        .map_err(open_failed(topic.name()))
}

/// A listener on `topic`'s event service. Made before looking for the other end, so that
/// one arriving after the look wakes it.
pub(super) fn listener<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<Listener<ipc::Service>, OpenError> {
    event_port(node, topic, |event| event.listener_builder().create())
}

/// A notifier on `topic`'s event service that has told every end listening there that its
/// maker has arrived. An end that misses it (under load) still finds the newcomer when its
/// wait looks again.
pub(super) fn announce<T: Message>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<Notifier<ipc::Service>, OpenError> {
    let notifier = event_port(node, topic, |event| event.notifier_builder().create())?;
    let _ = notifier.notify();
    Ok(notifier)
}

/// A port that `create` makes on `topic`'s event service.
fn event_port<T: Message, P, E: Into<OpenFailure>>(
    node: &Node<ipc::Service>,
    topic: Topic<T>,
    create: impl FnOnce(&EventFactory<ipc::Service>) -> Result<P, E>,
) -> Result<P, OpenError> {
    create(&open_event(node, topic)?).map_err(open_failed(topic.name()))
}

/// How a discovery wait ended when it did not find what it waited for.
pub(super) enum Unmet {
    /// The timeout passed.
    TimedOut,
    /// SIGINT or SIGTERM arrived.
    Stopped,
    Failed(ListenerWaitError),
}

/// Waits on `listener` until `found()` holds, for at most `timeout` when given. Without a
/// timeout it writes `waiting()` to stderr every few seconds, when given.
pub(super) fn wait_until(
    listener: &Listener<ipc::Service>,
    timeout: Option<Duration>,
    waiting: Option<&dyn Fn() -> String>,
    mut found: impl FnMut() -> bool,
) -> Result<(), Unmet> {
    let start = Instant::now();
    let mut next_log = LOG_EVERY;
    loop {
        // The listener exists before the first look, so an arrival after a look is a
        // notification it still holds: the wait below returns at once.
        if found() {
            return Ok(());
        }
        if shutdown::requested() {
            return Err(Unmet::Stopped);
        }
        let elapsed = start.elapsed();
        let slice = match timeout {
            Some(timeout) if elapsed >= timeout => return Err(Unmet::TimedOut),
            Some(timeout) => (timeout - elapsed).min(SHUTDOWN_CHECK),
            None => {
                if let Some(waiting) = waiting.filter(|_| elapsed >= next_log) {
                    // Not eprintln!: it panics on a closed pipe (a launcher that has gone).
                    let _ = writeln!(std::io::stderr(), "{}", waiting());
                    next_log += LOG_EVERY;
                }
                SHUTDOWN_CHECK
            }
        };
        match listener.timed_wait(|_| {}, slice) {
            // A signal (a stop and continue, too) cut the wait short: look again, and at the
            // shutdown flag.
            Ok(_) | Err(ListenerWaitError::InterruptSignal) => {}
            Err(e) => return Err(Unmet::Failed(e)),
        }
    }
}
