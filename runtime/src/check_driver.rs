//! `rig check-driver`: a conformance check against a running driver (`docs/driver.md`).
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

use std::time::{Duration, Instant};

use anyhow::{Result, anyhow};
use driver::contract::{
    DriverCommand, DriverInfo, DriverLink, DriverSample, kind, service, status,
};
use plant::angle::wrap;
use plant::{SystemName, Task};
use wire::{Bus, MAX_U, now_ns, type_name_of};

/// Periods of the step input.
const STEP_PERIODS: usize = 10;

/// What to check and the bounds.
#[derive(Clone, Debug)]
pub struct CheckOptions {
    /// The driver id.
    pub driver: String,
    /// The task the driver must fit.
    pub system: SystemName,
    /// How long to wait for the driver's info.
    pub timeout: Duration,
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
pub struct Outcome {
    /// What was checked.
    pub name: &'static str,
    /// Whether it passed.
    pub pass: bool,
    /// What was measured, and the bound.
    pub detail: String,
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let verdict = if self.pass { "PASS" } else { "FAIL" };
        write!(f, "{verdict}  {:<34} {}", self.name, self.detail)
    }
}

/// Runs the check against a running driver; `report` sees each outcome as soon as it is
/// known. An error means the check could not start: no driver, incompatible payloads, the
/// driver in use by another rig process.
pub fn check(opts: &CheckOptions, report: &mut dyn FnMut(&Outcome)) -> Result<Vec<Outcome>> {
    let bus = Bus::join(&format!("check-{}", std::process::id()), "check-driver")
        .map_err(|e| anyhow!("{e}"))?;
    let link = DriverLink::connect(&bus, &opts.driver).map_err(|e| anyhow!("{e}"))?;
    let info = link
        .wait_info(&bus, opts.timeout)
        .map_err(|e| anyhow!("{e}"))?;
    let task = Task::new(opts.system);
    let mut s = Probe {
        silence: (info.period() * 20).max(Duration::from_secs(1)),
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
    task: Task,
    silence: Duration,
    reset_id: u64,
    outcomes: Vec<Outcome>,
    report: &'r mut dyn FnMut(&Outcome),
    opts: CheckOptions,
    /// The largest change of the state over the step's horizon with zero input.
    drift: f64,
    /// When the last action of the step was sent (monotonic ns).
    t_last_action: u64,
}

/// `[a, b]` with four decimals.
fn vector(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.4}")).collect();
    format!("[{}]", parts.join(", "))
}

/// Each sample's lateness against a regular grid placed at the earliest sample, sorted
/// \[ns\]; `stamps` are `(seq, t_sample_ns)` in order, at least two. The grid's period is
/// the median of the sample-to-sample periods, so that one late sample is one outlier: the
/// mean from the first to the last sample would tilt the grid when either of those is the
/// late one (a first sample 12 ms late spread 0–12 ms of "lateness" over all the others).
fn lateness(stamps: &[(u64, u64)]) -> Vec<f64> {
    let grid = percentile(&intervals(stamps), 0.5);
    let (seq0, t0) = stamps[0];
    let offsets: Vec<f64> = stamps
        .iter()
        .map(|&(seq, t)| (t - t0) as f64 - (seq - seq0) as f64 * grid)
        .collect();
    let earliest = offsets.iter().copied().fold(f64::INFINITY, f64::min);
    let mut late: Vec<f64> = offsets.iter().map(|o| o - earliest).collect();
    late.sort_by(f64::total_cmp);
    late
}

/// The sample-to-sample intervals per period, sorted \[ns\]; `stamps` as for
/// [`lateness`].
fn intervals(stamps: &[(u64, u64)]) -> Vec<f64> {
    let mut steps: Vec<f64> = stamps
        .windows(2)
        .map(|w| (w[1].1 - w[0].1) as f64 / (w[1].0 - w[0].0) as f64)
        .collect();
    steps.sort_by(f64::total_cmp);
    steps
}

/// How far each interval is from the median interval, sorted \[ns\]: how irregular the
/// driver's clock is from one sample to the next. Lateness against a grid sums such
/// errors when a driver times each sample from the previous one rather than from its
/// start.
fn interval_jitter(stamps: &[(u64, u64)]) -> Vec<f64> {
    let steps = intervals(stamps);
    let median = percentile(&steps, 0.5);
    let mut off: Vec<f64> = steps.iter().map(|s| (s - median).abs()).collect();
    off.sort_by(f64::total_cmp);
    off
}

