//! The driver's side's door for commands: each command from the network is judged —
//! whose session it is ([`Tenure`]), whether it came too late — and passed on to the
//! driver or dropped, counted either way.

use std::io::Write as _;
use std::sync::atomic::Ordering::Relaxed;
use std::time::Duration;

use crate::error::{Error, Result, zenoh};
use driver::contract::{DRIVER_QOS, DriverCommand, kind, service, topic};
use wire::{Bus, Monotonic, Tx};
use zenoh::Wait;
use zenoh::pubsub::Publisher;
use zenoh::sample::Sample;

use super::settings::DriverSide;
use super::shared::Shared;
use crate::claim::{Claim, CommandSource, Tenure, Verdict};
use crate::message::{Topic, from_bytes, to_bytes, user_of};
use crate::{Counts, publisher};

/// The door, and what went through it.
pub(crate) struct Gate<'a> {
    opts: &'a DriverSide,
    session: &'a zenoh::Session,
    shared: &'a Shared,
    tenure: Tenure,
    /// The time commands, claims and leases are judged on.
    time: Monotonic,
    /// The driver's command publisher on this host.
    tx: Tx<DriverCommand>,
    /// Who holds the driver, to the sessions refused.
    refusals: Publisher<'static>,
    timing: Option<std::io::BufWriter<std::fs::File>>,
    pub(crate) counts: Counts,
}

