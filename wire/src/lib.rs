//! The wire contract between plant, observer and agent processes, and the transport
//! over iceoryx2 0.10 zero-copy shared memory.
//!
//! ```text
//! plant ──Measurement──► observer ──Estimate──► agent ──Action──► plant
//!           (rig/<run>/measurement)   (rig/<run>/estimate)   (rig/<run>/action)
//! plant ──Truth──► supervisor only (rig/<run>/truth; angle-only sensing: ground truth)
//! ```
//!
//! Every payload is `#[repr(C)]`, made of `u64`, `f64` and fixed-size arrays of them,
//! sized for the largest system ([`MAX_X`] state and [`MAX_U`] action components), with a
//! versioned `#[type_name]` — iceoryx2 checks only name, size and alignment, so a layout
//! change must change the name. Each publish-subscribe service has an event service of
//! the same name: receivers block on it instead of spinning. Service names live under
//! `rig/<run id>/`, so runs on one host never see each other.
//!
//! Timestamps are `CLOCK_MONOTONIC` nanoseconds ([`now_ns`]), shared by all processes on
//! one host.

use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

/// State components a message can carry.
pub const MAX_X: usize = 8;
/// Action components a message can carry.
pub const MAX_U: usize = 4;

/// Bits of the `flags` field.
pub mod flags {
    /// The sample is a trial's start state `x_0` (no reward yet).
    pub const START: u64 = 1;
    /// The sample is a trial's last; the agent learns but its action is not applied.
    pub const END: u64 = 2;
    /// The trial is a greedy evaluation: no exploration, no learning.
    pub const GREEDY: u64 = 4;
    /// The run is over: forward and exit.
    pub const SHUTDOWN: u64 = 8;
    /// With [`END`]: the trial ended early because the state left the operating range
    /// (§6.4.2); the state is terminal, its value zero.
    pub const TERMINAL: u64 = 16;
    /// Observer → agent, predictive timing: the agent's last transition of the trial;
    /// learn it, no action follows.
    pub const LAST: u64 = 32;
    /// Observer → agent, predictive timing: nothing to learn or act on (the agent's
    /// trial is already closed); acknowledge.
    pub const HOLD: u64 = 64;
    /// Plant → observer, predictive timing: the start state again, right after the
    /// [`START`] exchange and before the trial's first interval, with `u_next` now the
    /// answer to [`START`] — the first interval's action `u_0`, computed from the known
    /// start state. The agent learns `(x_0, u_0) → x̂_{1|0}` and answers `u_1`.
    pub const PRIMED: u64 = 128;
    /// Plant → observer (and on, in every message of the run): the plant does not know
    /// the rewards — its driver measures positions only — so a measurement's `reward`
    /// is NaN (a terminal penalty excepted) and the observer computes `ρ(x̂_k, u_k)`
    /// from its estimate; the estimates carry the rewards the learning curves sum.
    pub const ESTIMATED_REWARD: u64 = 256;
}

/// Header fields shared by all messages.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Header.v1")]
pub struct Header {
    /// Sample counter over the whole run (one per plant sample).
    pub seq: u64,
    /// Learning trial number, 1-based; a greedy trial carries the number of the learning
    /// trial after which it runs.
    pub trial: u64,
    /// Sample index within the trial; 0 is the start state.
    pub step: u64,
    /// [`flags`] bits.
    pub flags: u64,
    /// Simulated time since the start of the run \[s\] (learning trials only advance it).
    pub t_sim: f64,
}