/// What a lateness p99 beyond `bound` says about the driver's clock, given the p99 of
/// its interval jitter (all in ns): either the period itself is irregular, or each
/// interval is fine and their errors accumulate.
fn clock_diagnosis(late_p99: f64, interval_p99: f64, bound: f64) -> Option<String> {
    if late_p99 <= bound {
        None
    } else if interval_p99 > bound {
        Some(format!(
            "the driver's clock is irregular: its intervals differ from the period by up to {:.3} ms (p99); sample on an absolute clock (docs/driver.md, \"Keeping time\")",
            interval_p99 * 1e-6
        ))
    } else {
        Some(format!(
            "the driver's clock drifts: each interval is within {:.3} ms (p99) of the period, but the instants stray from a regular grid, as when each sample is timed from the previous one; sample at t_start + k·period (docs/driver.md, \"Keeping time\")",
            interval_p99 * 1e-6
        ))
    }
}

/// Percentile `p` (0..=1) of sorted values.
fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
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
        let o = Outcome { name, pass, detail };
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

    /// The next sample, in order, well-formed (dimensions, finite values).
    fn sample(&self) -> Result<DriverSample> {
        let s = self
            .link
            .next_sample(&self.bus, self.silence)
            .map_err(|e| anyhow!("{e}"))?;
        s.validate(&self.info).map_err(|e| anyhow!("{e}"))?;
        Ok(s)
    }

    fn act(&self, u: &[f64], answering: &DriverSample) -> Result<u64> {
        self.link.act(u, answering.seq).map_err(|e| anyhow!("{e}"))
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
            .map(|()| driver::fits_task(&i, &self.task).err());
        let text = format!(
            "{}, n_x {}, n_u {}, Ts {:.3} ms (period {:.3} ms × time scale {}), u_min {}, u_max {}, watchdog {} period(s)",
            i.system_name(),
            i.n_x,
            i.n_u,
            i.ts() * 1e3,
            i.period_ns as f64 * 1e-6,
            i.time_scale,
            vector(&i.u_min[..(i.n_u as usize).min(MAX_U)]),
            vector(&i.u_max[..(i.n_u as usize).min(MAX_U)]),
            i.watchdog_periods
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

    fn run_phases(&mut self) {
        type Phase<'r> = (&'static str, fn(&mut Probe<'r>) -> Result<()>);
        let phases: [Phase<'_>; 6] = [
            ("reset", Probe::reset),
            ("sample rate", Probe::rate),
            ("step response", Probe::step),
            ("watchdog", Probe::watchdog),
            ("out-of-range actions", Probe::out_of_range),
            ("non-finite and malformed actions", Probe::non_finite),
        ];
        for (name, phase) in phases {
            if let Err(e) = phase(self) {
                self.record(name, false, format!("{e:#}"));
                return;
            }
        }
    }

    fn reset(&mut self) -> Result<()> {
        let x0 = self.task.initial_states[0].clone();
        let t0 = Instant::now();
        let id = self.link.reset(&x0).map_err(|e| anyhow!("{e}"))?;
        let s = self
            .link
            .wait_ready(&self.bus, &self.info, id, self.opts.reset_timeout)
            .map_err(|e| anyhow!("{e}"))?;
        self.reset_id = id;
        let off = self.change(&x0, s.state());
        self.record(
            "reset",
            off <= 0.05,
            format!(
                "READY after {:.2} s at x = {} (asked {}; off by {:.1} % of the state range, bound 5 %)",
                t0.elapsed().as_secs_f64(),
                vector(s.state()),
                vector(&x0),
                off * 100.0
            ),
        );
        Ok(())
    }

    /// Samples for `--rate-seconds`, each answered with zero.
    fn rate(&mut self) -> Result<()> {
        let zero = vec![0.0; self.n_u()];
        let t_end = Instant::now() + Duration::from_secs_f64(self.opts.rate_seconds);
        let mut samples: Vec<(DriverSample, u64)> = Vec::new();
        let mut problems: Vec<String> = Vec::new();
        while Instant::now() < t_end || samples.len() < STEP_PERIODS + 2 {
            let s = self.sample()?;
            let received = now_ns();
            if !s.has(status::READY) || s.reset_id != self.reset_id {
                problems.push(format!(
                    "sample {}: status {:#x}, reset_id {} (expected READY from {})",
                    s.seq, s.status, s.reset_id, self.reset_id
                ));
            }
            if s.t_sample_ns > received || received - s.t_sample_ns > 1_000_000_000 {
                problems.push(format!(
                    "sample {}: t_sample_ns {} is not this host's CLOCK_MONOTONIC (now {received})",
                    s.seq, s.t_sample_ns
                ));
            }
            if s.t_publish_ns < s.t_sample_ns {
                problems.push(format!("sample {}: published before it was sampled", s.seq));
            }
            if let Some((prev, _)) = samples.last()
                && s.seq <= prev.seq
            {
                problems.push(format!("sample seq {} after {}", s.seq, prev.seq));
            }
            if let Some((first, _)) = samples.first()
                && s.positions_only() != first.positions_only()
            {
                problems.push(format!(
                    "sample {}: measures {} after sample {} measured {}",
                    s.seq,
                    measures(&s),
                    first.seq,
                    measures(first)
                ));
            }
            let cmd = self.act(&zero, &s)?;
            samples.push((s, cmd));
            if problems.len() > 3 {
                break;
            }
        }
        problems.truncate(3);
        let (first, _) = &samples[0];
        let hint = if first.positions_only() {
            ", velocities NaN: run the rig with `--sensor angle` and an observer"
        } else {
            ""
        };
        let measured = format!("{}{hint}", measures(first));
        self.record_problems(
            "samples",
            problems,
            format!(
                "{} well-formed: READY, finite ({measured}), stamped on this host's monotonic clock, seq increasing",
                samples.len()
            ),
        );
        let period = self.period_ns();
        let (first, last) = (samples[0].0, samples[samples.len() - 1].0);
        let periods = (last.seq - first.seq) as f64;
        let mean = (last.t_sample_ns - first.t_sample_ns) as f64 / periods;
        let stamps: Vec<(u64, u64)> = samples
            .iter()
            .map(|(s, _)| (s.seq, s.t_sample_ns))
            .collect();
        let jitter = lateness(&stamps);
        let (p50, p99, max) = (
            percentile(&jitter, 0.5),
            percentile(&jitter, 0.99),
            jitter[jitter.len() - 1],
        );
        let interval_p99 = percentile(&interval_jitter(&stamps), 0.99);
        let bound = self.opts.max_jitter * period;
        let diagnosis =
            clock_diagnosis(p99, interval_p99, bound).map_or(String::new(), |d| format!(" — {d}"));
        let mut missed = 0;
        let mut acked = 0;
        for w in samples.windows(2) {
            let ((a, cmd), (b, _)) = (w[0], w[1]);
            missed += (b.seq - a.seq).saturating_sub(1);
            acked += usize::from(b.last_command == cmd);
        }
        let rate_ok = (mean - period).abs() <= 0.01 * period;
        let jitter_ok = p99 <= bound;
        let missed_ok = missed as f64 <= self.opts.max_missed * periods;
        let acked_ok = acked * 10 >= (samples.len() - 1) * 9;
        self.record(
            "sample rate",
            rate_ok && jitter_ok && missed_ok && acked_ok,
            format!(
                "{} samples: mean period {:.3} ms (advertised {:.3}, bound ±1 %); lateness against a regular grid p50 {:.3} ms, p99 {:.3} (bound {:.3}), max {:.3}; intervals off the period by p99 {:.3} ms; {missed} missed period(s) (bound {:.0} %); {acked} of {} actions applied by the next sample (bound 90 %){diagnosis}",
                samples.len(),
                mean * 1e-6,
                period * 1e-6,
                p50 * 1e-6,
                p99 * 1e-6,
                bound * 1e-6,
                max * 1e-6,
                interval_p99 * 1e-6,
                self.opts.max_missed * 100.0,
                samples.len() - 1,
            ),
        );
        // Zero input's drift over the step's horizon, for the step response to beat.
        let drift = samples
            .windows(STEP_PERIODS + 1)
            .map(|w| self.change(w[0].0.state(), w[STEP_PERIODS].0.state()))
            .fold(0.0, f64::max);
        self.drift = drift;
        Ok(())
    }

    /// A small step for [`STEP_PERIODS`] periods, from rest.
    fn step(&mut self) -> Result<()> {
        let u = self.action(self.opts.step);
        let s0 = self.sample()?;
        self.act(&u, &s0)?;
        let mut applied = 0;
        let mut s = s0;
        for _ in 0..STEP_PERIODS {
            s = self.sample()?;
            applied += usize::from(same(s.applied(), &u));
            self.act(&u, &s)?;
        }
        self.t_last_action = now_ns();
        let response = self.change(s0.state(), s.state());
        let bound = (5.0 * self.drift).max(1e-3);
        self.record(
            "step response",
            response > bound && applied == STEP_PERIODS,
            format!(
                "u = {} for {STEP_PERIODS} periods: x {} → {}, a change of {:.2} % of the state range (bound: > {:.2} %, five times zero input's); reported applied in {applied} of {STEP_PERIODS} samples",
                vector(&u),
                vector(s0.state()),
                vector(s.state()),
                response * 100.0,
                bound * 100.0
            ),
        );
        Ok(())
    }

    /// Actions stop after the step: zero and WATCHDOG within two periods.
    fn watchdog(&mut self) -> Result<()> {
        let period = self.period_ns();
        let t_a = self.t_last_action as f64;
        // The driver decides at sample instants; allow for its jitter.
        let due = t_a + 2.0 * period + (0.1 * period).max(1e6);
        let mut late: Vec<String> = Vec::new();
        let mut last_nonzero: Option<f64> = None;
        let mut first_zero: Option<f64> = None;
        let trips_before = self.sample()?.watchdog_trips;
        let trips_after = loop {
            let s = self.sample()?;
            let t = s.t_sample_ns as f64;
            let zero = s.applied().iter().all(|&u| u == 0.0);
            if zero {
                first_zero.get_or_insert(t);
            } else {
                last_nonzero = Some(t);
            }
            if t > due && !(zero && s.has(status::WATCHDOG)) && late.len() < 2 {
                late.push(format!(
                    "sample {} ({:.2} periods after the last action): u_applied {}, status {:#x}",
                    s.seq,
                    (t - t_a) / period,
                    vector(s.applied()),
                    s.status
                ));
            }
            if t > t_a + 5.0 * period {
                break s.watchdog_trips;
            }
        };
        let after =
            |t: Option<f64>| t.map_or("-".to_string(), |t| format!("{:.2}", (t - t_a) / period));
        let tripped = trips_after > trips_before;
        self.record(
            "watchdog",
            late.is_empty() && tripped,
            if late.is_empty() {
                format!(
                    "zero applied from between {} and {} periods after the last action (bound: by 2) with WATCHDOG; watchdog_trips {trips_before} → {trips_after} (must grow)",
                    after(last_nonzero.filter(|&t| first_zero.is_none_or(|z| t < z))),
                    after(first_zero)
                )
            } else {
                format!("still acting more than 2 periods after the last action: {}", late.join("; "))
            },
        );
        Ok(())
    }

    /// Sends `cmd` answering the next sample; returns that sample and the one after it.
    fn probe(&self, cmd: DriverCommand) -> Result<(DriverSample, DriverSample)> {
        let before = self.sample()?;
        self.link
            .send_raw(DriverCommand {
                sample_seq: before.seq,
                ..cmd
            })
            .map_err(|e| anyhow!("{e}"))?;
        Ok((before, self.sample()?))
    }

    fn action_command(&self, u: &[f64], n_u: usize) -> DriverCommand {
        let mut c = DriverCommand {
            kind: kind::ACTION,
            n_u: n_u as u64,
            ..Default::default()
        };
        c.u[..u.len()].copy_from_slice(u);
        c
    }

    /// Actions far above and below the limits: clamped, counted.
    fn out_of_range(&mut self) -> Result<()> {
        let n = self.n_u();
        let (lo, hi) = (&self.info.u_min[..n], &self.info.u_max[..n]);
        let span: Vec<f64> = (0..n).map(|j| hi[j] - lo[j]).collect();
        let above: Vec<f64> = (0..n).map(|j| hi[j] + 10.0 * span[j]).collect();
        let below: Vec<f64> = (0..n).map(|j| lo[j] - 10.0 * span[j]).collect();
        let mut wrong = Vec::new();
        for (u, want) in [(above, hi.to_vec()), (below, lo.to_vec())] {
            let (before, after) = self.probe(self.action_command(&u, n))?;
            let counted = after.clamped - before.clamped;
            if !same(after.applied(), &want) || counted != 1 {
                wrong.push(format!(
                    "u = {} applied as {} (want {}), clamped count +{counted} (want +1)",
                    vector(&u),
                    vector(after.applied()),
                    vector(&want)
                ));
            }
        }
        let ok = format!(
            "10 ranges above and below: applied as {} and {}, each counted as clamped",
            vector(hi),
            vector(lo)
        );
        self.record_problems("out-of-range actions", wrong, ok);
        Ok(())
    }

    /// NaN, ±inf and a wrong `n_u`, each after a valid action: rejected, zero applied.
    fn non_finite(&mut self) -> Result<()> {
        let n = self.n_u();
        let valid = self.action(0.5);
        let mut wrong = Vec::new();
        let cases = [
            ("NaN", f64::NAN, n),
            ("+inf", f64::INFINITY, n),
            ("-inf", f64::NEG_INFINITY, n),
            ("n_u = 0", valid[0], 0),
        ];
        for (label, value, n_u) in cases {
            let (_, armed) = self.probe(self.action_command(&valid, n))?;
            let mut u = valid.clone();
            u[0] = value;
            let (before, after) = self.probe(self.action_command(&u, n_u))?;
            let counted = after.rejected - before.rejected;
            let zero = after.applied().iter().all(|&x| x == 0.0);
            if !same(armed.applied(), &valid) || !zero || counted != 1 {
                wrong.push(format!(
                    "{label}: applied {} after {} (want zero after {}), rejected count +{counted} (want +1)",
                    vector(after.applied()),
                    vector(armed.applied()),
                    vector(&valid)
                ));
            }
        }
        self.record_problems(
            "non-finite and malformed actions",
            wrong,
            "NaN, +inf, -inf and n_u = 0, each after a valid action: zero applied, each counted as rejected".to_string(),
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 167 samples on a 30 ms grid, sample `late` delayed by 12 ms.
    fn grid_with_late(late: usize) -> Vec<(u64, u64)> {
        (0..167u64)
            .map(|k| {
                let delay = if k as usize == late { 12_000_000 } else { 0 };
                (k, 1_000_000_000 + k * 30_000_000 + delay)
            })
            .collect()
    }

    #[test]
    fn one_late_sample_is_one_outlier_wherever_it_is() {
        for late in [0, 80, 166] {
            let l = lateness(&grid_with_late(late));
            assert_eq!(l.len(), 167);
            assert!(percentile(&l, 0.99).abs() < 1.0, "late {late}: {l:?}");
            assert!((l[166] - 12e6).abs() < 1.0, "late {late}: max {}", l[166]);
        }
    }

    /// A clock that times each sample from the previous one, each wait off by ±2 ms: every
    /// interval is within 2 ms of the period, the lateness against the grid grows past it,
    /// and the diagnosis says the clock drifts; a clock whose intervals themselves exceed
    /// the bound is called irregular.
    #[test]
    fn an_accumulating_clock_is_told_from_an_irregular_one() {
        let mut t = 0u64;
        let stamps: Vec<(u64, u64)> = (0..200u64)
            .map(|k| {
                // A fixed pattern of ±2 ms errors whose sum wanders (no random source).
                let e = [2_000_000i64, 1_500_000, 1_000_000, -500_000, 2_000_000][k as usize % 5]
                    * if (k / 25) % 2 == 0 { 1 } else { -1 };
                t = (t as i64 + 30_000_000 + e) as u64;
                (k, t)
            })
            .collect();
        let late = percentile(&lateness(&stamps), 0.99);
        let steps = percentile(&interval_jitter(&stamps), 0.99);
        assert!(
            steps <= 2.5e6 && late > 10e6,
            "intervals {steps}, lateness {late}"
        );
        let d = clock_diagnosis(late, steps, 3e6).unwrap();
        assert!(d.contains("drifts") && d.contains("Keeping time"), "{d}");
        assert!(clock_diagnosis(late, steps, 2.0 * late).is_none());
        let d = clock_diagnosis(late, 5e6, 3e6).unwrap();
        assert!(d.contains("irregular"), "{d}");
    }

    #[test]
    fn lateness_follows_a_jittered_clock() {
        // Every third sample 2 ms late, a missed period at 50.
        let stamps: Vec<(u64, u64)> = (0..100u64)
            .filter(|&k| k != 50)
            .map(|k| (k, k * 30_000_000 + if k % 3 == 0 { 2_000_000 } else { 0 }))
            .collect();
        let l = lateness(&stamps);
        assert!(percentile(&l, 0.5).abs() < 1.0);
        assert!((percentile(&l, 0.99) - 2e6).abs() < 1.0);
    }
}
