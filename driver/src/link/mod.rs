//! The rig's end of the driver contract: finding the running drivers ([`running`]),
//! waiting for a driver's info ([`wait_info`]), watching a driver's traffic
//! ([`DriverWatch`]) and commanding a driver ([`DriverLink`]); whether a driver fits a
//! task ([`fits_task`], [`check_info`]); which command serves a task when no driver
//! answers ([`how_to_serve`]); and the [`conformance`] check a driver passes.

use std::cell::Cell;
use std::time::Duration;

use iceoryx2::prelude::ZeroCopySend;
use wire::{Bus, Monotonic, Rx, Tx};

use crate::contract::{
    DRIVER_QOS, DriverCommand, DriverInfo, DriverNotice, DriverSample, LinkSample, check_id, kind,
    service, status, topic,
};
use crate::error::Error;

pub mod conformance;
mod fits;
mod suggest;

pub use fits::{check_info, fits_task};
pub use suggest::how_to_serve;

/// Drivers whose nodes are alive on this host: `(id, process id)`, by node name.
pub fn running(bus: &Bus) -> Vec<(String, u32)> {
    let mut found: Vec<(String, u32)> = wire::peers(bus.node().config(), wire::DRIVER_RUN)
        .into_iter()
        .filter(|p| p.alive)
        .map(|p| (p.role, p.pid))
        .collect();
    found.sort();
    found
}

/// The newest [`DriverInfo`] published on `rx` within `timeout` (not validated: see
/// [`DriverInfo::validate`]); waits in steps of 100 ms, so Ctrl-C ends the wait. With
/// `say`, a driver silent for a second is said to be awaited, on stderr. The error names
/// the service, the drivers that are running and `serve`: how to start one
/// ([`how_to_serve`]). The timeout is kept on `time`.
pub fn wait_info(
    bus: &Bus,
    rx: &Rx<DriverInfo>,
    id: &str,
    timeout: Duration,
    say: bool,
    serve: &str,
    time: &Monotonic,
) -> Result<DriverInfo, Error> {
    let t0 = time.now_ns();
    let elapsed = || Duration::from_nanos(time.now_ns().saturating_sub(t0));
    let mut said = !say;
    loop {
        let mut newest = rx.recv_timeout(Duration::from_millis(100))?;
        while let Some(i) = rx.try_recv()? {
            newest = Some(i);
        }
        if let Some(i) = newest {
            return Ok(i);
        }
        if bus.interrupted() {
            return Err(wire::Error::Interrupted.into());
        }
        let waited = elapsed();
        if !said && waited >= Duration::from_secs(1) && waited < timeout {
            said = true;
            eprintln!(
                "waiting up to {:.0} s for driver {id:?} (services {}) ...",
                timeout.as_secs_f64(),
                service(id, "*")
            );
        }
        if waited >= timeout {
            let others: Vec<String> = running(bus)
                .into_iter()
                .map(|(id, pid)| format!("{id:?} (pid {pid})"))
                .collect();
            let hint = if others.is_empty() {
                "no driver is running on this host".to_string()
            } else {
                format!("running drivers: {}", others.join(", "))
            };
            return Err(Error::NoInfo {
                id: id.to_string(),
                service: service(id, topic::INFO),
                timeout,
                hint,
                serve: serve.to_string(),
            });
        }
    }
}

/// A read-only view of a driver's traffic (for recorders and monitors): its info,
/// samples and the commands it receives.
pub struct DriverWatch {
    /// The driver's info messages.
    pub info: Rx<DriverInfo>,
    /// The driver's samples.
    pub samples: Rx<DriverSample>,
    /// The commands sent to the driver.
    pub commands: Rx<DriverCommand>,
    /// The link's timing, when a bridge stands in for a driver on another host.
    pub link: Rx<LinkSample>,
}

impl DriverWatch {
    /// Subscribes to driver `id`'s services (creating them if the driver is not there
    /// yet).
    pub fn open(bus: &Bus, id: &str) -> Result<Self, Error> {
        check_id(id)?;
        Ok(Self {
            info: bus
                .rx_on(&service(id, topic::INFO), DRIVER_QOS)
                .map_err(other_version::<DriverInfo>(bus, id))?,
            samples: bus
                .rx_on(&service(id, topic::SAMPLE), DRIVER_QOS)
                .map_err(other_version::<DriverSample>(bus, id))?,
            commands: bus.rx_on(&service(id, topic::COMMAND), DRIVER_QOS)?,
            link: bus.rx_on(&service(id, topic::LINK), DRIVER_QOS)?,
        })
    }
}

