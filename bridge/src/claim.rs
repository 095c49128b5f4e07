//! Who commands the driver: one rig session at a time.
//!
//! A *session* is one rig commanding the driver through the network: a `rig run`, `rig
//! check-driver` or `rig latency` behind a rig's bridge, from its first command until it
//! lets go, or one `rig bridge probe`. Every command it puts carries its [`Claim`] (the
//! command's attachment): the putting peer's Zenoh id, the session's number on that peer
//! and the command's number in the session, from 1. The driver's bridge keeps the
//! [`Tenure`]:
//!
//! - an idle driver goes to the first session that commands it;
//! - that session holds the driver until it lets go ([`kind::RELEASE`]) or its lease
//!   lapses: [`Lease`] — ten periods of the driver, at least 250 ms — without a command or
//!   a hold ([`kind::HOLD`]: the rig's bridge sends one every 50 ms its rig is there
//!   but silent, as while the driver resets);
//! - the commands of every other session are refused: counted, logged with the user and
//!   address that put them (the first of each session), and answered with one line naming
//!   the holder;
//! - the numbers are the session's own, so a rig whose clock is ahead of the others'
//!   locks nobody out: within a session a command not after the last one is out of order,
//!   a skipped number is a command lost on the way (counted), and a RESET passed on once
//!   is not passed on again (the rig's bridge repeats a RESET the driver has not
//!   acknowledged).

use std::collections::HashMap;
use std::time::Duration;

/// Values of [`Claim::kind`].
pub mod kind {
    /// The claim of a command (its attachment).
    pub const COMMAND: u64 = 1;
    /// The session is there and holds on to the driver (no command due).
    pub const HOLD: u64 = 2;
    /// The session is over: the driver is free.
    pub const RELEASE: u64 = 3;
}

/// A session's claim on the driver, with each command it puts and in its holds and
/// releases.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Claim {
    /// The Zenoh id of the peer that puts it (little-endian bytes).
    pub peer: [u8; 16],
    /// Which of the peer's sessions: 1, 2, … in the order it opened them.
    pub session: u64,
    /// The command's number in the session, from 1 (a hold or a release: the last
    /// command's).
    pub seq: u64,
    /// [`kind`].
    pub kind: u64,
}

impl Claim {
    /// Which session this claim is of.
    pub fn id(&self) -> SessionId {
        SessionId {
            peer: self.peer,
            session: self.session,
        }
    }
}

/// A session: a peer and its session's number.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SessionId {
    /// The peer's Zenoh id.
    pub peer: [u8; 16],
    /// The session's number on that peer.
    pub session: u64,
}

impl std::fmt::Display for SessionId {
    /// The peer's Zenoh id as Zenoh writes it, and the session's number: `a1b2…/2`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:x}/{}", u128::from_le_bytes(self.peer), self.session)
    }
}

/// Who put a command: the user it was put as and the address it came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CommandSource {
    /// The user (authenticated: the access control lets each user put on its own keys
    /// only).
    pub user: String,
    /// The peer's address as the driver's host sees it, e.g. `tcp/192.168.1.30:51234`.
    pub address: String,
}

impl std::fmt::Display for CommandSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "user {} at {}", self.user, self.address)
    }
}

/// How long a session holds the driver without a word from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lease {
    /// Periods of the driver.
    pub periods: u64,
    /// The least it lasts, whatever the period.
    pub at_least: Duration,
}

impl Lease {
    /// Ten periods, at least 250 ms.
    pub const DEFAULT: Lease = Lease {
        periods: 10,
        at_least: Duration::from_millis(250),
    };

    /// The lease for a driver of period `period_ns` (0: not known yet) \[ns\].
    pub fn ns(&self, period_ns: u64) -> u64 {
        (self.periods * period_ns).max(self.at_least.as_nanos() as u64)
    }
}

/// The session that holds the driver.
#[derive(Clone, Debug)]
pub struct Holder {
    /// The session.
    pub id: SessionId,
    /// Who it is.
    pub peer: CommandSource,
    /// Since when it holds the driver (monotonic ns).
    pub since: u64,
    /// When it was last heard from.
    heard: u64,
    /// Its last command passed on.
    last: u64,
    /// The driver's `seq` of the last RESET passed on for it.
    last_reset: u64,
}

impl Holder {
    /// "user rig at tcp/…:51234 (session a1b2…/1, for 3.2 s)", at monotonic time `now`.
    pub fn describe(&self, now: u64) -> String {
        format!(
            "{} (session {}, for {:.1} s)",
            self.peer,
            self.id,
            now.saturating_sub(self.since) as f64 * 1e-9
        )
    }
}

/// What to do with a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Pass it on: its session holds the driver (`granted`: from now on); `lost` commands
    /// of the session went missing before it.
    Pass {
        /// The session has just been given the driver.
        granted: bool,
        /// Commands of the session skipped before this one.
        lost: u64,
    },
    /// Not after the last command of its session.
    OutOfOrder,
    /// A RESET of its session passed on already.
    Repeated,
    /// Another session holds the driver; `first`: the first refusal of this session;
    /// `notify`: time to tell it again (once a second).
    Refused {
        /// The first command of this session refused.
        first: bool,
        /// Tell the session who holds the driver.
        notify: bool,
    },
}