/// Plant → observer: what the sensor measured at sample `step`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Measurement.v3")]
pub struct Measurement {
    /// Sample identification.
    pub header: Header,
    /// Used components of `y` and `u_applied`.
    pub n_x: u64,
    /// Used components of `u_applied`.
    pub n_u: u64,
    /// `r_k = ρ(x_{k−1}, u_{k−1})`, the reward of the transition into this sample (0 at a
    /// trial start).
    pub reward: f64,
    /// The measurement `y_k` (the full state with full-state sensing). Components the
    /// sensor does not measure (an encoder's velocities) are NaN, bit for bit as the
    /// sensor wrote them; the recording writes them as JSON `null`. At a trial start
    /// ([`flags::START`]) `y` is the true start state: the plant has just been put there.
    pub y: [f64; MAX_X],
    /// The action the plant applied over the interval before this sample.
    pub u_applied: [f64; MAX_U],
    /// The action the plant applies from this sample on, as the agent sent it: in
    /// predictive timing (`observer.mode`) the one that arrived for it a sample ahead (zero
    /// at a trial start); NaN in direct timing, where it is not known at the sample
    /// instant (the recording writes `null`).
    pub u_next: [f64; MAX_U],
    /// The sample-to-actuation delay drawn for the interval before this sample \[s\]
    /// (`run.delay_ms` / `run.delay_from`, lockstep; in predictive timing the action
    /// arrived this long after its sample and was held until this one). 0 at a trial
    /// start and in real time.
    pub delay_s: f64,
    /// Monotonic time at which the plant sampled \[ns\].
    pub t_sample_ns: u64,
    /// Monotonic time at which the plant published \[ns\].
    pub t_publish_ns: u64,
    /// Deadlines missed so far in the run (realtime timing: no action arrived within a
    /// sample interval; always 0 in lockstep).
    pub deadline_misses: u64,
}

/// Observer → agent: the state the agent acts on — the estimate `x̂_k` in direct timing,
/// the prediction `x̂_{k+1|k}` in predictive timing — and the agent call it makes
/// (`observer::timing`; the flags [`flags::LAST`] and [`flags::HOLD`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Estimate.v1")]
pub struct Estimate {
    /// Copied from the measurement.
    pub header: Header,
    /// Used components of `x` and `u_applied`.
    pub n_x: u64,
    /// Used components of `u_applied`.
    pub n_u: u64,
    /// The reward the agent learns: the measurement's in direct timing; in predictive
    /// timing `ρ(x̂_k, u_k)` from the estimate (the range penalty on a terminal sample).
    pub reward: f64,
    /// What the agent acts on: `x̂_k` (direct) or `x̂_{k+1|k}` (predictive).
    pub x: [f64; MAX_X],
    /// The action in effect over the interval `x` starts (direct: the measurement's
    /// `u_applied`; predictive: its `u_next`, made safe as the plant makes it).
    pub u_applied: [f64; MAX_U],
    /// The plant's sample time \[ns\].
    pub t_sample_ns: u64,
    /// Monotonic time at which the observer received the measurement \[ns\].
    pub t_received_ns: u64,
    /// Monotonic time at which the observer published \[ns\].
    pub t_publish_ns: u64,
}

/// Agent → plant: the action for the next interval.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Action.v1")]
pub struct Action {
    /// Copied from the estimate it answers.
    pub header: Header,
    /// Used components of `u`.
    pub n_u: u64,
    /// The action `u_k` (the plant saturates it).
    pub u: [f64; MAX_U],
    /// The plant's sample time \[ns\].
    pub t_sample_ns: u64,
    /// Monotonic time at which the agent received the estimate \[ns\].
    pub t_received_ns: u64,
    /// Monotonic time at which the agent published \[ns\].
    pub t_publish_ns: u64,
}

/// Plant → supervisor only: the true state at sample `step` — the *evaluation* channel
/// (ground truth for observer errors and a finite horizon's terminal reward). Published
/// only when the sensor does not measure the full state (with full-state sensing the
/// [`Measurement`] is the truth), on its own topic [`topic::TRUTH`], which the observer
/// and the agent never open: they see the sensor output only.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Truth.v1")]
pub struct Truth {
    /// The header of the [`Measurement`] of the same sample (published right after this).
    pub header: Header,
    /// Used components of `x`.
    pub n_x: u64,
    /// The true state `x_k` (angles wrapped).
    pub x: [f64; MAX_X],
    /// Monotonic time at which the plant sampled \[ns\].
    pub t_sample_ns: u64,
}

