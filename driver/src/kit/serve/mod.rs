//! The driver's side of the driver contract (`docs/driver.md`): [`serve`] makes a
//! process the driver of a [`Device`] — the clock (a sample every period on
//! `CLOCK_MONOTONIC`), the safety layer of the actuator (clamping, rejection and the
//! watchdog of [`plant::safety::SafetyLayer`]) and resets — so that a driver for a real
//! motor is one `impl Device` for its amplifier and encoder. [`serve_lockstep`] serves a
//! simulation ([`Lockstep`]) without a clock: one period per action.

use wire::{Bus, Monotonic, Rx, Tx};

use crate::contract::{
    DRIVER_QOS, DriverCommand, DriverInfo, DriverSample, VERSION, provides, service, topic,
};
use crate::error::Error;
use crate::kit::device::Device;

mod announce;
mod lockstep;
mod realtime;
mod state;

pub use lockstep::{Lockstep, serve_lockstep};
pub use realtime::serve;

/// The [`DriverInfo`] of `device`, keeping time by `clock`, started at `t_start_ns`,
/// with period `period_ns`.
fn info(device: &impl Device, clock: u64, period_ns: u64, t_start_ns: u64) -> DriverInfo {
    let (task, time_scale) = (device.task(), device.time_scale());
    let mut i = DriverInfo {
        version: VERSION,
        clock,
        n_x: task.state_dim() as u64,
        n_u: task.action_dim() as u64,
        period_ns,
        time_scale,
        watchdog_periods: 1,
        t_start_ns,
        t_publish_ns: t_start_ns,
        provides: if device.provides_reward() {
            provides::REWARD
        } else {
            0
        },
        ..Default::default()
    };
    let name = task.name.as_bytes();
    i.task[..name.len()].copy_from_slice(name);
    i.task_hash = task.hash();
    i.u_min[..task.action_dim()].copy_from_slice(&task.action_low);
    i.u_max[..task.action_dim()].copy_from_slice(&task.action_high);
    i
}

/// What a driver did while it served.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Served {
    /// Samples published.
    pub samples: u64,
    /// Periods missed (woken a whole period late or more).
    pub missed: u64,
}

/// How [`serve`] runs.
#[derive(Clone, Debug, Default)]
pub struct Serving {
    /// Stop after this many samples (`None`: at Ctrl-C or SIGTERM only).
    pub stop_after: Option<u64>,
    /// How long before each sample instant to stop sleeping and poll (a busy core), so
    /// that the instant does not depend on the operating system's wake-up latency \[ns\].
    pub spin_ns: u64,
    /// Log resets, rejected commands, watchdog trips and missed periods to stderr.
    pub verbose: bool,
}

/// A driver's three services (`docs/driver.md`, "Connecting").
struct Services {
    bus: Bus,
    infos: Tx<DriverInfo>,
    samples: Tx<DriverSample>,
    commands: Rx<DriverCommand>,
    id: String,
    /// The time the driver keeps: its instants, stamps and info's second.
    time: Monotonic,
}

impl Services {
    /// Opens the services of driver `driver_id`, keeping time on `time`; a second
    /// driver of the same id is a one-line error.
    fn open(driver_id: &str, time: Monotonic) -> Result<Self, Error> {
        crate::contract::check_id(driver_id)?;
        let bus = Bus::with_node(&crate::contract::node_name(driver_id), wire::DRIVER_RUN)
            .map_err(Error::transport(driver_id))?;
        let open = |t: &str, e: wire::Error| {
            if e.publisher_taken() {
                Error::AlreadyServed {
                    id: driver_id.to_string(),
                    service: service(driver_id, t),
                }
            } else {
                Error::transport(driver_id)(e)
            }
        };
        Ok(Self {
            infos: bus
                .tx_on(&service(driver_id, topic::INFO), DRIVER_QOS)
                .map_err(|e| open(topic::INFO, e))?,
            samples: bus
                .tx_on(&service(driver_id, topic::SAMPLE), DRIVER_QOS)
                .map_err(|e| open(topic::SAMPLE, e))?,
            commands: bus
                .rx_on(&service(driver_id, topic::COMMAND), DRIVER_QOS)
                .map_err(|e| open(topic::COMMAND, e))?,
            bus,
            id: driver_id.to_string(),
            time,
        })
    }

    /// Publishes `advertised`, stamped now.
    fn publish_info(&self, advertised: DriverInfo) -> Result<(), Error> {
        let mut i = advertised;
        i.t_publish_ns = self.time.now_ns();
        self.infos.send(i).map_err(|e| self.err(e))
    }

    /// A transport error, naming the driver.
    fn err(&self, e: wire::Error) -> Error {
        Error::transport(&self.id)(e)
    }
}

/// The sample period of `device` on the monotonic clock \[ns\]: `Ts` over its time scale.
fn period_ns(device: &impl Device) -> Result<u64, Error> {
    let scale = device.time_scale();
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::TimeScale(scale));
    }
    Ok((device.task().ts / scale * 1e9).round() as u64)
}

/// A driver as it starts serving: its services open, its state, zero in effect, its info
/// published.
struct Start {
    io: Services,
    d: state::Driver,
    advertised: DriverInfo,
    t_start: u64,
    period_ns: u64,
}

impl Start {
    /// Starts serving `device` as driver `driver_id`, keeping time by `clock` on `time`.
    fn of(
        device: &mut impl Device,
        driver_id: &str,
        clock: u64,
        time: &Monotonic,
        verbose: bool,
    ) -> Result<Self, Error> {
        let period_ns = period_ns(device)?;
        let io = Services::open(driver_id, time.clone())?;
        let d = state::Driver::new(device.task(), verbose);
        let t_start = time.now_ns();
        device.apply(t_start, &d.u[..d.n_u]);
        let advertised = info(device, clock, period_ns, t_start);
        io.publish_info(advertised)?;
        Ok(Self {
            io,
            d,
            advertised,
            t_start,
            period_ns,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_driver_of_one_id_is_already_served() {
        let id = format!("served{}", std::process::id());
        let _first = Services::open(&id, Monotonic::host()).unwrap();
        let Err(e) = Services::open(&id, Monotonic::host()) else {
            panic!("a second driver {id:?} opened its services");
        };
        assert!(
            matches!(&e, Error::AlreadyServed { id: i, service: s } if *i == id && *s == service(&id, topic::INFO)),
            "{e:?}"
        );
        assert_eq!(
            e.to_string(),
            format!(
                "another driver {id:?} is running: rig/driver/{id}/info has its one publisher already"
            )
        );
        let other = Services::open("a b", Monotonic::host());
        assert!(matches!(other, Err(Error::Id(i)) if i == "a b"));
    }
}
