//! What can go wrong on the transport: joining a run, opening its services and ports,
//! sending and receiving. Each iceoryx2 failure keeps its typed cause, so that a caller
//! matches on the variant (e.g. [`Error::publisher_taken`]), not on the text.

use std::time::Duration;

use iceoryx2::node::NodeCreationFailure;
use iceoryx2::port::listener::{ListenerCreateError, ListenerWaitError};
use iceoryx2::port::notifier::{NotifierCreateError, NotifierNotifyError};
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::port::subscriber::SubscriberCreateError;
use iceoryx2::port::{LoanError, ReceiveError, SendError};
use iceoryx2::prelude::SemanticStringError;
use iceoryx2::service::builder::event::EventOpenOrCreateError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenOrCreateError;
use iceoryx2::service::service_name::ServiceNameError;

/// An error of the transport.
///
/// The variants that open a service or a port name the service and carry iceoryx2's
/// error in their message; the message is the whole story (no separate `source`).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A run id with characters other than letters, digits, '-' and '_'.
    #[error("run id {0:?}: use letters, digits, '-' and '_' only")]
    RunId(String),
    /// The run id `driver`, which names the driver services.
    #[error("run id \"driver\" is reserved for driver services (rig/driver/...)")]
    ReservedRunId,
    /// A node name iceoryx2 does not accept.
    #[error(transparent)]
    NodeName(#[from] SemanticStringError),
    /// A service name iceoryx2 does not accept.
    #[error(transparent)]
    ServiceName(#[from] ServiceNameError),
    /// The process's iceoryx2 node could not be created.
    #[error(transparent)]
    Node(#[from] NodeCreationFailure),
    /// A publish-subscribe service could not be opened or created: `needs` says what this
    /// process asked for, `found` what the service is.
    #[error("service {service}: {error:?}: this process needs {needs}; {found}")]
    Service {
        /// The service's name.
        service: String,
        /// iceoryx2's reason.
        error: PublishSubscribeOpenOrCreateError,
        /// The payload and settings this process asked for.
        needs: String,
        /// What the service found under that name is ([`crate::describe_service`]).
        found: String,
    },
    /// An event service could not be opened or created.
    #[error("event service {service}: {error:?}")]
    Event {
        /// The service's name.
        service: String,
        /// iceoryx2's reason.
        error: EventOpenOrCreateError,
    },
    /// A publisher could not be created ([`Error::publisher_taken`]: the service's
    /// publishers are all taken).
    #[error("publisher on {service}: {error:?} (is another process publishing there already?)")]
    Publisher {
        /// The service's name.
        service: String,
        /// iceoryx2's reason.
        error: PublisherCreateError,
    },
    /// A subscriber could not be created.
    #[error("subscriber on {service}: {error:?}")]
    Subscriber {
        /// The service's name.
        service: String,
        /// iceoryx2's reason.
        error: SubscriberCreateError,
    },
    /// A listener could not be created.
    #[error("listener on {service}: {error:?}")]
    Listener {
        /// The service's name.
        service: String,
        /// iceoryx2's reason.
        error: ListenerCreateError,
    },
    /// A notifier could not be created.
    #[error(transparent)]
    Notifier(#[from] NotifierCreateError),
    /// No memory to loan for a message.
    #[error(transparent)]
    Loan(#[from] LoanError),
    /// A message could not be sent.
    #[error(transparent)]
    Send(#[from] SendError),
    /// Receivers could not be woken.
    #[error(transparent)]
    Notify(#[from] NotifierNotifyError),
    /// A message could not be received.
    #[error(transparent)]
    Receive(#[from] ReceiveError),
    /// Waiting for a wake-up failed.
    #[error(transparent)]
    Wait(#[from] ListenerWaitError),
    /// The operating system refused a wait.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// Ctrl-C or a termination request arrived while waiting.
    #[error("interrupted")]
    Interrupted,
    /// Fewer receivers than a sender waits for connected in time.
    #[error("only {connected} of {wanted} receivers connected after {timeout:?}")]
    TooFewReceivers {
        /// Receivers connected at the end.
        connected: usize,
        /// Receivers waited for.
        wanted: usize,
        /// How long the sender waited.
        timeout: Duration,
    },
    /// Processes of the run stopped or died while a receiver waited: `who` names them
    /// ("the agent process", "the observer and agent processes").
    #[error("{who} of this run stopped")]
    PeersStopped {
        /// The processes, in words.
        who: String,
    },
    /// No message for longer than the receiver's patience.
    #[error("no message for {0:?}: a peer process stopped")]
    Silence(Duration),
}

impl Error {
    /// Whether a publisher could not be created because the service has as many as it
    /// allows — another process publishes there already.
    pub fn publisher_taken(&self) -> bool {
        matches!(
            self,
            Error::Publisher {
                error: PublisherCreateError::ExceedsMaxSupportedPublishers,
                ..
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Action, Bus, Qos};

    const ONE_PUBLISHER: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 2,
        buffer: 4,
        safe_overflow: true,
    };

    #[test]
    fn a_second_publisher_is_the_typed_publisher_limit() {
        let bus = Bus::join(&format!("errtest{}", std::process::id()), "test").unwrap();
        let service = bus.run_service("limited");
        let _first = bus.tx_on::<Action>(&service, ONE_PUBLISHER).unwrap();
        let Err(e) = bus.tx_on::<Action>(&service, ONE_PUBLISHER) else {
            panic!("a second publisher on a one-publisher service was created");
        };
        assert!(e.publisher_taken(), "{e:?}");
        assert_eq!(
            e.to_string(),
            format!(
                "publisher on {service}: ExceedsMaxSupportedPublishers \
                 (is another process publishing there already?)"
            )
        );
    }

    #[test]
    fn other_errors_are_not_the_publisher_limit() {
        let e = Bus::join("bad id", "test").err().unwrap();
        assert!(matches!(&e, Error::RunId(id) if id == "bad id"), "{e:?}");
        assert!(!e.publisher_taken());
        let e = Bus::join("driver", "test").err().unwrap();
        assert!(matches!(e, Error::ReservedRunId), "{e:?}");
        assert_eq!(
            e.to_string(),
            "run id \"driver\" is reserved for driver services (rig/driver/...)"
        );
    }
}
