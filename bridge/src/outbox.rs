//! The rig's side's way out for commands: the commands of the rig on this host, each
//! with its session's claim ([`crate::claim`]), to the network; the session held on to
//! while that rig is there and silent, and let go when it is gone.
//!
//! Actions go as the loop's messages do: dropped, not queued, when the link cannot take
//! them (the driver's side counts them lost; the driver's watchdog covers them). What
//! must not be lost waits for room on the link instead: RESETs and claims. A RESET is
//! also sent again until a sample of the driver acknowledges it (its `reset_id`): after
//! five periods (at least 200 ms), then after twice as long each time, at most 2 s. A
//! link that dropped it while it was down (Zenoh re-establishes a session that lapsed,
//! but not what was in flight) costs a resend, not the run. The driver's side passes a
//! RESET of a session on once.

use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicI64, AtomicU64, Ordering::Relaxed};
use std::time::Duration;

use crate::error::{Result, zenoh};
use driver::contract::{DRIVER_QOS, DriverCommand, kind, service, topic};
use wire::{Bus, Monotonic};
use zenoh::Wait;
use zenoh::pubsub::Publisher;

use crate::claim::{Claim, Claimant};
use crate::message::{Topic, to_bytes};
use crate::{publisher, reliable_publisher};

/// How long the commands' thread waits for a command at most, and how often a hold
/// goes out while the rig is there and silent (a lease lasts at least 250 ms).
const HOLD_EVERY: Duration = Duration::from_millis(50);

/// What the commands' thread shares with the main one.
#[derive(Default)]
pub(crate) struct Shared {
    pub(crate) stop: AtomicBool,
    /// The driver's clock minus the rig's (ns).
    pub(crate) offset: AtomicI64,
    /// The driver's period (0 until its info came) \[ns\].
    pub(crate) period_ns: AtomicU64,
    /// The newest sample's `reset_id`: the RESET it acknowledges.
    pub(crate) reset_id: AtomicU64,
    /// Commands sent: `(seq, when)`, the newest last.
    pub(crate) sent: Mutex<VecDeque<(u64, u64)>>,
}

/// The publishers and the session's claims.
pub(crate) struct Outbox {
    /// The driver's id.
    id: String,
    /// Actions: dropped when the link cannot take them.
    actions: Publisher<'static>,
    /// RESETs: never dropped.
    resets: Publisher<'static>,
    claims: Publisher<'static>,
    claimant: Claimant,
    /// When the last command or claim went out.
    last_put: u64,
    /// The last RESET, until a sample acknowledges it.
    pending: Unacknowledged,
    /// The time holds and resends are timed on.
    time: Monotonic,
    /// Commands put.
    pub(crate) sent: u64,
    /// RESETs sent again.
    pub(crate) resent: u64,
}

/// A RESET is first sent again after this many periods without an acknowledgement, and
/// after at least [`RESEND_AT_LEAST`]; then after twice as long each time, at most
/// [`RESEND_AT_MOST`] (a congested link is not flooded with them).
const RESEND_PERIODS: u64 = 5;
const RESEND_AT_LEAST: Duration = Duration::from_millis(200);
const RESEND_AT_MOST: Duration = Duration::from_secs(2);

impl Outbox {
    /// The way out for driver `id`'s commands, put as `user` by `session`, timed on
    /// `time`.
    pub(crate) fn new(
        session: &zenoh::Session,
        id: &str,
        user: &str,
        time: Monotonic,
    ) -> Result<Self> {
        let commands = Topic::Command.key_of(id, user);
        Ok(Self {
            id: id.to_string(),
            actions: publisher(session, &commands)?,
            resets: reliable_publisher(session, &commands)?,
            claims: reliable_publisher(session, &Topic::Claim.key_of(id, user))?,
            claimant: Claimant::new(session.zid().to_le_bytes()),
            last_put: 0,
            pending: Unacknowledged::default(),
            time,
            sent: 0,
            resent: 0,
        })
    }

    /// Puts command `c` with the next claim of the session (opened by the first).
    pub(crate) fn command(&mut self, c: &DriverCommand) -> Result<()> {
        let claim = self.claimant.command();
        let reset = c.kind == kind::RESET;
        if reset {
            self.pending.sent(c, self.time.now_ns());
        }
        let out = if reset { &self.resets } else { &self.actions };
        out.put(to_bytes(c))
            .attachment(to_bytes(&claim))
            .wait()
            .map_err(zenoh(|| "publishing a command".to_string()))?;
        self.last_put = self.time.now_ns();
        self.sent += 1;
        Ok(())
    }

    /// No command for a while: holds on to the session while the rig is `there` (a
    /// hold every 50 ms), lets go of it once it is not.
    pub(crate) fn idle(&mut self, there: bool) -> Result<()> {
        if !self.claimant.is_open() {
            return Ok(());
        }
        let claim = match there {
            false => self.claimant.release(),
            true if self.time.now_ns().saturating_sub(self.last_put)
                >= HOLD_EVERY.as_nanos() as u64 =>
            {
                self.claimant.hold()
            }
            true => return Ok(()),
        };
        self.put_claim(&claim)
    }

