//! The ends of a topic: a sender that publishes and wakes its receivers, and a receiver
//! that waits for messages.

use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

use crate::{Bus, Error, FOREVER, Waiting, now_ns};

/// Sends messages of type `T` on a topic and wakes its receivers.
pub struct Tx<T: std::fmt::Debug + ZeroCopySend + 'static> {
    pub(crate) publisher: Publisher<ipc::Service, T, ()>,
    pub(crate) notifier: Notifier<ipc::Service>,
    pub(crate) service:
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
    /// Whether sending wakes the receivers (not needed when they poll).
    pub(crate) wake: bool,
}

/// Receives messages of type `T` from a topic.
pub struct Rx<T: std::fmt::Debug + ZeroCopySend + 'static> {
    pub(crate) subscriber: Subscriber<ipc::Service, T, ()>,
    pub(crate) listener: Listener<ipc::Service>,
    pub(crate) service:
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
    pub(crate) waiting: Waiting,
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Tx<T> {
    /// Publishes `msg` and wakes the receivers (unless they poll, [`Waiting::Yield`]).
    pub fn send(&self, msg: T) -> Result<(), Error> {
        self.publisher.loan_uninit()?.write_payload(msg).send()?;
        if self.wake {
            self.notifier.notify()?;
        }
        Ok(())
    }

    /// This sender waking its receivers whatever this process's [`Waiting`]: for
    /// receivers in processes that wait their own way and may block (a driver). A wake-up
    /// the receiver has not taken yet costs the next send nothing.
    pub fn waking(mut self) -> Self {
        self.wake = true;
        self
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
                return Err(Error::Interrupted);
            }
            if t0.elapsed() > timeout {
                return Err(Error::TooFewReceivers {
                    connected: self.receivers(),
                    wanted: n,
                    timeout,
                });
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        Ok(())
    }
}

/// The run's signal that the recorder has read every message (`rig/<run id>/recorded`):
/// a process of a recorded run waits for it before it exits, since what a process sent
/// may be gone from the recorder's queue once the process is ([`Bus::recorded`]).
pub struct RecordedSignal {
    pub(crate) notifier: Notifier<ipc::Service>,
    pub(crate) listener: Listener<ipc::Service>,
}

impl RecordedSignal {
    /// Tells the run's processes that everything is recorded.
    pub fn announce(&self) -> Result<(), Error> {
        self.notifier.notify()?;
        Ok(())
    }

    /// Waits until the recorder announces that everything is recorded, at most
    /// `timeout`, or until the recorder's process (role `rig`) is gone; whether it was
    /// announced.
    pub fn wait(&self, bus: &Bus, timeout: Duration) -> Result<bool, Error> {
        let t0 = std::time::Instant::now();
        while t0.elapsed() < timeout {
            let mut announced = false;
            match self
                .listener
                .timed_wait(|_| announced = true, Duration::from_millis(20))
            {
                Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) | Ok(_) => {}
                Err(e) => return Err(e.into()),
            }
            if announced {
                return Ok(true);
            }
            if bus.interrupted() || bus.lost_peers().iter().any(|p| p == "rig") {
                return Ok(false);
            }
        }
        Ok(false)
    }
}

