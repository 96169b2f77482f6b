//! Sleeping on several inlets at once, on one WaitSet kept for the process's life.

use std::cell::RefCell;
use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;

use super::WaitError;
use crate::shutdown;

/// Something [`wait_any`] can sleep on.
pub trait Wakeable {
    #[doc(hidden)]
    fn wake_listener(&self) -> &Listener<ipc::Service>;
}

/// What ended a wait.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// A publisher notified (there may be data) or the timeout passed: drain the inlets.
    Poll,
    /// SIGINT or SIGTERM arrived.
    Shutdown,
}

thread_local! {
    /// The WaitSet of the thread that waits (a stage's loop), made at its first wait. A
    /// WaitSet is not `Send`, and the inlets are attached for one wait at a time: an
    /// attachment borrows its inlet's listener, so it cannot outlive the call.
    static WAITSET: RefCell<Option<WaitSet<ipc::Service>>> = const { RefCell::new(None) };
}

/// Sleeps until one of `inlets` is notified or `timeout` passes. Always drain every inlet
/// after it returns [`Wake::Poll`], timeout included: a wake-up can be missed under load.
pub fn wait_any(inlets: &[&dyn Wakeable], timeout: Duration) -> Result<Wake, WaitError> {
    if shutdown::requested() {
        return Ok(Wake::Shutdown);
    }
    let result = WAITSET.with(|cell| -> Result<_, WaitError> {
        let mut cell = cell.borrow_mut();
        let waitset = match cell.take() {
            Some(waitset) => cell.insert(waitset),
            None => cell.insert(
                WaitSetBuilder::new()
                    .signal_handling_mode(SignalHandlingMode::Disabled)
                    .create::<ipc::Service>()
                    .map_err(WaitError::Create)?,
            ),
        };
        let guards = inlets
            .iter()
            .map(|inlet| waitset.attach_notification(inlet.wake_listener()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(WaitError::Attach)?;
        // A signal interrupting the wait surfaces as an error or an early return; the flag
        // below tells them apart.
        let result =
            waitset.wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, timeout);
        drop(guards);
        Ok(result)
    })?;
    for inlet in inlets {
        // Consume the notifications so the next wait sleeps again.
        let _ = inlet.wake_listener().try_wait(|_| {});
    }
    if shutdown::requested() {
        return Ok(Wake::Shutdown);
    }
    result.map_err(WaitError::Run)?;
    Ok(Wake::Poll)
}

/// Runs `poll` after every wake-up of `inlets` (a notification, or `timeout` passing) until
/// it returns `false` or SIGINT or SIGTERM arrives. One wait set serves the whole loop, the
/// inlets attached once: a reader woken for every message of many topics (the recorder, the
/// live view) would spend more system time making and dropping attachments, as
/// [`wait_any`] does at each wait, than on the messages.
pub fn wait_loop<E: From<WaitError>>(
    inlets: &[&dyn Wakeable],
    timeout: Duration,
    mut poll: impl FnMut() -> Result<bool, E>,
) -> Result<(), E> {
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(WaitError::Create)?;
    let guards = inlets
        .iter()
        .map(|inlet| waitset.attach_notification(inlet.wake_listener()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(WaitError::Attach)?;
    while !shutdown::requested() {
        let woken = waitset.wait_and_process_once_with_timeout(
            |id| {
                // Consume the notifications of the inlets that woke us, so the next wait
                // sleeps again; `poll` drains whoever notified.
                for (guard, inlet) in guards.iter().zip(inlets) {
                    if id.has_event_from(guard) {
                        let _ = inlet.wake_listener().try_wait(|_| {});
                    }
                }
                CallbackProgression::Continue
            },
            timeout,
        );
        if shutdown::requested() {
            break;
        }
        // A signal interrupting the wait surfaces as an error; the flag above tells.
        woken.map_err(WaitError::Run)?;
        if !poll()? {
            break;
        }
    }
    Ok(())
}