    /// Sends the pending RESET again if no sample acknowledged it (`acknowledged`: the
    /// newest sample's `reset_id`) in time: five periods of `period_ns`, at least
    /// 200 ms, twice as long after each resend, at most 2 s.
    pub(crate) fn repeat_reset(&mut self, acknowledged: u64, period_ns: u64) -> Result<()> {
        let now = self.time.now_ns();
        let Some((c, waited)) = self.pending.due(acknowledged, period_ns, now) else {
            return Ok(());
        };
        eprintln!(
            "bridge for driver {:?}: RESET {} sent again: no sample acknowledged it within {:.0} ms",
            self.id,
            c.seq,
            waited as f64 * 1e-6
        );
        self.command(&c)?;
        self.sent -= 1;
        self.resent += 1;
        Ok(())
    }

    /// Lets go of the session, if one is open (the bridge stops).
    pub(crate) fn close(&mut self) -> Result<()> {
        if self.claimant.is_open() {
            let claim = self.claimant.release();
            self.put_claim(&claim)?;
        }
        Ok(())
    }

    fn put_claim(&mut self, claim: &Claim) -> Result<()> {
        self.claims
            .put(to_bytes(claim))
            .wait()
            .map_err(zenoh(|| "publishing a claim".to_string()))?;
        self.last_put = self.time.now_ns();
        Ok(())
    }
}

/// The RESET waiting for a sample to acknowledge it: when it went last, and how long
/// to wait before it goes again (0: not sent again yet).
#[derive(Default)]
struct Unacknowledged(Option<(DriverCommand, u64, u64)>);

impl Unacknowledged {
    /// RESET `c` went out at `now`: a new one waits from now.
    fn sent(&mut self, c: &DriverCommand, now: u64) {
        if self.0.is_none_or(|(p, ..)| p.seq != c.seq) {
            self.0 = Some((*c, now, 0));
        }
    }

    /// The RESET to send again at `now`, with how long it waited, if no sample
    /// acknowledged it (`acknowledged`: the newest sample's `reset_id`) in time: five
    /// periods of `period_ns`, at least 200 ms, twice as long after each resend, at
    /// most 2 s.
    fn due(&mut self, acknowledged: u64, period_ns: u64, now: u64) -> Option<(DriverCommand, u64)> {
        let (c, sent, wait) = self.0?;
        if acknowledged == c.seq {
            self.0 = None;
            return None;
        }
        let wait = match wait {
            0 => (RESEND_PERIODS * period_ns).max(RESEND_AT_LEAST.as_nanos() as u64),
            w => w,
        };
        if now.saturating_sub(sent) <= wait {
            return None;
        }
        let next = (2 * wait).min(RESEND_AT_MOST.as_nanos() as u64);
        self.0 = Some((c, now, next));
        Some((c, wait))
    }
}

/// The rig's commands to the network, until stopped, timed on `time`; how many were
/// put, and how many RESETs were sent again.
pub(crate) fn commands_up(
    session: &zenoh::Session,
    (id, user): (&str, &str),
    shared: &Shared,
    time: &Monotonic,
) -> Result<(u64, u64)> {
    let bus = Bus::with_node(&format!("rig-bridge-{id}"), "driver")?;
    let rx = bus.rx_on::<DriverCommand>(&service(id, topic::COMMAND), DRIVER_QOS)?;
    let mut out = Outbox::new(session, id, user, time.clone())?;
    while !shared.stop.load(Relaxed) {
        out.repeat_reset(
            shared.reset_id.load(Relaxed),
            shared.period_ns.load(Relaxed),
        )?;
        let Some(mut c) = rx.recv_timeout(HOLD_EVERY)? else {
            // The rig on this host is there while it holds the command service.
            out.idle(rx.senders() > 0)?;
            continue;
        };
        let sent = time.now_ns();
        c.t_publish_ns = c
            .t_publish_ns
            .saturating_add_signed(shared.offset.load(Relaxed));
        out.command(&c)?;
        let mut q = shared.sent.lock().expect("no panics while holding it");
        if q.len() == 4096 {
            q.pop_front();
        }
        q.push_back((c.seq, sent));
    }
    out.close()?;
    Ok((out.sent, out.resent))
}

#[cfg(test)]
mod tests {
    use super::*;

    use wire::MS;

    /// A RESET goes again after five periods (at least 200 ms) without an
    /// acknowledgement, then after twice as long each time, at most 2 s; an
    /// acknowledgement ends it; a RESET sent again keeps its wait.
    #[test]
    fn an_unacknowledged_reset_goes_again_ever_more_patiently() {
        let (clock, time) = Monotonic::mock();
        let reset = DriverCommand {
            seq: 7,
            kind: kind::RESET,
            ..Default::default()
        };
        let mut pending = Unacknowledged::default();
        pending.sent(&reset, clock.now_ns());
        let mut resent_at = Vec::new();
        let period_ns = 10 * MS;
        while time.now_ns() < 8_000 * MS {
            time.advance(Duration::from_millis(1));
            if let Some((c, _)) = pending.due(6, period_ns, clock.now_ns()) {
                assert_eq!(c.seq, 7);
                pending.sent(&c, clock.now_ns());
                resent_at.push(time.now_ns() / MS);
            }
        }
        assert_eq!(resent_at, [201, 602, 1403, 3004, 5005, 7006]);
        // Five periods of 100 ms are longer than 200 ms.
        let mut pending = Unacknowledged::default();
        pending.sent(&reset, clock.now_ns());
        time.advance(Duration::from_millis(500));
        assert!(pending.due(6, 100 * MS, clock.now_ns()).is_none());
        time.advance(Duration::from_millis(1));
        assert!(pending.due(7, 100 * MS, clock.now_ns()).is_none());
        time.advance(Duration::from_secs(5));
        assert!(pending.due(6, 100 * MS, clock.now_ns()).is_none());
    }
}