/// Names a driver of another protocol version in an error opening its service of
/// payload `T` on `bus`: the service carries another driver message's type (another
/// version's layout). A wrong layout under the right name stays iceoryx2's error.
fn other_version<'a, T: ZeroCopySend>(
    bus: &'a Bus,
    id: &'a str,
) -> impl Fn(wire::Error) -> Error + 'a {
    use iceoryx2::service::builder::publish_subscribe::{
        PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
    };
    move |e| match e {
        wire::Error::Service {
            service,
            error:
                PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(
                    PublishSubscribeOpenError::IncompatibleTypes,
                ),
            found,
            ..
        } if wire::payload_type_name(&service, bus.node().config())
            .is_some_and(|t| t.starts_with("rig.Driver") && t != wire::type_name_of::<T>()) =>
        {
            Error::OtherVersion {
                id: id.to_string(),
                service,
                found,
                speaks: crate::contract::VERSION,
            }
        }
        e => e.into(),
    }
}

/// The rig's end of a driver connection: reads its info and samples, sends commands.
pub struct DriverLink {
    /// The driver id.
    pub id: String,
    info: Rx<DriverInfo>,
    /// The driver's samples.
    pub samples: Rx<DriverSample>,
    commands: Tx<DriverCommand>,
    notices: Rx<DriverNotice>,
    next_seq: Cell<u64>,
    /// The time commands are stamped and silences measured on.
    time: Monotonic,
}

impl DriverLink {
    /// Opens driver `id`'s services (creating them if the driver is not there yet).
    /// Fails with a message naming the service and both layouts when the driver uses an
    /// incompatible payload, and when another rig process is commanding the driver.
    pub fn connect(bus: &Bus, id: &str) -> Result<Self, Error> {
        check_id(id)?;
        let info = bus
            .rx_on::<DriverInfo>(&service(id, topic::INFO), DRIVER_QOS)
            .map_err(other_version::<DriverInfo>(bus, id))?;
        let samples = bus
            .rx_on::<DriverSample>(&service(id, topic::SAMPLE), DRIVER_QOS)
            .map_err(other_version::<DriverSample>(bus, id))?;
        let commands = bus
            .tx_on::<DriverCommand>(&service(id, topic::COMMAND), DRIVER_QOS)
            .map(Tx::waking)
            .map_err(|e| {
                if e.publisher_taken() {
                    Error::InUse {
                        id: id.to_string(),
                        service: service(id, topic::COMMAND),
                    }
                } else {
                    e.into()
                }
            })?;
        Ok(Self {
            id: id.to_string(),
            info,
            samples,
            commands,
            notices: bus.rx_on(&service(id, topic::NOTICE), DRIVER_QOS)?,
            next_seq: Cell::new(wire::now_ns().max(1)),
            time: Monotonic::host(),
        })
    }

    /// The link keeping its time on `time` (by default the host's clock).
    pub fn on(self, time: Monotonic) -> Self {
        Self { time, ..self }
    }

    /// The time now on the link's clock \[ns\].
    pub fn now_ns(&self) -> u64 {
        self.time.now_ns()
    }

    /// The driver's info: the newest one published within `timeout` (not validated:
    /// see [`DriverInfo::validate`]), as [`wait_info`] waits for it.
    pub fn wait_info(
        &self,
        bus: &Bus,
        timeout: Duration,
        say: bool,
        serve: &str,
    ) -> Result<DriverInfo, Error> {
        wait_info(bus, &self.info, &self.id, timeout, say, serve, &self.time)
    }

    fn send(&self, mut cmd: DriverCommand) -> Result<u64, Error> {
        let seq = self.next_seq.get();
        self.next_seq.set(seq + 1);
        cmd.seq = seq;
        cmd.t_publish_ns = self.time.now_ns();
        self.commands.send(cmd)?;
        Ok(seq)
    }

    /// Sends an ACTION answering sample `sample_seq`; returns the command's `seq`.
    pub fn act(&self, u: &[f64], sample_seq: u64) -> Result<u64, Error> {
        let mut cmd = DriverCommand {
            kind: kind::ACTION,
            sample_seq,
            n_u: u.len() as u64,
            ..Default::default()
        };
        cmd.u[..u.len()].copy_from_slice(u);
        self.send(cmd)
    }

    /// Sends a raw command as it is (for conformance checks: wrong dimensions, unknown
    /// kinds); `seq` and `t_publish_ns` are filled in. Returns the `seq`.
    pub fn send_raw(&self, cmd: DriverCommand) -> Result<u64, Error> {
        self.send(cmd)
    }

