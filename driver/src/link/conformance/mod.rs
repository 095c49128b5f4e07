//! The conformance check against a running driver (`docs/driver.md`): `rig check-driver`,
//! or a driver author's own tests ([`check`]).
//!
//! It connects as the rig would (so a driver with incompatible payloads is a one-line
//! error naming the service and both layouts), then, with real messages and the
//! driver's own clock:
//!
//! 1. *info* — protocol version, dimensions, sample time, limits, watchdog, against the
//!    task of `--system`;
//! 2. *reset* — RESET to the task's start state; READY within `--reset-timeout`, near it;
//! 3. *samples* — well-formed: READY, finite (or all velocities NaN in every sample: a
//!    driver measuring positions only), stamped on this host's monotonic clock;
//! 4. *sample rate* — for `--rate-seconds`, answering every sample with zero: the mean
//!    period, the jitter (p99 of each sample's lateness against a regular grid, against
//!    `--max-jitter`), missed periods
//!    (against `--max-missed`), and whether each action shows as applied in the next
//!    sample;
//! 5. *step response* — a small step for ten periods moves the state clearly more than
//!    ten periods of zero input did, and is reported as applied;
//! 6. *watchdog* — actions stop: the driver applies zero, with the WATCHDOG status, by
//!    two periods after the last action;
//! 7. *out-of-range actions* — clamped to the limits and counted;
//! 8. *non-finite and malformed actions* — NaN, ±inf and a wrong `n_u` rejected: zero
//!    applied, counted.
//!
//! A lockstep driver (`clock = lockstep`) has no clock to measure and no watchdog: in
//! place of 4 and 6 it is checked for one sample per action and none without
//! (*lockstep*), and for the same samples from the same reset and actions
//! (*determinism*); its step response is compared with zero input's from the same
//! reset.

use std::time::Duration;

use crate::Error;
use crate::contract::{DriverCommand, DriverInfo, DriverSample, service};
use crate::link::DriverLink;
use plant::Task;
use plant::angle::wrap;
use wire::{Bus, MAX_U, type_name_of};

mod clock;
mod lockstep;
mod phases;

/// Periods of the step input.
const STEP_PERIODS: usize = 10;

/// What to check and the bounds.
#[derive(Clone, Debug)]
pub struct CheckOptions {
    /// The driver id.
    pub driver: String,
    /// The task the driver must fit.
    pub task: std::sync::Arc<Task>,
    /// How long to wait for the driver's info (saying so after a second).
    pub timeout: Duration,
    /// How to start a driver of the task, for the error when none answers
    /// ([`crate::link::how_to_serve`]).
    pub serve: String,
    /// How long one reset may take.
    pub reset_timeout: Duration,
    /// How long to measure the sample rate \[s\].
    pub rate_seconds: f64,
    /// Largest p99 of the samples' lateness against a regular grid, as a fraction of
    /// the period.
    pub max_jitter: f64,
    /// Largest fraction of periods without a sample.
    pub max_missed: f64,
    /// Step size, as a fraction of the way from the middle of the action range to its
    /// upper limit.
    pub step: f64,
}

/// One line of the report.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckLine {
    /// What was checked.
    pub name: &'static str,
    /// Whether it passed.
    pub pass: bool,
    /// What was measured, and the bound.
    pub detail: String,
}

impl std::fmt::Display for CheckLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let verdict = if self.pass { "PASS" } else { "FAIL" };
        write!(f, "{verdict}  {:<34} {}", self.name, self.detail)
    }
}

/// Runs the check against a running driver; `report` sees each outcome as soon as it is
/// known. An error means the check could not start: no driver, incompatible payloads, the
/// driver in use by another rig process.
pub fn check(
    opts: &CheckOptions,
    report: &mut dyn FnMut(&CheckLine),
) -> Result<Vec<CheckLine>, Error> {
    let bus = Bus::join(&format!("check-{}", std::process::id()), "check-driver")?;
    let link = DriverLink::connect(&bus, &opts.driver)?;
    let info = link.wait_info(&bus, opts.timeout, true, &opts.serve)?;
    let task = opts.task.clone();
    let mut s = Probe {
        silence: info.silence_limit(opts.timeout),
        bus,
        link,
        info,
        task,
        reset_id: 0,
        outcomes: Vec::new(),
        report,
        opts: opts.clone(),
        drift: 0.0,
        t_last_action: 0,
        last_action: 0,
        pending: None,
    };
    s.record(
        "payload types",
        true,
        format!(
            "{} ({} B), {} ({} B), {} ({} B) on {}",
            type_name_of::<DriverInfo>(),
            size_of::<DriverInfo>(),
            type_name_of::<DriverSample>(),
            size_of::<DriverSample>(),
            type_name_of::<DriverCommand>(),
            size_of::<DriverCommand>(),
            service(&opts.driver, "{info,sample,command}")
        ),
    );
    if s.info_check() {
        s.run_phases();
    }
    Ok(s.outcomes)
}

