//! The bridge on the driver's host (`rig bridge driver`): the driver's info and samples
//! out to the network, the rig's commands in to the driver ([`gate`]), pings
//! answered.
//!
//! Safety stays here, beside the motor, and needs nothing from the network: the driver's
//! own watchdog applies the safe action one period after the last action, whatever
//! happened to the link. The bridge lets one rig session command the driver at a time
//! ([`crate::claim`]), keeps stale commands away from it — an action that answers a
//! sample more than `max_age_periods` older than the newest (a burst the network
//! delivers late, after an outage) — and says, measured on this host, when the watchdog
//! engaged and how long after the last command.

use std::sync::Arc;
use std::sync::atomic::Ordering::Relaxed;
use std::time::Duration;

use crate::error::{Error, Result, zenoh};
use driver::contract::{DRIVER_QOS, DriverInfo, DriverSample, service, status, topic};
use wire::{Bus, Monotonic};
use zenoh::Wait;
use zenoh::pubsub::Publisher;

use crate::message::{Ping, Stamps, Topic, from_bytes, to_bytes};
use crate::session::driver_side;
use crate::{Counts, publisher};
use gate::Gate;
use settings::DriverSide;
use shared::Shared;

mod gate;
pub(crate) mod settings;
mod shared;

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
    let time = Monotonic::host();
    let _pong = answer_pings(&session, &opts.id, &shared, time.clone())?;
    let up = {
        let (session, opts, shared) = (session.clone(), opts.clone(), shared.clone());
        let time = time.clone();
        std::thread::Builder::new()
            .name("bridge-up".into())
            .spawn(move || {
                // Whichever half ends, the other follows.
                let r = samples_up(&session, &opts, &shared, &time);
                shared.stop.store(true, Relaxed);
                r
            })?
    };
    let down = commands_down(&session, opts, &shared, time);
    shared.stop.store(true, Relaxed);
    let up = up.join().map_err(|_| Error::Panicked("samples'"))?;
    let (mut counts, up) = (down?, up?);
    counts.samples = up.samples;
    counts.infos = up.infos;
    counts.watchdog = up.watchdog;
    let _ = session.close().wait();
    Ok(counts)
}

/// Answers each ping at once, from Zenoh's own thread, stamped on `time`.
fn answer_pings(
    session: &zenoh::Session,
    id: &str,
    shared: &Arc<Shared>,
    time: Monotonic,
) -> Result<zenoh::pubsub::Subscriber<()>> {
    let pong = publisher(session, &Topic::Pong.key(id))?;
    let shared = shared.clone();
    session
        .declare_subscriber(Topic::Ping.key(id))
        .callback(move |s| {
            let arrived = time.now_ns();
            if let Ok(mut p) = from_bytes::<Ping>(&s.payload().to_bytes()) {
                shared.pinged.store(arrived, Relaxed);
                p.arrived = arrived;
                p.answered = time.now_ns();
                let _ = pong.put(to_bytes(&p)).wait();
            }
        })
        .wait()
        .map_err(zenoh(|| "subscribing to pings".to_string()))
}

/// The rig's commands, from the network to the driver, until stopped; judged on `time`.
fn commands_down(
    session: &zenoh::Session,
    opts: &DriverSide,
    shared: &Shared,
    time: Monotonic,
) -> Result<Counts> {
    let bus = Bus::with_node(&format!("rig-bridge-{}", opts.id), "driver")?;
    Gate::open((opts, session, shared), &bus, time)?.serve(&bus)
}

/// The driver's info and samples, to the network, until stopped; what the driver's
/// watchdog did, and the link's state, said on the way; stamped on `time`.
fn samples_up(
    session: &zenoh::Session,
    opts: &DriverSide,
    shared: &Shared,
    time: &Monotonic,
) -> Result<Counts> {
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
                forwarded: time.now_ns(),
            };
            put(&sample_pub, to_bytes(&s), Some(to_bytes(&stamps)))?;
            counts.samples += 1;
            counts.watchdog += watch.sample(&s, shared.action_arrived.load(Relaxed)) as u64;
        }
        watch.link(shared.pinged.load(Relaxed), time.now_ns());
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

    /// Reports the link lost when no ping came for the timeout (`pinged`: when the last
    /// came; `now`: the time now), and back when one does.
    fn link(&mut self, pinged: u64, now: u64) {
        if pinged == 0 {
            return;
        }
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

    /// The link is lost once the rig's pings are silent for longer than the timeout,
    /// and back with the next ping.
    #[test]
    fn the_link_is_lost_after_the_timeout_of_silence() {
        let (clock, time) = Monotonic::mock();
        let mut watch = Watch::new("pend", Duration::from_millis(500));
        watch.link(0, clock.now_ns());
        time.advance(Duration::from_millis(1));
        let pinged = clock.now_ns();
        time.advance(Duration::from_millis(500));
        watch.link(pinged, clock.now_ns());
        assert_eq!(watch.lost_at, None);
        time.advance(Duration::from_millis(1));
        watch.link(pinged, clock.now_ns());
        assert_eq!(watch.lost_at, Some(pinged));
        time.advance(Duration::from_secs(2));
        watch.link(clock.now_ns(), clock.now_ns());
        assert_eq!(watch.lost_at, None);
    }
}