/// Topics, relative to a run.
pub mod topic {
    /// Plant → observer.
    pub const MEASUREMENT: &str = "measurement";
    /// Observer → agent.
    pub const ESTIMATE: &str = "estimate";
    /// Agent → plant.
    pub const ACTION: &str = "action";
    /// Plant → supervisor (`rig run`): ground truth, for evaluation only ([`super::Truth`]).
    pub const TRUTH: &str = "truth";
}

/// Subscriber buffer of every service: the recorder may lag this many samples behind.
pub const BUFFER: usize = 4096;

/// `CLOCK_MONOTONIC` now, in nanoseconds.
pub fn now_ns() -> u64 {
    let mut ts = libc_timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes a timespec; CLOCK_MONOTONIC = 1 on Linux.
    unsafe { clock_gettime(1, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

#[repr(C)]
struct libc_timespec {
    tv_sec: i64,
    tv_nsec: i64,
}

unsafe extern "C" {
    fn clock_gettime(clock: i32, ts: *mut libc_timespec) -> i32;
}

/// Publish-subscribe settings of a service. Both ends must use the same values:
/// iceoryx2 refuses to open a service whose settings cannot serve the opener's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// Publishers at most.
    pub max_publishers: usize,
    /// Subscribers at most.
    pub max_subscribers: usize,
    /// Samples a subscriber may have waiting (the oldest is overwritten when full).
    pub buffer: usize,
}

/// Settings of the run topics (`rig/<run id>/...`).
pub const RUN_QOS: Qos = Qos {
    max_publishers: 1,
    max_subscribers: 4,
    buffer: BUFFER,
};

/// The `#[type_name]` of a payload type: its identity across processes and languages.
pub fn type_name_of<T: ZeroCopySend>() -> &'static str {
    // SAFETY: only reads the name; the layout guarantee the trait asks for is the
    // implementer's (every payload here is `#[repr(C)]` and derives it).
    unsafe { <T as ZeroCopySend>::type_name() }
}

/// What an existing publish-subscribe service carries, in words, e.g. "the existing
/// service carries payload `X` (16 bytes, alignment 8), max 1 publisher(s), 8
/// subscribers, buffer 2" — for error messages about incompatible peers.
pub fn describe_service(name: &ServiceName, config: &iceoryx2::config::Config) -> String {
    match ipc::Service::details(name, config, MessagingPattern::PublishSubscribe) {
        Ok(Some(d)) => {
            let ps = d.static_details.publish_subscribe();
            let p = &ps.message_type_details().payload;
            format!(
                "the existing service carries payload {} ({} bytes, alignment {}), max {} publisher(s), {} subscribers, buffer {}",
                p.type_name(),
                p.size(),
                p.alignment(),
                ps.max_publishers(),
                ps.max_subscribers(),
                ps.subscriber_max_buffer_size()
            )
        }
        Ok(None) => "no such service exists yet".to_string(),
        Err(e) => format!("its settings cannot be read ({e:?})"),
    }
}

/// Errors of the transport.
pub type Error = Box<dyn std::error::Error + Send + Sync>;

/// One process's connection to a run.
pub struct Bus {
    node: Node<ipc::Service>,
    run_id: String,
    /// Processes of the run seen alive so far.
    seen: std::cell::RefCell<std::collections::BTreeSet<String>>,
    primed: std::cell::Cell<bool>,
}

/// Sends messages of type `T` on a topic and wakes its receivers.
pub struct Tx<T: std::fmt::Debug + ZeroCopySend + 'static> {
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
}

