//! The run's clock: what moves a run of three processes from one sample to the next —
//! the plant in lockstep with the agent, the plant on the monotonic clock, or an
//! external driver. Its rules (which configurations it refuses) are here, and nowhere
//! else. They are checked once where a run is set up — a run's options carry the proof,
//! [`Checked`], on to the plant node's settings file — or, by a plant node started by
//! hand, from its settings file.

use std::time::Duration;

use driver::contract::DriverInfo;
use serde::{Deserialize, Serialize};
use wire::Waiting;

use crate::config::ExperimentConfig;
use plant::config::ConfigError;

plant::choice! {
    /// How the simulated plant keeps time (`rig run --timing`, `rig sim-driver --clock`).
    #[derive(Debug, PartialEq, Eq)]
    pub enum Timing {
        /// Simulated time advances only when the action for a sample has arrived
        /// (deterministic).
        Lockstep => "lockstep",
        /// Samples at absolute deadlines of the monotonic clock; a late action is applied
        /// from the moment it arrives.
        Realtime => "realtime",
    }
}

/// An external driver in place of the simulated plant (`rig run --plant external`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExternalDriver {
    /// The driver's id (services `rig/driver/<id>/...`).
    pub id: String,
    /// How long to wait for the driver to appear (in a settings file: seconds).
    #[serde(with = "seconds")]
    pub timeout: Duration,
    /// How long one reset may take (in a settings file: seconds).
    #[serde(with = "seconds")]
    pub reset_timeout: Duration,
}

/// How the command line names an external driver.
#[derive(Clone, Copy, Debug)]
pub struct DriverFlags<'a> {
    /// `--driver` (default: the task's name).
    pub id: Option<&'a str>,
    /// `--driver-timeout` and `--reset-timeout` \[s\].
    pub timeouts: (f64, f64),
}

impl ExternalDriver {
    /// The driver `id` — by default the task's name `task` (one a driver id cannot be,
    /// with '.', needs `--driver`) — waited for `timeout` seconds, given `reset_timeout`
    /// seconds per reset (`--driver`, `--driver-timeout`, `--reset-timeout`), checked.
    pub fn named(
        id: Option<&str>,
        task: &str,
        (timeout, reset_timeout): (f64, f64),
    ) -> Result<Self, ClockError> {
        let id = id.unwrap_or(task).to_string();
        driver::contract::check_id(&id).map_err(ClockError::DriverId)?;
        Ok(Self {
            id,
            timeout: seconds("--driver-timeout", timeout)?,
            reset_timeout: seconds("--reset-timeout", reset_timeout)?,
        })
    }
}

/// A clock the command line or a settings file asks for that cannot be: the flag or key,
/// and what it may be.
#[derive(Debug, thiserror::Error)]
pub enum ClockError {
    /// `--speed` outside (0, [`MAX_SPEED`]].
    #[error("`--speed` {0} is out of range: must be a number in (0, {MAX_SPEED}]")]
    Speed(f64),
    /// A speed so high that the period rounds to zero.
    #[error("the real-time period is zero: `--speed` is too high for the task's sampling time")]
    ZeroPeriod,
    /// A time in seconds (`flag`) outside (0, 1e6].
    #[error("`{flag}` {value} is out of range: must be a number of seconds in (0, 1e6]")]
    Seconds {
        /// The flag.
        flag: &'static str,
        /// Its value.
        value: f64,
    },
    /// `--timing`/`--speed` given with an external driver.
    #[error("`--timing`/`--speed` do not apply with `--plant external`: the driver is the clock")]
    ExternalTiming,
    /// A driver id the contract does not allow.
    #[error("`--driver`: {0}")]
    DriverId(driver::Error),
    /// A driver timeout of zero (a settings file).
    #[error("the driver's `timeout` and `reset_timeout` must be longer than zero")]
    ZeroTimeout,
    /// An injected delay outside lockstep.
    #[error(
        "`--delay-ms`/`--delay-from` (run.delay_ms, run.delay_from) apply in lockstep with the simulated plant only: in real time the delays are real"
    )]
    Delayed,
    /// Predictive timing against an external driver.
    #[error(
        "predictive timing (`observer.mode = \"predictive\"`) needs the simulated plant: an external driver applies each action as it arrives (use `--observer-mode direct`)"
    )]
    Predictive,
    /// Polling without end outside lockstep.
    #[error(
        "`--wait spin|yield` without `--wait-us` applies in lockstep only (the simulated plant, or a driver that keeps the lockstep clock): in real time the plant sleeps until its next sample and must be woken"
    )]
    Unwoken,
    /// A task the rig cannot simulate, on the simulated plant.
    #[error(transparent)]
    Simulated(#[from] ConfigError),
}