/// One check of a driver: the connection, what the driver advertised, and the outcomes
/// so far.
struct Probe<'r> {
    bus: Bus,
    link: DriverLink,
    info: DriverInfo,
    task: std::sync::Arc<Task>,
    silence: Duration,
    reset_id: u64,
    outcomes: Vec<CheckLine>,
    report: &'r mut dyn FnMut(&CheckLine),
    opts: CheckOptions,
    /// The largest change of the state over the step's horizon with zero input.
    drift: f64,
    /// When the last action of the step was sent (monotonic ns), and its `seq`.
    t_last_action: u64,
    last_action: u64,
    /// A lockstep driver's newest sample, read but not answered yet: it publishes no
    /// other until it is.
    pending: Option<DriverSample>,
}

/// `[a, b]` with four decimals.
fn vector(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.4}")).collect();
    format!("[{}]", parts.join(", "))
}

/// What a sample measures, in words.
fn measures(s: &DriverSample) -> &'static str {
    if s.positions_only() {
        "positions only"
    } else {
        "the full state"
    }
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-9 * (1.0 + y.abs()))
}

impl Probe<'_> {
    fn record(&mut self, name: &'static str, pass: bool, detail: String) {
        let o = CheckLine { name, pass, detail };
        (self.report)(&o);
        self.outcomes.push(o);
    }

    /// Records a check that passes when `problems` is empty (then saying `ok`).
    fn record_problems(&mut self, name: &'static str, problems: Vec<String>, ok: String) {
        let pass = problems.is_empty();
        self.record(name, pass, if pass { ok } else { problems.join("; ") });
    }

    fn period_ns(&self) -> f64 {
        self.info.period_ns as f64
    }

    fn n_u(&self) -> usize {
        self.info.n_u as usize
    }

    /// The next sample, in order, well-formed (dimensions, finite values): a lockstep
    /// driver's sample left pending by the last phase, else the next to arrive.
    fn sample(&mut self) -> Result<DriverSample, Error> {
        if let Some(s) = self.pending.take() {
            return Ok(s);
        }
        let s = self.link.next_sample(&self.bus, self.silence)?;
        s.validate(&self.info).map_err(|error| Error::Sample {
            id: self.opts.driver.clone(),
            error,
        })?;
        Ok(s)
    }

    fn act(&self, u: &[f64], answering: &DriverSample) -> Result<u64, Error> {
        self.link.act(u, answering.seq)
    }

    /// The task's action `fraction` of the way from the middle of the range to the upper
    /// limit.
    fn action(&self, fraction: f64) -> Vec<f64> {
        (0..self.n_u())
            .map(|j| {
                let (lo, hi) = (self.info.u_min[j], self.info.u_max[j]);
                let mid = 0.5 * (lo + hi);
                mid + fraction * (hi - mid)
            })
            .collect()
    }

    /// The largest change between two states (unmeasured components, NaN, ignored), each component relative to the width of
    /// the task's state range (angles wrapped).
    fn change(&self, a: &[f64], b: &[f64]) -> f64 {
        (0..a.len())
            .map(|i| {
                let d = b[i] - a[i];
                let d = if self.task.angle_mask[i] { wrap(d) } else { d };
                let (lo, hi) = self.task.state_range[i];
                d.abs() / (hi - lo)
            })
            .filter(|c| !c.is_nan())
            .fold(0.0, f64::max)
    }

    fn info_check(&mut self) -> bool {
        let i = self.info;
        let fits = i
            .validate()
            .map(|()| crate::link::fits_task(&i, &self.task).err());
        let text = format!(
            "task {} (hash {:016x}), {} clock, n_x {}, n_u {}, Ts {:.3} ms (period {:.3} ms × time scale {}), u_min {}, u_max {}, watchdog {} period(s), reward {}",
            i.task_name(),
            i.task_hash,
            if i.lockstep() { "lockstep" } else { "realtime" },
            i.n_x,
            i.n_u,
            i.ts() * 1e3,
            i.period_ns as f64 * 1e-6,
            i.time_scale,
            vector(&i.u_min[..(i.n_u as usize).min(MAX_U)]),
            vector(&i.u_max[..(i.n_u as usize).min(MAX_U)]),
            i.watchdog_periods,
            if i.provides_reward() {
                "and endings from the driver"
            } else {
                "computed by the rig"
            }
        );
        match fits {
            Err(e) => {
                self.record(
                    "info",
                    false,
                    format!("{e}; the other checks need a valid info"),
                );
                false
            }
            Ok(Some(e)) => {
                self.record("info", false, format!("{text}: does not fit the task: {e}"));
                true
            }
            Ok(None) => {
                self.record("info", true, text);
                true
            }
        }
    }
}