/// Receives messages of type `T` from a topic.
pub struct Rx<T: std::fmt::Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<ipc::Service, T, ()>,
    listener: Listener<ipc::Service>,
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
            return Err(format!("run id {run_id:?}: use letters, digits, '-' and '_' only").into());
        }
        if run_id == "driver" {
            return Err(
                "run id \"driver\" is reserved for driver services (rig/driver/...)".into(),
            );
        }
        Self::with_node(&format!("rig-{run_id}-{name}"), run_id)
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
        })
    }

    /// The roles of the live processes of run `run_id`, sorted (e.g. `["agent",
    /// "plant"]`): non-empty when a run with this id is going on. Processes killed
    /// without cleaning up do not count.
    pub fn live_roles(run_id: &str) -> Vec<String> {
        use iceoryx2::node::NodeView;
        let prefix = format!("rig-{run_id}-");
        let mut roles = Vec::new();
        let _ = Node::<ipc::Service>::list(&iceoryx2::config::Config::default(), |state| {
            if let NodeState::Alive(v) = &state
                && let Some(role) = v
                    .details()
                    .as_ref()
                    .and_then(|d| d.name().to_string().strip_prefix(&prefix).map(String::from))
            {
                roles.push(role);
            }
            CallbackProgression::Continue
        });
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
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| {
                let found = describe_service(&name, self.node.config());
                format!(
                    "service {service}: {e:?}: this process needs payload {} ({} bytes, alignment {}), \
                     max {} publisher(s), {} subscribers, buffer {}; {found}",
                    type_name_of::<T>(),
                    std::mem::size_of::<T>(),
                    std::mem::align_of::<T>(),
                    qos.max_publishers,
                    qos.max_subscribers,
                    qos.buffer,
                )
                .into()
            })
    }

    fn event(
        &self,
        service: &str,
    ) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, Error> {
        Ok(self
            .node
            .service_builder(&ServiceName::new(service)?)
            .event()
            .open_or_create()
            .map_err(|e| format!("event service {service}: {e:?}"))?)
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
            .create()
            .map_err(|e| {
                format!(
                    "publisher on {service}: {e:?} (is another process publishing there already?)"
                )
            })?;
        let notifier = self.event(service)?.notifier_builder().create()?;
        Ok(Tx {
            publisher,
            notifier,
            service: factory,
        })
    }

    /// A receiver on the service named `service` (see [`Bus::tx_on`]).
    pub fn rx_on<T: std::fmt::Debug + ZeroCopySend + 'static>(
        &self,
        service: &str,
        qos: Qos,
    ) -> Result<Rx<T>, Error> {
        let factory = self.pubsub::<T>(service, qos)?;
        let subscriber = factory
            .subscriber_builder()
            .create()
            .map_err(|e| format!("subscriber on {service}: {e:?}"))?;
        let listener = self
            .event(service)?
            .listener_builder()
            .create()
            .map_err(|e| format!("listener on {service}: {e:?}"))?;
        Ok(Rx {
            subscriber,
            listener,
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
        use iceoryx2::node::NodeView;
        let prefix = format!("rig-{}-", self.run_id);
        let (mut alive, mut dead) = (Vec::new(), Vec::new());
        let _ = Node::<ipc::Service>::list(self.node.config(), |state| {
            let (view_name, is_alive) = match &state {
                NodeState::Alive(v) => (v.details().as_ref().map(|d| d.name().to_string()), true),
                NodeState::Dead(v) => (v.details().as_ref().map(|d| d.name().to_string()), false),
                _ => (None, false),
            };
            if let Some(role) = view_name.as_deref().and_then(|n| n.strip_prefix(&prefix)) {
                if is_alive {
                    alive.push(role.to_string())
                } else {
                    dead.push(role.to_string())
                }
            }
            CallbackProgression::Continue
        });
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

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Tx<T> {
    /// Publishes `msg` and wakes the receivers.
    pub fn send(&self, msg: T) -> Result<(), Error> {
        self.publisher.loan_uninit()?.write_payload(msg).send()?;
        self.notifier.notify()?;
        Ok(())
    }

    /// Receivers currently connected.
    pub fn receivers(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }

    /// Waits until at least `n` receivers are connected (all peers started), for at most
    /// `timeout`.
    pub fn wait_for_receivers(&self, n: usize, timeout: Duration, bus: &Bus) -> Result<(), Error> {
        let t0 = std::time::Instant::now();
        while self.receivers() < n {
            if bus.interrupted() {
                return Err("interrupted".into());
            }
            if t0.elapsed() > timeout {
                return Err(format!(
                    "only {} of {n} receivers connected after {timeout:?}",
                    self.receivers()
                )
                .into());
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        Ok(())
    }
}

/// How long a receiver still waits for a message after a peer process has left: what the
/// peer sent last may still be passed on by a process in between.
const PASSING_ON: Duration = Duration::from_millis(250);

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Rx<T> {
    /// The next message, if one is waiting.
    pub fn try_recv(&self) -> Result<Option<T>, Error> {
        Ok(self.subscriber.receive()?.map(|s| *s))
    }

    /// The next message, waiting for at most `timeout` (`None` if none came).
    ///
    /// A signal that interrupts the wait only ends it early: Ctrl-C and termination
    /// requests are for the caller to notice with [`Bus::interrupted`], and any other
    /// signal (`SIGCONT` after the process was stopped, `SIGWINCH`, …) must not end the
    /// process.
    pub fn recv_timeout(&self, timeout: Duration) -> Result<Option<T>, Error> {
        if let Some(m) = self.try_recv()? {
            return Ok(Some(m));
        }
        match self.listener.timed_wait(|_| {}, timeout) {
            Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) | Ok(_) => {
                self.try_recv()
            }
            Err(e) => Err(e.into()),
        }
    }

    /// Waits until a message may have arrived or until monotonic time `t_ns`, whichever
    /// comes first; [`Rx::try_recv`] then tells which. Unlike [`Rx::recv_timeout`]
    /// (the socket's receive timeout, in whole scheduler ticks) the deadline is kept to
    /// the high-resolution timer's precision: `ppoll(2)` on the listener's socket, whose
    /// pending wake-ups are then cleared. A signal ends the wait early.
    pub fn wait_until(&self, t_ns: u64) -> Result<(), Error> {
        let left = t_ns.saturating_sub(now_ns());
        if left == 0 {
            return Ok(());
        }
        let timeout = libc::timespec {
            tv_sec: (left / 1_000_000_000) as libc::time_t,
            tv_nsec: (left % 1_000_000_000) as libc::c_long,
        };
        let mut fd = libc::pollfd {
            // SAFETY: the descriptor is the listener's own and outlives the call.
            fd: unsafe { self.listener.file_descriptor().native_handle() },
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd, a valid timeout, no signal mask change.
        let ready = unsafe { libc::ppoll(&mut fd, 1, &timeout, std::ptr::null()) };
        if ready < 0 {
            let e = std::io::Error::last_os_error();
            return match e.kind() {
                std::io::ErrorKind::Interrupted => Ok(()),
                _ => Err(e.into()),
            };
        }
        if ready > 0 {
            match self.listener.try_wait(|_| {}) {
                Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) | Ok(_) => {}
                Err(e) => return Err(e.into()),
            }
        }
        Ok(())
    }

    /// The next message, waiting as long as it takes; errors on Ctrl-C, when a process
    /// of the run has stopped or died (checked every 100 ms of waiting), or when no
    /// message arrives for `silence`.
    pub fn recv(&self, bus: &Bus, silence: Duration) -> Result<T, Error> {
        let t0 = std::time::Instant::now();
        loop {
            if let Some(m) = self.recv_timeout(Duration::from_millis(100))? {
                bus.prime();
                return Ok(m);
            }
            if bus.interrupted() {
                return Err("interrupted".into());
            }
            let lost = bus.lost_peers();
            if !lost.is_empty() {
                // A message sent before its sender left is in the queue by now; one that
                // a process in between (the observer) still forwards comes within
                // moments — the plant ends a run by sending SHUTDOWN and exiting.
                if let Some(m) = self.recv_timeout(PASSING_ON)? {
                    bus.prime();
                    return Ok(m);
                }
                let who = match lost.as_slice() {
                    [one] => format!("the {one} process"),
                    [init @ .., last] => format!("the {} and {last} processes", init.join(", ")),
                    [] => unreachable!(),
                };
                return Err(format!("{who} of this run stopped").into());
            }
            if t0.elapsed() > silence {
                return Err(format!("no message for {silence:?}: a peer process stopped").into());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_are_fixed() {
        // Changing a layout must change the type name's version: these sizes pin them.
        assert_eq!(std::mem::size_of::<Header>(), 40);
        // v3: + u_next, delay_s.
        assert_eq!(
            std::mem::size_of::<Measurement>(),
            40 + 3 * 8 + 8 * 8 + 2 * 4 * 8 + 8 + 24
        );
        assert_eq!(
            std::mem::size_of::<Estimate>(),
            40 + 3 * 8 + 8 * 8 + 4 * 8 + 24
        );
        assert_eq!(std::mem::size_of::<Action>(), 40 + 8 + 4 * 8 + 24);
        assert_eq!(std::mem::size_of::<Truth>(), 40 + 8 + 8 * 8 + 8);
        assert_eq!(std::mem::align_of::<Measurement>(), 8);
    }

    #[test]
    fn monotonic_clock_advances() {
        let a = now_ns();
        std::thread::sleep(Duration::from_millis(2));
        assert!(now_ns() >= a + 1_000_000);
    }

    #[test]
    fn round_trip_in_one_process() {
        let run = format!("wiretest{}", std::process::id());
        let bus = Bus::join(&run, "test").unwrap();
        let rx = bus.rx::<Measurement>(topic::MEASUREMENT).unwrap();
        let tx = bus.tx::<Measurement>(topic::MEASUREMENT).unwrap();
        assert_eq!(tx.receivers(), 1);
        let mut m = Measurement {
            n_x: 2,
            reward: -1.5,
            ..Default::default()
        };
        m.header.seq = 7;
        m.y[1] = 3.25;
        tx.send(m).unwrap();
        assert_eq!(rx.recv(&bus, Duration::from_secs(2)).unwrap(), m);
        assert!(rx.try_recv().unwrap().is_none());
        assert!(Bus::join("bad id/..", "x").is_err());
    }

    #[test]
    fn wait_until_keeps_its_deadline_and_wakes_on_arrival() {
        let run = format!("waittest{}", std::process::id());
        let bus = Bus::join(&run, "test").unwrap();
        let rx = bus.rx::<Action>(topic::ACTION).unwrap();
        // Nothing sent: returns at the deadline — not a scheduler tick later, as a socket
        // receive timeout would, every time. Generous bounds, on the median of five
        // waits: on a shared machine one wait can be held up by a stall of the host.
        for wait_us in [300, 3_000] {
            let mut late: Vec<u64> = (0..5)
                .map(|_| {
                    let t0 = now_ns();
                    rx.wait_until(t0 + wait_us * 1000).unwrap();
                    let waited = now_ns() - t0;
                    assert!(waited >= wait_us * 1000, "woke after {waited} ns");
                    waited - wait_us * 1000
                })
                .collect();
            late.sort_unstable();
            assert!(late[2] < 2_000_000, "woke late by {late:?} ns");
            assert!(rx.try_recv().unwrap().is_none());
        }
        // A message sent from another thread 20 ms into a 2 s wait ends it.
        let sender = std::thread::spawn(move || {
            let bus = Bus::join(&run, "sender").unwrap();
            let tx = bus.tx::<Action>(topic::ACTION).unwrap();
            std::thread::sleep(Duration::from_millis(20));
            let mut a = Action::default();
            a.header.seq = 9;
            tx.send(a).unwrap();
            std::thread::sleep(Duration::from_millis(200));
        });
        let t0 = now_ns();
        let mut got = None;
        while got.is_none() && now_ns() < t0 + 2_000_000_000 {
            rx.wait_until(t0 + 2_000_000_000).unwrap();
            got = rx.try_recv().unwrap();
        }
        let waited = now_ns() - t0;
        assert_eq!(got.map(|a| a.header.seq), Some(9));
        assert!(waited < 1_000_000_000, "woke {waited} ns after the start");
        sender.join().unwrap();
    }
}
