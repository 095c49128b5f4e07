//! The bridge on the driver's host (`rig bridge driver`): the driver's info and samples
//! out to the network, the rig's commands in to the driver ([`crate::gate`]), pings
//! answered.
//!
//! Safety stays here, beside the motor, and needs nothing from the network: the driver's
//! own watchdog applies the safe action one period after the last action, whatever
//! happened to the link. The bridge lets one rig session command the driver at a time
//! ([`crate::claim`]), keeps stale commands away from it — an action that answers a
//! sample more than `max_age_periods` older than the newest (a burst the network
//! delivers late, after an outage) — and says, measured on this host, when the watchdog
//! engaged and how long after the last command.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::error::{Error, Result, zenoh};
use driver::contract::{DRIVER_QOS, DriverInfo, DriverSample, service, status, topic};
use wire::{Bus, now_ns};
use zenoh::Wait;
use zenoh::pubsub::Publisher;

use crate::claim::Lease;
use crate::gate::Gate;
use crate::message::{Ping, Stamps, Topic, from_bytes, to_bytes};
use crate::session::{Network, driver_side};
use crate::{Counts, publisher};

/// What `rig bridge driver` serves.
#[derive(Clone, Debug)]
pub struct DriverSide {
    /// The driver's id on this host.
    pub id: String,
    /// Where the rig's bridge connects, and who may.
    pub net: Network,
    /// Commands answering a sample more than this many periods older than the newest
    /// are dropped.
    pub max_age_periods: u64,
    /// Silence of the rig's pings after which the link is reported lost.
    pub link_timeout: Duration,
    /// How long a rig session holds the driver without a word from it.
    pub lease: Lease,
    /// Each action's sample-to-actuation delay across the link as CSV, if given
    /// (`seq,t_sample_ns,t_arrived_ns,sample_to_actuation`, ns on this host's clock: a
    /// file `rig learn --delay-from` takes).
    pub timing_out: Option<std::path::PathBuf>,
}

/// What the two halves share.
#[derive(Default)]
pub(crate) struct Shared {
    pub(crate) stop: AtomicBool,
    /// `seq` of the last command passed to the driver, and when it arrived.
    pub(crate) command: AtomicU64,
    pub(crate) command_arrived: AtomicU64,
    /// When the last ACTION passed to the driver arrived; 0 once a RESET or another
    /// control command followed it.
    pub(crate) action_arrived: AtomicU64,
    /// The newest sample's `seq`.
    pub(crate) newest: AtomicU64,
    /// The driver's period (0 until its info came) \[ns\].
    pub(crate) period_ns: AtomicU64,
    /// When the last ping arrived.
    pinged: AtomicU64,
    /// The recent samples' `(seq, t_sample_ns)`, the newest last.
    pub(crate) sampled: Mutex<VecDeque<(u64, u64)>>,
}

/// Samples remembered for the actions that answer them.
const RECENT: usize = 1024;

/// Serves until Ctrl-C or a termination request; returns what was forwarded.
pub fn serve_driver(opts: &DriverSide) -> Result<Counts> {
    driver::contract::check_id(&opts.id)?;
    let _refusals = crate::refusal::listen(Some(format!("bridge for driver {:?}", opts.id)));
    let session = driver_side(&opts.id, &opts.net)?;
    eprintln!(
        "bridge for driver {:?}: listening on {} (session {})",
        opts.id,
        opts.net.endpoint,
        session.zid()
    );
    let shared = Arc::new(Shared::default());
    let _pong = answer_pings(&session, &opts.id, &shared)?;
    let up = {
        let (session, opts, shared) = (session.clone(), opts.clone(), shared.clone());
        std::thread::Builder::new()
            .name("bridge-up".into())
            .spawn(move || {
                // Whichever half ends, the other follows.
                let r = samples_up(&session, &opts, &shared);
                shared.stop.store(true, Relaxed);
                r
            })?
    };
    let down = commands_down(&session, opts, &shared);
    shared.stop.store(true, Relaxed);
    let up = up.join().map_err(|_| Error::Panicked("samples'"))?;
    let (mut counts, up) = (down?, up?);
    counts.samples = up.samples;
    counts.infos = up.infos;
    counts.watchdog = up.watchdog;
    let _ = session.close().wait();
    Ok(counts)
}

/// Answers each ping at once, from Zenoh's own thread.
fn answer_pings(
    session: &zenoh::Session,
    id: &str,
    shared: &Arc<Shared>,
) -> Result<zenoh::pubsub::Subscriber<()>> {
    let pong = publisher(session, &Topic::Pong.key(id))?;
    let shared = shared.clone();
    session
        .declare_subscriber(Topic::Ping.key(id))
        .callback(move |s| {
            let arrived = now_ns();
            if let Ok(mut p) = from_bytes::<Ping>(&s.payload().to_bytes()) {
                shared.pinged.store(arrived, Relaxed);
                p.arrived = arrived;
                p.answered = now_ns();
                let _ = pong.put(to_bytes(&p)).wait();
            }
        })
        .wait()
        .map_err(zenoh(|| "subscribing to pings".to_string()))
}

/// The rig's commands, from the network to the driver, until stopped.
fn commands_down(session: &zenoh::Session, opts: &DriverSide, shared: &Shared) -> Result<Counts> {
    let bus = Bus::with_node(&format!("rig-bridge-{}", opts.id), "driver")?;
    Gate::open(opts, session, shared, &bus)?.serve(&bus)
}