impl<'a> Gate<'a> {
    /// Takes the driver's command service on this host (so that no rig here commands
    /// it meanwhile); judges on `time`.
    pub(crate) fn open(
        (opts, session, shared): (&'a DriverSide, &'a zenoh::Session, &'a Shared),
        bus: &Bus,
        time: Monotonic,
    ) -> Result<Self> {
        let tx = bus
            .tx_on::<DriverCommand>(&service(&opts.id, topic::COMMAND), DRIVER_QOS)
            .map_err(|error| Error::Taken {
                doing: format!("commanding driver {:?}", opts.id),
                error,
                hint: "is a rig commanding it here?",
            })?;
        Ok(Self {
            opts,
            session,
            shared,
            tenure: Tenure::default(),
            time,
            tx,
            refusals: publisher(session, &Topic::Refused.key(&opts.id))?,
            timing: match &opts.timing_out {
                Some(path) => Some(timing_file(path)?),
                None => None,
            },
            counts: Counts::default(),
        })
    }

    /// Passes the commands and claims on until stopped; what went through.
    pub(crate) fn serve(mut self, bus: &Bus) -> Result<Counts> {
        let id = &self.opts.id;
        let subscribe = |t: Topic| {
            self.session
                .declare_subscriber(t.key(id))
                .wait()
                .map_err(zenoh(|| format!("subscribing to {}", t.key(id))))
        };
        let (commands, claims) = (subscribe(Topic::Command)?, subscribe(Topic::Claim)?);
        while !bus.interrupted() && !self.shared.stop.load(Relaxed) {
            while let Ok(Some(s)) = claims.try_recv() {
                self.claim(&s);
            }
            if let Ok(Some(s)) = commands.recv_timeout(Duration::from_millis(10)) {
                self.command(&s)?;
            }
            self.lapse();
        }
        if let Some(f) = &mut self.timing {
            f.flush()?;
        }
        Ok(self.counts)
    }

    fn say(&self, what: std::fmt::Arguments) {
        eprintln!("bridge for driver {:?}: {what}", self.opts.id);
    }

    /// A hold or a release.
    fn claim(&mut self, s: &Sample) {
        let Ok(c) = from_bytes::<Claim>(&s.payload().to_bytes()) else {
            self.counts.malformed += 1;
            return;
        };
        if let Some(h) = self.tenure.claim(&c, self.time.now_ns()) {
            let held = h.describe(self.time.now_ns());
            self.say(format_args!("{held} let go of the driver"));
        }
    }

    /// Frees the driver when its holder's lease lapsed.
    fn lapse(&mut self) {
        let now = self.time.now_ns();
        let lease = self.opts.lease.ns(self.shared.period_ns.load(Relaxed));
        let silent = self.tenure.heard().map(|t| now.saturating_sub(t));
        if let Some(h) = self.tenure.lapse(now, lease) {
            self.say(format_args!(
                "the lease of {} lapsed after {:.0} ms without a word: the driver is free",
                h.describe(now),
                silent.unwrap_or_default() as f64 * 1e-6
            ));
        }
    }

    /// One command from the network: judged, then passed on or dropped.
    fn command(&mut self, s: &Sample) -> Result<()> {
        let arrived = self.time.now_ns();
        let parsed = from_bytes::<DriverCommand>(&s.payload().to_bytes()).and_then(|c| {
            let claim = s.attachment().map(|a| from_bytes::<Claim>(&a.to_bytes()));
            Ok((c, claim.ok_or(Error::Unclaimed)??))
        });
        let (c, claim) = match parsed {
            Ok(p) => p,
            Err(e) => {
                self.counts.malformed += 1;
                self.say(format_args!("dropped a command: {e}"));
                return Ok(());
            }
        };
        let user = user_of(s.key_expr().as_str()).to_string();
        let reset = (c.kind == kind::RESET).then_some(c.seq);
        let session = self.session;
        match self
            .tenure
            .command(&claim, reset, arrived, || peer_of(session, &claim, user))
        {
            Verdict::Pass { granted, lost } => {
                self.counts.lost += lost;
                if granted && let Some(h) = self.tenure.holder() {
                    self.say(format_args!("{} holds the driver", h.describe(arrived)));
                }
                self.pass(&c, arrived)?;
            }
            Verdict::OutOfOrder => self.counts.out_of_order += 1,
            Verdict::Repeated => self.counts.repeated += 1,
            Verdict::Refused { first, notify } => {
                self.counts.refused += 1;
                self.refuse(&claim, s, first, notify);
            }
        }
        Ok(())
    }

    /// Passes command `c`, arrived at `arrived`, to the driver unless it is stale.
    fn pass(&mut self, c: &DriverCommand, arrived: u64) -> Result<()> {
        let newest = self.shared.newest.load(Relaxed);
        if c.kind == kind::ACTION && c.sample_seq + self.opts.max_age_periods < newest {
            self.counts.stale += 1;
            return Ok(());
        }
        self.tx.send(*c)?;
        self.shared.command.store(c.seq, Relaxed);
        self.shared.command_arrived.store(arrived, Relaxed);
        let action_arrived = if c.kind == kind::ACTION { arrived } else { 0 };
        self.shared.action_arrived.store(action_arrived, Relaxed);
        self.counts.commands += 1;
        if let Some(f) = &mut self.timing
            && c.kind == kind::ACTION
        {
            write_delay(f, self.shared, c, arrived)?;
        }
        Ok(())
    }

    /// Says who holds the driver: in this side's log the first time (with who was
    /// refused), to the refused session when `notify`.
    fn refuse(&mut self, claim: &Claim, s: &Sample, first: bool, notify: bool) {
        let now = self.time.now_ns();
        let Some(held) = self.tenure.holder().map(|h| h.describe(now)) else {
            return;
        };
        if first {
            let who = peer_of(self.session, claim, user_of(s.key_expr().as_str()).into());
            self.say(format_args!(
                "refused {who} (session {}): the driver is held by {held}",
                claim.id()
            ));
        }
        if notify {
            let text = format!(
                "driver {:?} is held by {held}: it serves one rig session at a time; this session's commands are refused until that one ends or its lease lapses",
                self.opts.id
            );
            let _ = self.refusals.put(text).attachment(to_bytes(claim)).wait();
        }
    }
}

/// Who put a command of `claim` as `user`: the user, and the address of the link to its
/// peer.
fn peer_of(session: &zenoh::Session, claim: &Claim, user: String) -> CommandSource {
    let address = session
        .info()
        .links()
        .wait()
        .find(|l| l.zid().to_le_bytes() == claim.peer)
        .map_or_else(|| "an unknown address".to_string(), |l| l.dst().to_string());
    CommandSource { user, address }
}

/// `--timing-out`'s file, with its header.
fn timing_file(path: &std::path::Path) -> Result<std::io::BufWriter<std::fs::File>> {
    let f = std::fs::File::create(path).map_err(|error| Error::File {
        what: "--timing-out".into(),
        path: path.to_owned(),
        error,
    })?;
    let mut f = std::io::BufWriter::new(f);
    writeln!(f, "seq,t_sample_ns,t_arrived_ns,sample_to_actuation")?;
    Ok(f)
}

/// The row of action `c`, arrived at `arrived`: from its sample's instant to its arrival,
/// both on this host's clock.
fn write_delay(
    f: &mut impl std::io::Write,
    shared: &Shared,
    c: &DriverCommand,
    arrived: u64,
) -> Result<()> {
    let sampled = {
        let q = shared.sampled.lock().expect("no panics while holding it");
        q.iter()
            .rev()
            .find(|(seq, _)| *seq == c.sample_seq)
            .map(|&(_, t)| t)
    };
    if let Some(t) = sampled {
        let delay = arrived.saturating_sub(t);
        writeln!(f, "{},{t},{arrived},{delay}", c.sample_seq)?;
    }
    Ok(())
}
