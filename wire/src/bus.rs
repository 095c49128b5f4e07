//! One process's connection to a run: its iceoryx2 node, the services it opens and the
//! processes of the run it has seen.

use std::time::Duration;

use iceoryx2::prelude::*;

use iceoryx2::port::{BackpressureAction, BackpressureInfo};

use crate::PATIENCE;
use crate::nodes::{DRIVER_RUN, node_name, peers};
use crate::{Error, Qos, RUN_QOS, RecordedSignal, Rx, Tx, Waiting, describe_service, type_name_of};

/// One process's connection to a run.
pub struct Bus {
    node: Node<ipc::Service>,
    run_id: String,
    /// Processes of the run seen alive so far.
    seen: std::cell::RefCell<std::collections::BTreeSet<String>>,
    primed: std::cell::Cell<bool>,
    /// How this process's receivers wait, and so whether its senders wake theirs.
    waiting: Waiting,
}

impl Bus {
    /// Joins run `run_id` as process `name`. Stale resources of dead processes are
    /// cleaned up on the way (iceoryx2's default configuration).
    pub fn join(run_id: &str, name: &str) -> Result<Self, Error> {
        if run_id.is_empty()
            || !run_id
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(Error::RunId(run_id.to_string()));
        }
        if run_id == DRIVER_RUN {
            return Err(Error::ReservedRunId);
        }
        Self::with_node(&node_name(run_id, name), run_id)
    }

    /// A connection through a new node named `node_name`, of run `run_id` (the driver
    /// kit's drivers join as run `driver`).
    pub fn with_node(node_name: &str, run_id: &str) -> Result<Self, Error> {
        set_log_level_from_env_or(LogLevel::Error);
        let node = NodeBuilder::new()
            .name(&NodeName::new(node_name)?)
            .config(&iceoryx2::config::Config::default())
            .create::<ipc::Service>()?;
        Ok(Self {
            node,
            run_id: run_id.to_string(),
            seen: Default::default(),
            primed: Default::default(),
            waiting: Waiting::Block,
        })
    }

    /// This connection with its receivers waiting as `waiting` says (default
    /// [`Waiting::Block`]); its senders then wake their receivers only if the run's
    /// processes may block ([`Waiting::needs_wake_up`]: all processes of a run wait the
    /// same way).
    pub fn with_waiting(mut self, waiting: Waiting) -> Self {
        self.waiting = waiting;
        self
    }

    /// The roles of the live processes of run `run_id`, sorted (e.g. `["agent",
    /// "plant"]`): non-empty when a run with this id is going on. Processes killed
    /// without cleaning up do not count.
    pub fn live_roles(run_id: &str) -> Vec<String> {
        let mut roles: Vec<String> = peers(&iceoryx2::config::Config::default(), run_id)
            .into_iter()
            .filter(|p| p.alive)
            .map(|p| p.role)
            .collect();
        roles.sort();
        roles.dedup();
        roles
    }

    /// The full service name of a run topic: `rig/<run id>/<topic>`.
    pub fn run_service(&self, topic: &str) -> String {
        format!("rig/{}/{topic}", self.run_id)
    }

    /// The iceoryx2 node of this process.
    pub fn node(&self) -> &Node<ipc::Service> {
        &self.node
    }

    fn pubsub<T: std::fmt::Debug + ZeroCopySend + 'static>(
        &self,
        service: &str,
        qos: Qos,
    ) -> Result<
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
        Error,
    > {
        let name = ServiceName::new(service)?;
        self.node
            .service_builder(&name)
            .publish_subscribe::<T>()
            .max_publishers(qos.max_publishers)
            .max_subscribers(qos.max_subscribers)
            .subscriber_max_buffer_size(qos.buffer)
            .enable_safe_overflow(qos.safe_overflow)
            .open_or_create()
            .map_err(|error| Error::Service {
                service: service.to_string(),
                error,
                needs: format!(
                    "payload {} ({} bytes, alignment {}), max {} publisher(s), {} subscribers, buffer {}",
                    type_name_of::<T>(),
                    std::mem::size_of::<T>(),
                    std::mem::align_of::<T>(),
                    qos.max_publishers,
                    qos.max_subscribers,
                    qos.buffer,
                ),
                found: describe_service(&name, self.node.config()),
            })
    }

    fn event(
        &self,
        service: &str,
    ) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, Error> {
        self.node
            .service_builder(&ServiceName::new(service)?)
            .event()
            .open_or_create()
            .map_err(|error| Error::Event {
                service: service.to_string(),
                error,
            })
    }

    /// The run's [`RecordedSignal`] (both ends; a process of a recorded run opens it
    /// when it starts, so that the announcement, made once, reaches it).
    pub fn recorded(&self) -> Result<RecordedSignal, Error> {
        let service = self.run_service("recorded");
        let event = self.event(&service)?;
        Ok(RecordedSignal {
            notifier: event.notifier_builder().create()?,
            listener: event
                .listener_builder()
                .create()
                .map_err(|error| Error::Listener { service, error })?,
        })
    }

    /// A sender on run topic `topic`.
    pub fn tx<T: std::fmt::Debug + ZeroCopySend + 'static>(
        &self,
        topic: &str,
    ) -> Result<Tx<T>, Error> {
        self.tx_on(&self.run_service(topic), RUN_QOS)
    }

    /// A receiver on run topic `topic`.
    pub fn rx<T: std::fmt::Debug + ZeroCopySend + 'static>(
        &self,
        topic: &str,
    ) -> Result<Rx<T>, Error> {
        self.rx_on(&self.run_service(topic), RUN_QOS)
    }

    /// A sender on the service named `service` (publish-subscribe with settings `qos`,
    /// plus the event service of the same name).
    pub fn tx_on<T: std::fmt::Debug + ZeroCopySend + 'static>(
        &self,
        service: &str,
        qos: Qos,
    ) -> Result<Tx<T>, Error> {
        let factory = self.pubsub::<T>(service, qos)?;
        let publisher = factory
            .publisher_builder()
            .max_loaned_samples(2)
            .set_backpressure_handler(|info: &BackpressureInfo| {
                if info.elapsed_time < PATIENCE {
                    BackpressureAction::Retry
                } else {
                    BackpressureAction::DiscardData
                }
            })
            .create()
            .map_err(|error| Error::Publisher {
                service: service.to_string(),
                error,
            })?;
        let notifier = self.event(service)?.notifier_builder().create()?;
        Ok(Tx {
            publisher,
            notifier,
            service: factory,
            wake: self.waiting.needs_wake_up(),
        })
    }

    /// A receiver on the service named `service` (see [`Bus::tx_on`]).
    pub fn rx_on<T: std::fmt::Debug + ZeroCopySend + 'static>(
        &self,
        service: &str,
        qos: Qos,
    ) -> Result<Rx<T>, Error> {
        let factory = self.pubsub::<T>(service, qos)?;
        let subscriber =
            factory
                .subscriber_builder()
                .create()
                .map_err(|error| Error::Subscriber {
                    service: service.to_string(),
                    error,
                })?;
        let listener = self
            .event(service)?
            .listener_builder()
            .create()
            .map_err(|error| Error::Listener {
                service: service.to_string(),
                error,
            })?;
        Ok(Rx {
            subscriber,
            listener,
            service: factory,
            waiting: self.waiting,
        })
    }

    /// Whether Ctrl-C or a termination request arrived.
    pub fn interrupted(&self) -> bool {
        self.node.wait(Duration::ZERO).is_err()
    }

    /// Records, once, which processes of the run are alive (called when the first message
    /// arrives: all of them are running by then), so that [`Bus::lost_peers`] can tell
    /// when one goes.
    pub fn prime(&self) {
        if !self.primed.replace(true) {
            let _ = self.lost_peers();
        }
    }

    /// This run's processes that are gone: seen alive by an earlier call and now dead
    /// (killed without cleaning up) or no longer there, e.g. `["agent"]`.
    pub fn lost_peers(&self) -> Vec<String> {
        let (alive, dead): (Vec<_>, Vec<_>) = peers(self.node.config(), &self.run_id)
            .into_iter()
            .partition(|p| p.alive);
        let alive: Vec<String> = alive.into_iter().map(|p| p.role).collect();
        let dead: Vec<String> = dead.into_iter().map(|p| p.role).collect();
        let mut seen = self.seen.borrow_mut();
        seen.extend(alive.iter().cloned());
        let mut lost: Vec<String> = seen
            .iter()
            .filter(|r| !alive.contains(r))
            .cloned()
            .collect();
        lost.extend(dead);
        lost.sort();
        lost.dedup();
        lost
    }
}