/// `s` seconds of flag `flag`, in (0, 1e6].
pub fn seconds(flag: &'static str, s: f64) -> Result<Duration, ClockError> {
    if !(s.is_finite() && s > 0.0 && s <= 1e6) {
        return Err(ClockError::Seconds { flag, value: s });
    }
    Ok(Duration::from_secs_f64(s))
}

/// The run's clock.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Clock {
    /// The simulated plant; simulated time advances when the action has arrived.
    Lockstep,
    /// The simulated plant, sampled every `period` of the monotonic clock.
    Realtime {
        /// The sampling period on the monotonic clock (the task's `Ts` divided by the
        /// speed, [`Clock::realtime`]; in a settings file: seconds).
        #[serde(with = "seconds")]
        period: Duration,
    },
    /// An external driver's system, which is the clock.
    External(ExternalDriver),
}

/// Proof that a run's clock was checked against its experiment ([`Clock::check`]):
/// what [`crate::run::RunOptions`] asks for, so that the run does not check it again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Checked(pub(crate) ());

/// The fastest a simulated plant may run in real time, × its sampling time.
pub const MAX_SPEED: f64 = 1000.0;

impl Clock {
    /// The simulated plant in real time, `speed` times faster than its sampling time `ts`
    /// \[s\] (`--speed`): the one conversion from a speed to a period.
    pub fn realtime(ts: f64, speed: f64) -> Result<Self, ClockError> {
        if !(speed.is_finite() && speed > 0.0 && speed <= MAX_SPEED) {
            return Err(ClockError::Speed(speed));
        }
        Ok(Self::Realtime {
            period: Duration::from_nanos((ts * 1e9 / speed).round() as u64),
        })
    }

    /// The clock `--timing` and `--speed` ask for, against the simulated plant of
    /// sampling time `ts` \[s\] and name `task`; `driver`: an external driver instead
    /// (`--plant external`), which keeps its own time.
    pub fn of_flags(
        (timing, speed): (Timing, f64),
        (ts, task): (f64, &str),
        driver: Option<DriverFlags<'_>>,
    ) -> Result<Self, ClockError> {
        // The speed is checked whatever the timing.
        let realtime = Self::realtime(ts, speed)?;
        match (timing, driver) {
            (_, Some(_)) if timing == Timing::Realtime || speed != 1.0 => {
                Err(ClockError::ExternalTiming)
            }
            (_, Some(d)) => ExternalDriver::named(d.id, task, d.timeouts).map(Self::External),
            (Timing::Lockstep, None) => Ok(Self::Lockstep),
            (Timing::Realtime, None) => Ok(realtime),
        }
    }

    /// Whether simulated time waits for the agent (deterministic).
    pub fn is_lockstep(&self) -> bool {
        matches!(self, Self::Lockstep)
    }

    /// Whether the simulated plant keeps real time, sampled every period of the
    /// monotonic clock.
    pub fn is_realtime(&self) -> bool {
        matches!(self, Self::Realtime { .. })
    }

    /// Whether an external driver is the plant, and the clock.
    pub fn is_external(&self) -> bool {
        matches!(self, Self::External(_))
    }

    /// The external driver, if the plant is one.
    pub fn driver(&self) -> Option<&ExternalDriver> {
        match self {
            Self::External(d) => Some(d),
            _ => None,
        }
    }