/// The driver's info and samples, to the network, until stopped; what the driver's
/// watchdog did, and the link's state, said on the way.
fn samples_up(session: &zenoh::Session, opts: &DriverSide, shared: &Shared) -> Result<Counts> {
    let id = &opts.id;
    let bus = Bus::with_node(&format!("rig-bridge-{id}-samples"), "driver")?;
    let info_rx = bus.rx_on::<DriverInfo>(&service(id, topic::INFO), DRIVER_QOS)?;
    let samples = bus.rx_on::<DriverSample>(&service(id, topic::SAMPLE), DRIVER_QOS)?;
    let info_pub = publisher(session, &Topic::Info.key(id))?;
    let sample_pub = publisher(session, &Topic::Sample.key(id))?;
    let mut watch = Watch::new(id, opts.link_timeout);
    let mut counts = Counts::default();
    while !shared.stop.load(Relaxed) {
        while let Some(i) = info_rx.try_recv()? {
            watch.period_ns = i.period_ns;
            shared.period_ns.store(i.period_ns, Relaxed);
            put(&info_pub, to_bytes(&i), None)?;
            counts.infos += 1;
        }
        if let Some(s) = samples.recv_timeout(Duration::from_millis(20))? {
            shared.newest.store(s.seq, Relaxed);
            {
                let mut q = shared.sampled.lock().expect("no panics while holding it");
                if q.len() == RECENT {
                    q.pop_front();
                }
                q.push_back((s.seq, s.t_sample_ns));
            }
            let stamps = Stamps {
                command: shared.command.load(Relaxed),
                command_arrived: shared.command_arrived.load(Relaxed),
                forwarded: now_ns(),
            };
            put(&sample_pub, to_bytes(&s), Some(to_bytes(&stamps)))?;
            counts.samples += 1;
            counts.watchdog += watch.sample(&s, shared.action_arrived.load(Relaxed)) as u64;
        }
        watch.link(shared.pinged.load(Relaxed));
    }
    Ok(counts)
}

fn put(p: &Publisher<'_>, bytes: Vec<u8>, attachment: Option<Vec<u8>>) -> Result<()> {
    let mut put = p.put(bytes);
    if let Some(a) = attachment {
        put = put.attachment(a);
    }
    put.wait()
        .map_err(zenoh(|| format!("publishing on {}", p.key_expr())))
}

/// Says, once each time, when the driver's watchdog engages and when the link goes and
/// comes back.
struct Watch<'a> {
    id: &'a str,
    period_ns: u64,
    timeout: Duration,
    watchdog: bool,
    lost_at: Option<u64>,
}

impl<'a> Watch<'a> {
    fn new(id: &'a str, timeout: Duration) -> Self {
        Self {
            id,
            period_ns: 0,
            timeout,
            watchdog: false,
            lost_at: None,
        }
    }

    /// Whether the watchdog engaged at sample `s`, the last action having arrived at
    /// `action_arrived`; says so.
    fn sample(&mut self, s: &DriverSample, action_arrived: u64) -> bool {
        let engaged = s.has(status::WATCHDOG) && !self.watchdog;
        self.watchdog = s.has(status::WATCHDOG);
        if engaged && self.period_ns != 0 {
            eprintln!("{}", engagement(self.id, s, action_arrived, self.period_ns));
        }
        engaged
    }

    /// Reports the link lost when no ping came for the timeout, and back when one does.
    fn link(&mut self, pinged: u64) {
        if pinged == 0 {
            return;
        }
        let now = now_ns();
        let silent = now.saturating_sub(pinged);
        match self.lost_at {
            None if silent > self.timeout.as_nanos() as u64 => {
                eprintln!(
                    "bridge for driver {:?}: link lost: no ping from the rig for {:.0} ms",
                    self.id,
                    silent as f64 * 1e-6
                );
                self.lost_at = Some(pinged);
            }
            Some(t) if pinged > t => {
                eprintln!(
                    "bridge for driver {:?}: link back after {:.1} s",
                    self.id,
                    (pinged - t) as f64 * 1e-9
                );
                self.lost_at = None;
            }
            _ => {}
        }
    }
}

/// What the driver's bridge says when the driver's watchdog engages at sample `s`: how
/// long after the last action's arrival (`action_arrived`) the safe action took over —
/// within the period the sample closes. After a RESET (`action_arrived` 0) the driver
/// held the state it was reset to, and no time is claimed.
fn engagement(id: &str, s: &DriverSample, action_arrived: u64, period_ns: u64) -> String {
    if action_arrived == 0 {
        return format!(
            "bridge for driver {id:?}: the driver applies the safe action (watchdog) at sample {}, no action having come since its reset",
            s.seq
        );
    }
    let after = s.t_sample_ns.saturating_sub(action_arrived) as f64;
    let period = period_ns as f64;
    format!(
        "bridge for driver {id:?}: the driver applies the safe action (watchdog) from between {:.2} and {:.2} periods after the last action arrived (sample {}, {:.1} ms)",
        (after - period).max(0.0) / period,
        after / period,
        s.seq,
        after * 1e-6
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(seq: u64, t_sample_ns: u64) -> DriverSample {
        DriverSample {
            seq,
            t_sample_ns,
            ..Default::default()
        }
    }

    #[test]
    fn the_time_to_the_safe_action_counts_from_the_last_action_not_from_a_reset() {
        let after_action = engagement("pend", &sample(9, 70_000_000), 10_000_000, 30_000_000);
        assert!(
            after_action.contains("from between 1.00 and 2.00 periods after the last action arrived (sample 9, 60.0 ms)"),
            "{after_action}"
        );
        let after_reset = engagement("pend", &sample(9, 70_000_000), 0, 30_000_000);
        assert!(
            after_reset.contains("no action having come since its reset"),
            "{after_reset}"
        );
        assert!(!after_reset.contains("periods after"), "{after_reset}");
    }
}
