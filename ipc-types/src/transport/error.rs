//! What can go wrong, one enum per operation, each keeping iceoryx2's error as its source.
//!
//! The messages name the topic and the step; the iceoryx2 error is the source, not part of
//! the message, so `{:#}` prints it once.

use iceoryx2::port::listener::{ListenerCreateError, ListenerWaitError};
use iceoryx2::port::notifier::NotifierCreateError;
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::port::subscriber::SubscriberCreateError;
use iceoryx2::port::update_connections::ConnectionFailure;
use iceoryx2::port::{LoanError, SendError};
use iceoryx2::service::builder::event::EventOpenOrCreateError;
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::waitset::{WaitSetAttachmentError, WaitSetCreateError, WaitSetRunError};

use crate::capacity::CapacityError;

/// Why a topic could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    #[error("'{0}' is not a valid service name")]
    BadServiceName(String),
    #[error("'{0}' is not a valid port name")]
    BadPortName(String),
    #[error("cannot open '{service}'")]
    Failed {
        service: String,
        source: OpenFailure,
    },
    #[error("stopped by a signal while waiting for service '{0}'")]
    Stopped(String),
}

/// The step of opening a topic that failed, with iceoryx2's error.
#[derive(Debug, thiserror::Error)]
pub enum OpenFailure {
    #[error(
        "cannot open or create the service (all processes of a run must agree on lockstep or \
         real time)"
    )]
    CreateService(#[from] PublishSubscribeOpenOrCreateError),
    #[error("cannot open the service")]
    OpenService(#[from] PublishSubscribeOpenError),
    #[error("cannot open or create its event service")]
    Event(#[from] EventOpenOrCreateError),
    #[error("cannot create a publisher")]
    Publisher(#[from] PublisherCreateError),
    #[error("cannot create a subscriber")]
    Subscriber(#[from] SubscriberCreateError),
    #[error("cannot create a notifier on its event service")]
    Notifier(#[from] NotifierCreateError),
    #[error("cannot create a listener on its event service")]
    Listener(#[from] ListenerCreateError),
    #[error("cannot wait for a publisher")]
    Wait(#[from] ListenerWaitError),
}

/// Makes an iceoryx2 error on `service` an [`OpenError`], for `map_err`.
pub(super) fn open_failed<E: Into<OpenFailure>>(service: &str) -> impl FnOnce(E) -> OpenError {
    let service = service.to_owned();
    move |e| OpenError::Failed {
        service,
        source: e.into(),
    }
}

/// Why a message could not be published.
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    #[error("cannot publish on '{service}'")]
    Failed {
        service: String,
        source: PublishFailure,
    },
    #[error("stopped by a signal while waiting on '{0}'")]
    Stopped(String),
}

/// The step of publishing that failed, with its cause.
#[derive(Debug, thiserror::Error)]
pub enum PublishFailure {
    #[error("cannot loan a sample")]
    Loan(#[from] LoanError),
    #[error("cannot send")]
    Send(#[from] SendError),
    #[error("cannot connect to the subscribers")]
    Connect(#[from] ConnectionFailure),
    #[error("cannot wait for subscribers")]
    Wait(#[from] ListenerWaitError),
    /// The message went out, but without what did not fit in it.
    #[error("the message went out cut short")]
    Truncated(#[from] CapacityError),
}

/// Makes an error on `service` a [`PublishError`], for `map_err`.
pub(super) fn publish_failed<E: Into<PublishFailure>>(
    service: &str,
) -> impl FnOnce(E) -> PublishError {
    let service = service.to_owned();
    move |e| PublishError::Failed {
        service,
        source: e.into(),
    }
}

/// Why a message could not be received.
#[derive(Debug, thiserror::Error)]
#[error("cannot receive on '{service}'")]
pub struct ReceiveError {
    pub(crate) service: String,
    pub(crate) source: iceoryx2::port::ReceiveError,
}

/// Why waiting for messages failed.
#[derive(Debug, thiserror::Error)]
pub enum WaitError {
    #[error("cannot create the process's wait set")]
    Create(#[source] WaitSetCreateError),
    #[error("cannot attach an inlet to the wait set")]
    Attach(#[source] WaitSetAttachmentError),
    #[error("cannot wait for messages")]
    Run(#[source] WaitSetRunError),
}