/// The driver's holder, judged command by command ([module documentation](self)).
#[derive(Debug, Default)]
pub struct Tenure {
    holder: Option<Holder>,
    /// The last holder and where its commands were, should it come back after its lease
    /// lapsed.
    previous: Option<(SessionId, u64, u64)>,
    /// Refused sessions and when they were last told.
    refused: HashMap<SessionId, u64>,
}

/// How often a refused session is told who holds the driver.
const NOTICE_NS: u64 = 1_000_000_000;

impl Tenure {
    /// The session that holds the driver, if any.
    pub fn holder(&self) -> Option<&Holder> {
        self.holder.as_ref()
    }

    /// Judges a command with claim `claim` at monotonic time `now`; `reset`: the
    /// driver's `seq` if it is a RESET; `peer`: who put it.
    pub fn command(
        &mut self,
        claim: &Claim,
        reset: Option<u64>,
        now: u64,
        peer: impl FnOnce() -> CommandSource,
    ) -> Verdict {
        let id = claim.id();
        let granted = self.holder.is_none();
        if granted {
            let (last, last_reset) = match self.previous {
                Some((p, last, r)) if p == id => (last, r),
                _ => (0, 0),
            };
            self.holder = Some(Holder {
                id,
                peer: peer(),
                since: now,
                heard: now,
                last,
                last_reset,
            });
            self.refused.remove(&id);
        }
        let h = self.holder.as_mut().expect("held from here on");
        if h.id != id {
            let told = self.refused.get(&id).copied();
            let notify = told.is_none_or(|t| now.saturating_sub(t) >= NOTICE_NS);
            if notify {
                self.refused.insert(id, now);
            }
            return Verdict::Refused {
                first: told.is_none(),
                notify,
            };
        }
        h.heard = now;
        if claim.seq <= h.last {
            return Verdict::OutOfOrder;
        }
        let lost = claim.seq - h.last - 1;
        h.last = claim.seq;
        if let Some(seq) = reset {
            if seq == h.last_reset {
                return Verdict::Repeated;
            }
            h.last_reset = seq;
        }
        Verdict::Pass { granted, lost }
    }

    /// A hold or a release with claim `claim` at `now`; a release of the holder frees
    /// the driver and returns who held it.
    pub fn claim(&mut self, claim: &Claim, now: u64) -> Option<Holder> {
        let h = self.holder.as_mut().filter(|h| h.id == claim.id())?;
        h.heard = now;
        (claim.kind == kind::RELEASE).then(|| self.free())
    }

    /// Frees the driver if its holder's lease (`lease_ns`) has lapsed at `now`; returns
    /// who held it.
    pub fn lapse(&mut self, now: u64, lease_ns: u64) -> Option<Holder> {
        let h = self.holder.as_ref()?;
        (now.saturating_sub(h.heard) > lease_ns).then(|| self.free())
    }

    fn free(&mut self) -> Holder {
        let h = self.holder.take().expect("held");
        self.previous = Some((h.id, h.last, h.last_reset));
        h
    }

    /// When the holder was last heard from, if the driver is held.
    pub fn heard(&self) -> Option<u64> {
        self.holder.as_ref().map(|h| h.heard)
    }
}

/// The rig's side of its sessions: opens one at its rig's first command, numbers the
/// commands, holds on, lets go.
#[derive(Clone, Debug)]
pub struct Claimant {
    peer: [u8; 16],
    /// The current session's number (0: none yet).
    session: u64,
    /// Commands put in the current session.
    seq: u64,
    /// Whether a session is open.
    open: bool,
}

impl Claimant {
    /// The claims of the peer with Zenoh id `peer`.
    pub fn new(peer: [u8; 16]) -> Self {
        Self {
            peer,
            session: 0,
            seq: 0,
            open: false,
        }
    }

    /// Whether a session is open.
    pub fn is_open(&self) -> bool {
        self.open
    }

    /// The claim of the next command, opening a session if none is.
    pub fn command(&mut self) -> Claim {
        if !self.open {
            self.open = true;
            self.session += 1;
            self.seq = 0;
        }
        self.seq += 1;
        self.current(kind::COMMAND)
    }

    /// A hold of the open session.
    pub fn hold(&self) -> Claim {
        self.current(kind::HOLD)
    }

    /// The release of the open session, which closes it.
    pub fn release(&mut self) -> Claim {
        self.open = false;
        self.current(kind::RELEASE)
    }

    /// Whether `c` is a claim of this peer's current session.
    pub fn owns(&self, c: &Claim) -> bool {
        c.peer == self.peer && c.session == self.session
    }