    /// The simulated plant's period on the monotonic clock, in real time.
    pub fn period(&self) -> Option<Duration> {
        match self {
            Self::Realtime { period } => Some(*period),
            _ => None,
        }
    }

    /// How many times faster than real time a simulation of sampling time `ts` \[s\]
    /// runs at `period` (for display, and for the simulated seconds of a monotonic
    /// interval).
    pub fn speed(ts: f64, period: Duration) -> f64 {
        ts / period.as_secs_f64()
    }

    /// Checks the clock against experiment `cfg` and the processes' `waiting`: an
    /// injected delay is lockstep's (in real time the delays are real); predictive
    /// timing and the built-in simulations' checks need the simulated plant; polling
    /// without end needs lockstep (with an external driver, its own: checked once its
    /// info is read, [`Clock::check_driver_waiting`]).
    pub fn check(&self, cfg: &ExperimentConfig, waiting: Waiting) -> Result<Checked, ClockError> {
        if let Self::Realtime { period } = self
            && period.is_zero()
        {
            return Err(ClockError::ZeroPeriod);
        }
        let delayed = cfg.run().delay_ms != 0.0 || !cfg.run().delay_from.is_empty();
        if delayed && !self.is_lockstep() {
            return Err(ClockError::Delayed);
        }
        match self {
            Self::External(d) => {
                driver::contract::check_id(&d.id).map_err(ClockError::DriverId)?;
                if d.timeout.is_zero() || d.reset_timeout.is_zero() {
                    return Err(ClockError::ZeroTimeout);
                }
                if cfg.observer().mode == ::observer::config::ObserverMode::Predictive {
                    return Err(ClockError::Predictive);
                }
            }
            _ => cfg.check_simulated()?,
        }
        polls_only_in_lockstep(matches!(self, Self::Lockstep | Self::External(_)), waiting)?;
        Ok(Checked(()))
    }

    /// Checks the processes' `waiting` against the clock an external driver keeps
    /// (`info`): polling without end needs a driver in lockstep.
    pub fn check_driver_waiting(info: &DriverInfo, waiting: Waiting) -> Result<(), ClockError> {
        polls_only_in_lockstep(info.lockstep(), waiting)
    }

    /// The clock in words, for the recording's metadata: `ts` is the task's sampling
    /// time \[s\], `info` the external driver's.
    pub fn describe(&self, ts: f64, info: Option<&DriverInfo>) -> String {
        match (self, info) {
            (Self::Lockstep, _) => "lockstep".to_string(),
            (Self::Realtime { period }, _) => {
                let speed = (Self::speed(ts, *period) * 1e9).round() / 1e9;
                format!("realtime, speed {speed}")
            }
            (Self::External(d), Some(i)) => format!(
                "external driver {:?}: period {} ns, time scale {}",
                d.id, i.period_ns, i.time_scale
            ),
            (Self::External(d), None) => format!("external driver {:?}", d.id),
        }
    }
}

/// Refuses polling without end ([`Waiting::needs_wake_up`]) unless the clock is (or may
/// be) `lockstep`: in real time the plant sleeps until its next sample and must be woken.
fn polls_only_in_lockstep(lockstep: bool, waiting: Waiting) -> Result<(), ClockError> {
    if lockstep || waiting.needs_wake_up() {
        Ok(())
    } else {
        Err(ClockError::Unwoken)
    }
}

/// A duration in a settings file: a number of seconds in (0, 1e6] (exact to the
/// nanosecond both ways).
mod seconds {
    use std::time::Duration;

    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(d.as_secs_f64())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
        let s = f64::deserialize(d)?;
        if !(s.is_finite() && s > 0.0 && s <= 1e6) {
            return Err(D::Error::custom(format!(
                "{s} is not a number of seconds in (0, 1e6]"
            )));
        }
        Ok(Duration::from_secs_f64(s))
    }
}

#[cfg(test)]
mod tests;