    /// Sends a RESET to `x0`; returns its `seq`, which the driver reports in
    /// [`DriverSample::reset_id`] when done.
    pub fn reset(&self, x0: &[f64]) -> Result<u64, Error> {
        let mut cmd = DriverCommand {
            kind: kind::RESET,
            n_x: x0.len() as u64,
            ..Default::default()
        };
        cmd.x0[..x0.len()].copy_from_slice(x0);
        self.send(cmd)
    }

    /// The next sample, waiting at most `silence` ([`DriverInfo::silence_limit`]: longer
    /// means the driver stopped), the way `bus` waits ([`wire::Waiting`]: polling, as a
    /// lockstep run does, or blocked until the driver wakes it).
    pub fn next_sample(&self, bus: &Bus, silence: Duration) -> Result<DriverSample, Error> {
        let t0 = self.time.now_ns();
        loop {
            if let Some(s) = self.samples.recv_awhile()? {
                return Ok(s);
            }
            if bus.interrupted() {
                return Err(wire::Error::Interrupted.into());
            }
            if self.time.now_ns().saturating_sub(t0) > silence.as_nanos() as u64 {
                return Err(Error::Stopped {
                    id: self.id.clone(),
                    service: service(&self.id, topic::SAMPLE),
                    silence,
                });
            }
        }
    }

    /// The newest line the driver's side said of this rig's commands (across hosts,
    /// through the rig's bridge, [`DriverNotice`]), if one is waiting.
    pub fn latest_notice(&self) -> Result<Option<String>, Error> {
        let mut newest = None;
        while let Some(n) = self.notices.try_recv()? {
            newest = Some(n);
        }
        Ok(newest.map(|n| n.line()))
    }

    /// Drops every sample waiting; returns the newest, if any.
    pub fn latest_sample(&self) -> Result<Option<DriverSample>, Error> {
        let mut newest = None;
        while let Some(s) = self.samples.try_recv()? {
            newest = Some(s);
        }
        Ok(newest)
    }

    /// Waits until the driver reports reset `reset_id` done (READY), for at most
    /// `timeout`; returns that first READY sample (the trial's start state).
    pub fn wait_ready(
        &self,
        bus: &Bus,
        info: &DriverInfo,
        reset_id: u64,
        timeout: Duration,
    ) -> Result<DriverSample, Error> {
        let t0 = self.time.now_ns();
        let silence = info.silence_limit(timeout);
        loop {
            let s = self.next_sample(bus, silence)?;
            s.validate(info).map_err(|error| Error::Sample {
                id: self.id.clone(),
                error,
            })?;
            if s.reset_id == reset_id && s.has(status::READY) {
                return Ok(s);
            }
            if self.time.now_ns().saturating_sub(t0) > timeout.as_nanos() as u64 {
                return Err(Error::ResetTimeout {
                    id: self.id.clone(),
                    timeout,
                    last: Box::new((&s).into()),
                    said: self.latest_notice()?,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_rig_commanding_one_driver_finds_it_in_use() {
        let id = format!("inuse{}", std::process::id());
        let bus = Bus::join(&format!("linktest{}", std::process::id()), "rig").unwrap();
        let _first = DriverLink::connect(&bus, &id).unwrap();
        let Err(e) = DriverLink::connect(&bus, &id) else {
            panic!("a second link commands driver {id:?}");
        };
        assert!(
            matches!(&e, Error::InUse { id: i, service: s } if *i == id && *s == service(&id, topic::COMMAND)),
            "{e:?}"
        );
        assert!(matches!(
            DriverLink::connect(&bus, "a/b"),
            Err(Error::Id(i)) if i == "a/b"
        ));
    }

    /// A driver silent for longer than the silence limit has stopped, on the link's
    /// time.
    #[test]
    fn a_driver_silent_past_the_limit_has_stopped() {
        let id = format!("silent{}", std::process::id());
        let bus = Bus::join(&format!("silencetest{}", std::process::id()), "rig").unwrap();
        let (clock, time) = Monotonic::mock();
        time.step_each_reading(Duration::from_secs(1));
        let link = DriverLink::connect(&bus, &id).unwrap().on(clock);
        let e = link
            .next_sample(&bus, Duration::from_millis(3_500))
            .unwrap_err();
        assert!(matches!(e, Error::Stopped { .. }), "{e:?}");
        // Read at 0 (the start), then 1, 2 and 3 s within the limit, at 4 s past it.
        assert_eq!(time.now_ns(), 5_000_000_000);
    }
}
