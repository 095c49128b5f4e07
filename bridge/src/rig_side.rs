//! The bridge on the rig's host (`rig bridge rig`): the remote driver's info and samples
//! published here under its id — a stand-in the rig cannot tell from a local driver —
//! and the rig's commands carried back; the link's round trips measured.
//!
//! The driver's stamps (`t_start_ns`, `t_sample_ns`, `t_publish_ns`) are placed on this
//! host's clock by the offset of [`ClockMap`] (nothing is forwarded before the first
//! round trip measured it), and the commands' `t_publish_ns` on the driver's. Per
//! sample, the command it acknowledges gives the network's round trip through the loop;
//! the one-way hops only where both hosts read one clock.

use std::io::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::time::Duration;

use crate::error::{Error, Result, zenoh};
use driver::contract::{
    DRIVER_QOS, DriverInfo, DriverNotice, DriverSample, LinkSample, service, topic,
};
use wire::{Bus, Monotonic, Tx};
use zenoh::Wait;

use crate::claim::Claim;
use crate::clock::{ClockMap, Exchange};
use crate::message::{Ping, Stamps, Topic, from_bytes, to_bytes};
use crate::outbox::{Shared, commands_up};
use crate::refusal::{Heard, Refusal};
use crate::session::{Network, own_user, rig_side};
use crate::timing::{Durations, LinkTiming};
use crate::{Counts, publisher};

/// What `rig bridge rig` serves.
#[derive(Clone, Debug)]
pub struct RigSide {
    /// The driver's id (the same on both hosts).
    pub id: String,
    /// The driver's bridge's endpoint, and this side's credentials.
    pub net: Network,
    /// Whether both hosts read one monotonic clock: stamps pass unchanged and one-way
    /// hops are measured.
    pub same_clock: bool,
    /// How often the link is pinged.
    pub ping_period: Duration,
    /// Silence after which the link is reported lost.
    pub link_timeout: Duration,
    /// Every measurement of the link as CSV (`what,seq,ns`), if given.
    pub timing_out: Option<PathBuf>,
}

/// A message from the network, with when it arrived.
struct Arrival {
    topic: Topic,
    payload: Vec<u8>,
    attachment: Option<Vec<u8>>,
    at: u64,
}

/// How long the rig's bridge waits for a first answer before it says none came.
const SILENT_START: Duration = Duration::from_secs(3);

/// Serves until Ctrl-C or a termination request; returns what was forwarded and the
/// link's timing.
pub fn serve_rig(opts: &RigSide) -> Result<(Counts, LinkTiming)> {
    driver::contract::check_id(&opts.id)?;
    let user = own_user(&opts.net)?;
    let refusals = crate::refusal::listen(None);
    let session = rig_side(&opts.net)?;
    eprintln!(
        "bridge for driver {:?}: connecting to {} as user {user} (session {})",
        opts.id,
        opts.net.endpoint,
        session.zid()
    );
    let time = Monotonic::host();
    let (tx, rx) = channel();
    let _subs: Vec<_> = [Topic::Info, Topic::Sample, Topic::Pong, Topic::Refused]
        .into_iter()
        .map(|t| listen(&session, (&opts.id, t), tx.clone(), time.clone()))
        .collect::<Result<_>>()?;
    let shared = Arc::new(Shared::default());
    let up = {
        let (session, id, shared, time) = (
            session.clone(),
            opts.id.clone(),
            shared.clone(),
            time.clone(),
        );
        std::thread::Builder::new()
            .name("bridge-commands".into())
            .spawn(move || {
                // Whichever half ends, the other follows.
                let r = commands_up(&session, (&id, &user), &shared, &time);
                shared.stop.store(true, Relaxed);
                r
            })?
    };
    let mut side = Stand::new(opts, &session, shared.clone(), time)?;
    side.refusals = Some(refusals);
    let result = side.run(&rx);
    shared.stop.store(true, Relaxed);
    let (commands, resent) = up.join().map_err(|_| Error::Panicked("commands'"))??;
    let _ = session.close().wait();
    result?;
    side.counts.commands = commands;
    side.counts.repeated = resent;
    if let Some(f) = &mut side.log {
        f.flush()?;
    }
    Ok((side.counts, side.timing))
}

