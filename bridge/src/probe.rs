//! `rig bridge probe`: what a peer with given credentials — or none — can do at a
//! driver's bridge, seen from its own host: whether the driver's info and samples reach
//! it, and whether the zero actions it puts reach the driver (the driver's bridge counts
//! what it passed on, and tells a probe refused who holds the driver: a probe is a rig
//! session of its own, [`crate::claim`]). To check an access-control setup from another
//! machine.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::error::{Result, zenoh};
use driver::contract::{DriverCommand, DriverSample, kind};
use wire::Monotonic;
use zenoh::Wait;

use crate::claim::{Claim, Claimant};
use crate::message::{Topic, from_bytes, to_bytes};
use crate::publisher;
use crate::session::{Network, own_user, probe_side};

/// What a probe saw.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Probed {
    /// Info messages that arrived.
    pub infos: u64,
    /// Samples that arrived.
    pub samples: u64,
    /// Zero actions put (whether they arrived is the driver's bridge's count).
    pub commands: u64,
    /// What the driver's bridge said when it refused the zero actions: who holds the
    /// driver.
    pub refused: Option<String>,
    /// Why this side's connection did not become a session, as far as Zenoh said.
    pub unconnected: Option<String>,
}

impl Probed {
    /// Whether anything arrived from the driver.
    pub fn received(&self) -> bool {
        self.infos + self.samples > 0
    }
}

/// How often a probe puts a zero action.
const ZERO_ACTION_EVERY: Duration = Duration::from_millis(10);

/// How long a probe listens after its last action, for a refusal on its way.
const LAST_WORD: Duration = Duration::from_millis(100);

/// Calls `tick` with the time every `period` of `time`, from now for `seconds`.
fn every(time: &Monotonic, period: Duration, seconds: f64, mut tick: impl FnMut(u64)) {
    let t0 = time.now_ns();
    let end = t0 + (seconds * 1e9) as u64;
    let mut next = t0;
    loop {
        let now = time.now_ns();
        if now >= end {
            return;
        }
        tick(now);
        next = next.max(now) + period.as_nanos() as u64;
        time.sleep_until(next);
    }
}

/// Connects to `net.endpoint` with `net`'s credentials (or, if `anonymous`, none) for
/// `seconds`, listens to driver `id`'s info and samples and, if `zero_actions`, puts a
/// zero action every 10 ms.
pub fn probe(
    id: &str,
    net: &Network,
    anonymous: bool,
    zero_actions: bool,
    seconds: f64,
) -> Result<Probed> {
    driver::contract::check_id(id)?;
    let user = match anonymous {
        true => "anonymous".to_string(),
        false => own_user(net)?,
    };
    let heard = crate::refusal::listen(None);
    let session = probe_side(net, anonymous)?;
    // Infos, samples, the newest sample's seq (the one a zero action answers).
    let counters = Arc::new([AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)]);
    let _subs: Vec<_> = [Topic::Info, Topic::Sample]
        .into_iter()
        .enumerate()
        .map(|(i, t)| {
            let c = counters.clone();
            session
                .declare_subscriber(t.key(id))
                .callback(move |m| {
                    c[i].fetch_add(1, Relaxed);
                    if let Ok(s) = from_bytes::<DriverSample>(&m.payload().to_bytes()) {
                        c[2].store(s.seq, Relaxed);
                    }
                })
                .wait()
                .map_err(zenoh(|| format!("subscribing to {}", t.key(id))))
        })
        .collect::<Result<_>>()?;
    let mut claimant = Claimant::new(session.zid().to_le_bytes());
    let refused = Arc::new(Mutex::new(None));
    let _refusals = {
        let (refused, peer) = (refused.clone(), session.zid().to_le_bytes());
        session
            .declare_subscriber(Topic::Refused.key(id))
            .callback(move |m| {
                let ours = m
                    .attachment()
                    .and_then(|a| from_bytes::<Claim>(&a.to_bytes()).ok())
                    .is_some_and(|c| c.peer == peer);
                if ours {
                    let text = String::from_utf8_lossy(&m.payload().to_bytes()).into_owned();
                    *refused.lock().expect("no panics while holding it") = Some(text);
                }
            })
            .wait()
            .map_err(zenoh(|| {
                format!("subscribing to {}", Topic::Refused.key(id))
            }))?
    };
    let out = publisher(&session, &Topic::Command.key_of(id, &user))?;
    let mut commands = 0;
    let time = Monotonic::host();
    every(&time, ZERO_ACTION_EVERY, seconds, |now| {
        if zero_actions {
            let c = DriverCommand {
                seq: now,
                kind: kind::ACTION,
                sample_seq: counters[2].load(Relaxed),
                t_publish_ns: now,
                n_u: 1,
                ..Default::default()
            };
            // A refused session drops the put without an error, as it should.
            let claim = to_bytes(&claimant.command());
            let _ = out.put(to_bytes(&c)).attachment(claim).wait();
            commands += 1;
        }
    });
    if claimant.is_open() {
        let release = claimant.release();
        let claims = publisher(&session, &Topic::Claim.key_of(id, &user))?;
        let _ = claims.put(to_bytes(&release)).wait();
    }
    // Time for a last refusal on its way.
    time.sleep_until(time.now_ns() + LAST_WORD.as_nanos() as u64);
    let _ = session.close().wait();
    let refused = refused.lock().expect("no panics while holding it").take();
    Ok(Probed {
        infos: counters[0].load(Relaxed),
        samples: counters[1].load(Relaxed),
        commands,
        refused,
        unconnected: heard.latest().map(|r| r.explain(&net.endpoint)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A probe of 100 ms puts its zero actions every 10 ms, on time even when a put
    /// takes a while.
    #[test]
    fn a_probe_acts_every_ten_milliseconds_for_its_length() {
        let (clock, time) = Monotonic::mock();
        let mut at = Vec::new();
        every(&clock, ZERO_ACTION_EVERY, 0.1, |now| {
            at.push(now / 1_000_000);
            time.advance(Duration::from_millis(3));
        });
        assert_eq!(at, (0..10).map(|i| 10 * i).collect::<Vec<_>>());
        assert_eq!(time.now_ns(), 100_000_000);
    }
}