/// How long a receiver still waits for a message after a peer process has left: what the
/// peer sent last may still be passed on by a process in between.
const PASSING_ON: Duration = Duration::from_millis(250);

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> crate::Inbox<T> for Rx<T> {
    fn try_recv(&self) -> Result<Option<T>, Error> {
        Rx::try_recv(self)
    }

    fn wait_until(&self, t_ns: u64) -> Result<(), Error> {
        Rx::wait_until(self, t_ns)
    }
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> Rx<T> {
    /// Senders currently connected (a process that died may count until iceoryx2 has
    /// cleaned up after it).
    pub fn senders(&self) -> usize {
        self.service.dynamic_config().number_of_publishers()
    }

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

    /// The next message, waiting as long as it takes, the way the bus was told
    /// ([`Waiting`]); errors on Ctrl-C, when a process of the run has stopped or died
    /// (checked every 100 ms of waiting), or when no message arrives for `silence`.
    pub fn recv(&self, bus: &Bus, silence: Duration) -> Result<T, Error> {
        let t0 = std::time::Instant::now();
        loop {
            if let Some(m) = self.recv_awhile()? {
                bus.prime();
                return Ok(m);
            }
            if let Some(m) = self.peers_gone(bus, t0, silence)? {
                bus.prime();
                return Ok(m);
            }
        }
    }

    /// The next message, waiting for it the way this receiver waits ([`Waiting`]) for
    /// at most 100 ms; `None` if none came, so that the caller can check on its
    /// peers and its own time limits before it waits again.
    pub fn recv_awhile(&self) -> Result<Option<T>, Error> {
        match self.waiting {
            Waiting::Block => self.recv_timeout(CHECK_EVERY),
            Waiting::Spin(bound) => self.poll_then_block(bound, std::hint::spin_loop),
            Waiting::Yield(bound) => self.poll_then_block(bound, std::thread::yield_now),
        }
    }

    /// Polls for up to `bound` (at most [`CHECK_EVERY`] at a time), calling `pause`
    /// between polls; then, unless the bound is [`FOREVER`], blocks for the rest of
    /// [`CHECK_EVERY`].
    fn poll_then_block(&self, bound: Duration, pause: fn()) -> Result<Option<T>, Error> {
        if let Some(m) = self.poll(bound.min(CHECK_EVERY), pause)? {
            if bound != FOREVER {
                // The message's wake-up is pending: take it, so that wake-ups do not pile
                // up while the receiver polls.
                self.listener.try_wait(|_| {})?;
            }
            return Ok(Some(m));
        }
        if bound >= CHECK_EVERY {
            return Ok(None);
        }
        self.recv_timeout(CHECK_EVERY - bound)
    }

    /// Polls for up to `bound`, calling `pause` between polls.
    fn poll(&self, bound: Duration, pause: fn()) -> Result<Option<T>, Error> {
        let t0 = std::time::Instant::now();
        loop {
            if let Some(m) = self.try_recv()? {
                return Ok(Some(m));
            }
            if t0.elapsed() >= bound {
                return Ok(None);
            }
            pause();
        }
    }

    /// After a wait without a message: an error if the run was interrupted, a peer
    /// stopped (unless what it sent last comes through after all) or nothing came since
    /// `t0` for `silence`.
    fn peers_gone(
        &self,
        bus: &Bus,
        t0: std::time::Instant,
        silence: Duration,
    ) -> Result<Option<T>, Error> {
        if bus.interrupted() {
            return Err(Error::Interrupted);
        }
        let lost = bus.lost_peers();
        if !lost.is_empty() {
            // A message sent before its sender left is in the queue by now; one that a
            // process in between (the observer) still forwards comes within moments —
            // the plant ends a run by sending SHUTDOWN and exiting.
            if let Some(m) = self.recv_timeout(PASSING_ON)? {
                return Ok(Some(m));
            }
            let who = match lost.as_slice() {
                [one] => format!("the {one} process"),
                [init @ .., last] => format!("the {} and {last} processes", init.join(", ")),
                [] => unreachable!(),
            };
            return Err(Error::PeersStopped { who });
        }
        if t0.elapsed() > silence {
            return Err(Error::Silence(silence));
        }
        Ok(None)
    }
}

/// How often a waiting receiver checks on the run's processes ([`Rx::recv_awhile`]).
const CHECK_EVERY: Duration = Duration::from_millis(100);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Action, Measurement, topic};

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

    #[test]
    fn a_reader_a_whole_buffer_behind_holds_the_publisher_back_and_loses_nothing() {
        let run = format!("backpressure{}", std::process::id());
        let n = crate::BUFFER as u64 + 500;
        let (ready, listening) = std::sync::mpsc::channel();
        let reader = {
            let run = run.clone();
            std::thread::spawn(move || {
                let bus = Bus::join(&run, "reader").unwrap();
                let rx = bus.rx::<Action>(topic::ACTION).unwrap();
                ready.send(()).unwrap();
                let next = || rx.recv(&bus, Duration::from_secs(5)).unwrap().header.seq;
                let first = next();
                // A recorder that falls behind: reads nothing for 300 ms.
                std::thread::sleep(Duration::from_millis(300));
                std::iter::once(first)
                    .chain((1..n).map(|_| next()))
                    .collect::<Vec<u64>>()
            })
        };
        let bus = Bus::join(&run, "writer").unwrap();
        let tx = bus.tx::<Action>(topic::ACTION).unwrap();
        listening.recv().unwrap();
        let t0 = now_ns();
        for seq in 0..n {
            let mut a = Action::default();
            a.header.seq = seq;
            tx.send(a).unwrap();
        }
        let sending = now_ns() - t0;
        let got = reader.join().unwrap();
        // The publisher waited for the reader to make room rather than overwrite.
        assert!(sending >= 200_000_000, "sent in {sending} ns");
        assert_eq!(got, (0..n).collect::<Vec<u64>>());
    }
}