/// `--timing-out`'s file, with its header.
fn timing_file(path: &PathBuf) -> Result<std::io::BufWriter<std::fs::File>> {
    let mut f =
        std::io::BufWriter::new(std::fs::File::create(path).map_err(|error| Error::File {
            what: "--timing-out".into(),
            path: path.clone(),
            error,
        })?);
    writeln!(f, "what,seq,ns")?;
    Ok(f)
}

/// Subscribes to driver `id`'s topic `t`, passing each message to `tx` with its arrival
/// time on `time`.
fn listen(
    session: &zenoh::Session,
    (id, t): (&str, Topic),
    tx: Sender<Arrival>,
    time: Monotonic,
) -> Result<zenoh::pubsub::Subscriber<()>> {
    session
        .declare_subscriber(t.key(id))
        .callback(move |s| {
            let _ = tx.send(Arrival {
                topic: t,
                payload: s.payload().to_bytes().into_owned(),
                attachment: s.attachment().map(|a| a.to_bytes().into_owned()),
                at: time.now_ns(),
            });
        })
        .wait()
        .map_err(zenoh(|| format!("subscribing to {}", t.key(id))))
}

/// The stand-in driver on this host.
struct Stand<'a> {
    opts: &'a RigSide,
    bus: Bus,
    info: Tx<DriverInfo>,
    samples: Tx<DriverSample>,
    ping: zenoh::pubsub::Publisher<'static>,
    shared: Arc<Shared>,
    timing: LinkTiming,
    /// `--timing-out`: every measurement as it is made.
    log: Option<std::io::BufWriter<std::fs::File>>,
    counts: Counts,
    heard: u64,
    lost_at: Option<u64>,
    /// When the bridge started, and whether it said that nobody answers.
    started: u64,
    unanswered: bool,
    /// The last command whose round trip was measured.
    acknowledged: u64,
    /// The latest ping's round trip.
    last_ping: u64,
    link: Tx<LinkSample>,
    /// What the driver's side says of this side's commands, for the rig.
    notices: Tx<DriverNotice>,
    /// This side's Zenoh id (whether a refusal is about this side's session).
    zid: [u8; 16],
    /// When the driver's side last said that it refused this side's commands.
    refused_at: u64,
    /// Why this side's connection failed, as Zenoh said, and what was said of it.
    refusals: Option<Arc<Heard>>,
    said: Option<Refusal>,
    /// The time pings, silences and arrivals are measured on.
    time: Monotonic,
}

impl<'a> Stand<'a> {
    fn new(
        opts: &'a RigSide,
        session: &zenoh::Session,
        shared: Arc<Shared>,
        time: Monotonic,
    ) -> Result<Self> {
        let bus = driver::contract::bus(&opts.id)?;
        let taken = |error| Error::Taken {
            doing: format!("standing in for driver {:?}", opts.id),
            error,
            hint: "is that driver running here too?",
        };
        let info = bus
            .tx_on(&service(&opts.id, topic::INFO), DRIVER_QOS)
            .map_err(taken)?;
        let samples = bus
            .tx_on(&service(&opts.id, topic::SAMPLE), DRIVER_QOS)
            .map_err(taken)?;
        let link = bus
            .tx_on(&service(&opts.id, topic::LINK), DRIVER_QOS)
            .map_err(taken)?;
        let notices = bus
            .tx_on(&service(&opts.id, topic::NOTICE), DRIVER_QOS)
            .map_err(taken)?;
        Ok(Self {
            opts,
            info,
            samples,
            bus,
            ping: publisher(session, &Topic::Ping.key(&opts.id))?,
            shared,
            timing: LinkTiming {
                clock: ClockMap::new(opts.same_clock),
                ping: Durations::default(),
                command_round_trip: Durations::default(),
                command_hop: Durations::default(),
                sample_hop: Durations::default(),
            },
            log: match &opts.timing_out {
                Some(path) => Some(timing_file(path)?),
                None => None,
            },
            counts: Counts::default(),
            heard: 0,
            lost_at: None,
            started: time.now_ns(),
            unanswered: false,
            acknowledged: 0,
            last_ping: 0,
            link,
            notices,
            zid: session.zid().to_le_bytes(),
            refused_at: 0,
            refusals: None,
            said: None,
            time,
        })
    }