    fn current(&self, kind: u64) -> Claim {
        Claim {
            peer: self.peer,
            session: self.session,
            seq: self.seq,
            kind,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peer(user: &str) -> CommandSource {
        CommandSource {
            user: user.into(),
            address: format!("tcp/10.0.0.1:{}", user.len()),
        }
    }

    fn claim(peer: u8, session: u64, seq: u64) -> Claim {
        Claim {
            peer: [peer; 16],
            session,
            seq,
            kind: kind::COMMAND,
        }
    }

    #[test]
    fn one_session_holds_the_driver_until_it_lets_go_or_its_lease_lapses() {
        let mut t = Tenure::default();
        let pass = |granted, lost| Verdict::Pass { granted, lost };
        assert_eq!(
            t.command(&claim(1, 1, 1), None, 0, || peer("a")),
            pass(true, 0)
        );
        // Another peer, and another session of the same peer, are refused; each is told
        // once a second.
        let refused = |first, notify| Verdict::Refused { first, notify };
        assert_eq!(
            t.command(&claim(2, 1, 1), None, 10, || peer("b")),
            refused(true, true)
        );
        assert_eq!(
            t.command(&claim(2, 1, 2), None, 20, || peer("b")),
            refused(false, false)
        );
        assert_eq!(
            t.command(&claim(2, 1, 3), None, 1_000_000_020, || peer("b")),
            refused(false, true)
        );
        assert_eq!(
            t.command(&claim(1, 2, 1), None, 30, || peer("a")),
            refused(true, true)
        );
        // The holder's numbers: in order, skipped ones lost, a RESET passed once.
        assert_eq!(
            t.command(&claim(1, 1, 4), Some(77), 40, || peer("a")),
            pass(false, 2)
        );
        assert_eq!(
            t.command(&claim(1, 1, 4), None, 50, || peer("a")),
            Verdict::OutOfOrder
        );
        assert_eq!(
            t.command(&claim(1, 1, 5), Some(77), 60, || peer("a")),
            Verdict::Repeated
        );
        // A hold keeps the lease; silence beyond it frees the driver.
        let hold = Claim {
            kind: kind::HOLD,
            ..claim(1, 1, 5)
        };
        assert!(t.claim(&hold, 500).is_none());
        assert!(t.lapse(600, 200).is_none());
        let lapsed = t.lapse(701, 200).expect("lapsed");
        assert_eq!((lapsed.peer.user.as_str(), lapsed.since), ("a", 0));
        // The session comes back where it was; a release frees the driver.
        assert_eq!(
            t.command(&claim(1, 1, 6), None, 800, || peer("a")),
            pass(true, 0)
        );
        let release = Claim {
            kind: kind::RELEASE,
            ..claim(1, 1, 6)
        };
        assert!(t.claim(&claim(2, 1, 9), 810).is_none(), "not the holder's");
        assert_eq!(t.claim(&release, 820).map(|h| h.id), Some(release.id()));
        assert!(t.holder().is_none());
        // Then the other peer's session, with numbers of its own.
        assert_eq!(
            t.command(&claim(2, 1, 4), None, 830, || peer("b")),
            pass(true, 3)
        );
        assert_eq!(t.holder().unwrap().peer, peer("b"));
    }

    /// On a mock clock, the default lease of a driver of period 10 ms (100 ms) is 250
    /// ms of silence: a command at 0 and a hold at 200 ms keep the driver held until
    /// 450 ms; it is free a millisecond later. A driver of period 40 ms: 400 ms.
    #[test]
    fn a_lease_lapses_after_its_silence() {
        let (clock, time) = wire::Monotonic::mock();
        let ms = |n: u64| std::time::Duration::from_millis(n);
        let mut t = Tenure::default();
        t.command(&claim(1, 1, 1), None, clock.now_ns(), || peer("a"));
        time.advance(ms(200));
        let hold = Claim {
            kind: kind::HOLD,
            ..claim(1, 1, 1)
        };
        assert!(t.claim(&hold, clock.now_ns()).is_none());
        let lease = Lease::DEFAULT.ns(10_000_000);
        time.advance(ms(250));
        assert!(t.lapse(clock.now_ns(), lease).is_none());
        assert!(
            t.lapse(clock.now_ns(), Lease::DEFAULT.ns(40_000_000))
                .is_none()
        );
        time.advance(ms(1));
        assert!(
            t.lapse(clock.now_ns(), Lease::DEFAULT.ns(40_000_000))
                .is_none()
        );
        assert!(t.lapse(clock.now_ns(), lease).is_some());
        assert!(t.holder().is_none());
    }

    #[test]
    fn a_claimant_numbers_each_session_from_one() {
        let mut c = Claimant::new([7; 16]);
        assert!(!c.is_open());
        assert_eq!((c.command().session, c.command().seq), (1, 2));
        assert_eq!(c.hold().kind, kind::HOLD);
        let r = c.release();
        assert_eq!((r.kind, r.seq, c.is_open()), (kind::RELEASE, 2, false));
        let next = c.command();
        assert_eq!((next.session, next.seq), (2, 1));
        assert!(c.owns(&next) && !c.owns(&r));
        assert_eq!(size_of::<Claim>(), 40);
        let id = SessionId {
            peer: 0xa1b2u128.to_le_bytes(),
            session: 3,
        };
        assert_eq!(id.to_string(), "a1b2/3");
        assert_eq!(Lease::DEFAULT.ns(30_000_000), 300_000_000);
        assert_eq!(Lease::DEFAULT.ns(0), 250_000_000);
    }
}