    /// Pings every period and passes on what arrives, until interrupted.
    fn run(&mut self, rx: &Receiver<Arrival>) -> Result<()> {
        let mut next_ping = self.time.now_ns();
        while !self.bus.interrupted() && !self.shared.stop.load(Relaxed) {
            let now = self.time.now_ns();
            if now >= next_ping {
                let p = Ping {
                    sent: now,
                    ..Default::default()
                };
                self.ping
                    .put(to_bytes(&p))
                    .wait()
                    .map_err(zenoh(|| "pinging".to_string()))?;
                next_ping = now + self.opts.ping_period.as_nanos() as u64;
                self.watch_link(now);
            }
            match rx.recv_timeout(Duration::from_nanos(next_ping.saturating_sub(now))) {
                Ok(a) => self.arrived(a)?,
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
        }
        Ok(())
    }

    fn arrived(&mut self, a: Arrival) -> Result<()> {
        self.heard = a.at;
        match a.topic {
            Topic::Pong => {
                let e = Exchange::of(&from_bytes::<Ping>(&a.payload)?, a.at);
                self.timing.clock.add(e);
                self.shared
                    .offset
                    .store(self.timing.clock.offset(), Relaxed);
                self.timing.ping.push(e.round_trip);
                self.last_ping = e.round_trip;
                self.row("ping_round_trip", 0, e.round_trip)?;
            }
            Topic::Refused => self.refused(&a)?,
            _ if !self.timing.clock.ready() => {}
            Topic::Info => {
                let mut i: DriverInfo = from_bytes(&a.payload)?;
                self.shared.period_ns.store(i.period_ns, Relaxed);
                i.t_start_ns = self.timing.clock.to_rig(i.t_start_ns);
                i.t_publish_ns = self.timing.clock.to_rig(i.t_publish_ns);
                self.info.send(i)?;
                self.counts.infos += 1;
            }
            Topic::Sample => {
                let mut s: DriverSample = from_bytes(&a.payload)?;
                self.shared.reset_id.store(s.reset_id, Relaxed);
                let stamps = match &a.attachment {
                    Some(b) => from_bytes::<Stamps>(b)?,
                    None => Stamps::default(),
                };
                s.t_sample_ns = self.timing.clock.to_rig(s.t_sample_ns);
                s.t_publish_ns = self.timing.clock.to_rig(s.t_publish_ns);
                self.samples.send(s)?;
                self.counts.samples += 1;
                let l = self.time_sample(s.seq, &stamps, a.at)?;
                self.link.send(l)?;
            }
            Topic::Command | Topic::Claim | Topic::Ping => {}
        }
        Ok(())
    }

    /// The driver's side refused a session's commands: when it is this side's, passed on
    /// to the rig ([`DriverNotice`], each time) and logged (at most every 5 s: the
    /// driver's side repeats it every second).
    fn refused(&mut self, a: &Arrival) -> Result<()> {
        let Some(claim) = a
            .attachment
            .as_ref()
            .and_then(|b| from_bytes::<Claim>(b).ok())
        else {
            return Ok(());
        };
        if claim.peer != self.zid {
            return Ok(());
        }
        let said = String::from_utf8_lossy(&a.payload);
        self.notices.send(DriverNotice::new(&said, a.at))?;
        if a.at.saturating_sub(self.refused_at) < 5_000_000_000 {
            return Ok(());
        }
        self.refused_at = a.at;
        self.counts.refused += 1;
        eprintln!("bridge for driver {:?}: refused: {said}", self.opts.id);
        Ok(())
    }

    /// What the link did with sample `seq`, arrived at `at`: the one-way hops on one
    /// clock, the round trip through the command it is the first to acknowledge.
    fn time_sample(&mut self, seq: u64, st: &Stamps, at: u64) -> Result<LinkSample> {
        let clock = &self.timing.clock;
        let mut l = LinkSample {
            seq,
            t_received_ns: at,
            ping_round_trip_ns: self.last_ping,
            clock_offset_ns: clock.offset(),
            clock_uncertainty_ns: clock.uncertainty(),
            ..Default::default()
        };
        if clock.same() && st.forwarded != 0 {
            l.sample_hop_ns = at.saturating_sub(st.forwarded);
            self.timing.sample_hop.push(l.sample_hop_ns);
            self.row("sample_hop", seq, l.sample_hop_ns)?;
        }
        let Some(sent) = self.first_acknowledged(st) else {
            return Ok(l);
        };
        let held = st.forwarded.saturating_sub(st.command_arrived);
        l.command_round_trip_ns = at.saturating_sub(sent).saturating_sub(held);
        self.timing.command_round_trip.push(l.command_round_trip_ns);
        self.row("command_round_trip", st.command, l.command_round_trip_ns)?;
        if self.timing.clock.same() {
            l.command_hop_ns = st.command_arrived.saturating_sub(sent);
            self.timing.command_hop.push(l.command_hop_ns);
            self.row("command_hop", st.command, l.command_hop_ns)?;
        }
        Ok(l)
    }

    /// When the command that `st` says arrived last was sent, if this is the first
    /// sample to say so.
    fn first_acknowledged(&mut self, st: &Stamps) -> Option<u64> {
        if st.command == 0 || st.command == self.acknowledged {
            return None;
        }
        let q = self.shared.sent.lock().expect("no panics while holding it");
        let sent = q.iter().rev().find(|(s, _)| *s == st.command)?.1;
        self.acknowledged = st.command;
        Some(sent)
    }

    /// Says why the connection fails, when Zenoh said and it is news: once the start
    /// went unanswered, or the link is lost.
    fn explain_refusal(&mut self) {
        let latest = self.refusals.as_ref().and_then(|h| h.latest());
        if let Some(r) = latest.filter(|r| self.said.as_ref() != Some(r)) {
            eprintln!(
                "bridge for driver {:?}: {}",
                self.opts.id,
                r.explain(&self.opts.net.endpoint)
            );
            self.said = Some(r);
        }
    }

    /// Reports the link lost after the timeout's silence, and back when it speaks.
    fn watch_link(&mut self, now: u64) {
        if (self.heard == 0 && self.unanswered) || self.lost_at.is_some() {
            self.explain_refusal();
        }
        if self.heard == 0
            && !self.unanswered
            && now - self.started > SILENT_START.as_nanos() as u64
            && self.refusals.as_ref().and_then(|h| h.latest()).is_some()
        {
            self.unanswered = true;
            self.explain_refusal();
        }
        if self.heard == 0
            && !self.unanswered
            && now - self.started > SILENT_START.as_nanos() as u64
        {
            eprintln!(
                "bridge for driver {:?}: no answer from {} after {:.0} s: is `rig bridge driver` running there, and is the user of {} in its credentials file with this password? (a refused session is not reported to this side)",
                self.opts.id,
                self.opts.net.endpoint,
                SILENT_START.as_secs_f64(),
                self.opts.net.credentials.display()
            );
            self.unanswered = true;
        }
        let silent = now.saturating_sub(self.heard);
        match self.lost_at {
            None if self.heard != 0 && silent > self.opts.link_timeout.as_nanos() as u64 => {
                eprintln!(
                    "bridge for driver {:?}: link lost: nothing from {} for {:.0} ms (the driver's watchdog holds the safe action)",
                    self.opts.id,
                    self.opts.net.endpoint,
                    silent as f64 * 1e-6
                );
                self.lost_at = Some(self.heard);
                self.counts.watchdog += 1;
            }
            Some(t) if self.heard > t => {
                eprintln!(
                    "bridge for driver {:?}: link back after {:.1} s",
                    self.opts.id,
                    (self.heard - t) as f64 * 1e-9
                );
                self.lost_at = None;
            }
            _ => {}
        }
    }

    /// One measurement of the link, to `--timing-out`.
    fn row(&mut self, what: &str, seq: u64, ns: u64) -> Result<()> {
        if let Some(f) = &mut self.log {
            writeln!(f, "{what},{seq},{ns}")?;
        }
        Ok(())
    }
}
