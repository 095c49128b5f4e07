//! The phases of the check after the info: reset, sample rate, step response,
//! watchdog, out-of-range and non-finite actions.

use std::time::Duration;

use crate::Error;
use crate::contract::{DriverCommand, DriverSample, kind, status};

use super::clock::{clock_diagnosis, interval_jitter, lateness, percentile};
use super::{Probe, STEP_PERIODS, measures, same, vector};

/// How many periods a real-time driver's sample may take to show a probe's command.
const TAKEN_PERIODS: usize = 50;

/// What the step's samples show as applied. A sample whose own action (the one answering
/// the sample before it) the driver has taken must show the step; one whose action came
/// late may still show the step before it, or zero (the watchdog's, or the rest before
/// the step): lateness is the sample-rate check's to judge.
#[derive(Default)]
struct StepShown {
    /// Samples showing the step.
    applied: usize,
    /// Samples taken before their action arrived.
    late: usize,
    /// Samples showing anything else, and what.
    wrong: Vec<String>,
}

impl StepShown {
    /// Sample `s`, whose action is command `sent`; the step is `u`.
    fn add(&mut self, s: &DriverSample, sent: u64, u: &[f64]) {
        let taken = s.last_command >= sent;
        if same(s.applied(), u) {
            self.applied += 1;
        } else if !taken && applies_zero(s) {
            self.late += 1;
        } else {
            let what = format!("sample {}: {}", s.seq, vector(s.applied()));
            self.wrong.push(what);
        }
    }

    fn ok(&self) -> bool {
        self.applied > 0 && self.wrong.is_empty()
    }

    fn describe(&self) -> String {
        let mut text = format!(
            "reported applied in {} of {STEP_PERIODS} samples",
            self.applied
        );
        if self.late > 0 {
            text += &format!(", {} taken before their action arrived (late)", self.late);
        }
        if !self.wrong.is_empty() {
            text += &format!(", other actions shown: {}", self.wrong.join("; "));
        }
        text
    }
}

/// The sample shows zero applied: the safe action.
fn applies_zero(s: &DriverSample) -> bool {
    s.applied().iter().all(|&u| u == 0.0)
}

/// The sample shows the action `seq` applied (clamped or not).
fn applied(_: &DriverSample, s: &DriverSample, seq: u64) -> bool {
    s.last_command >= seq
}

/// The sample shows one more command rejected than `before`.
fn rejected(before: &DriverSample, s: &DriverSample, _: u64) -> bool {
    s.rejected > before.rejected
}

impl Probe<'_> {
    /// The phases in order; the first that cannot go on ends the check.
    pub(super) fn run_phases(&mut self) {
        type Phase<'r> = (&'static str, fn(&mut Probe<'r>) -> Result<(), Error>);
        let realtime: [Phase<'_>; 6] = [
            ("reset", Probe::reset),
            ("sample rate", Probe::rate),
            ("step response", Probe::step),
            ("watchdog", Probe::watchdog),
            ("out-of-range actions", Probe::out_of_range),
            ("non-finite and malformed actions", Probe::non_finite),
        ];
        let lockstep: [Phase<'_>; 6] = [
            ("reset", Probe::reset),
            ("lockstep", Probe::lockstep),
            ("step response", Probe::step_against_zero),
            ("determinism", Probe::determinism),
            ("out-of-range actions", Probe::out_of_range),
            ("non-finite and malformed actions", Probe::non_finite),
        ];
        let phases = if self.info.lockstep() {
            lockstep
        } else {
            realtime
        };
        for (name, phase) in phases {
            if let Err(e) = phase(self) {
                self.record(name, false, format!("{e:#}"));
                return;
            }
        }
    }

    fn reset(&mut self) -> Result<(), Error> {
        let x0 = self.task.initial_states[0].clone();
        let t0 = self.link.now_ns();
        let id = self.link.reset(&x0)?;
        let s = self
            .link
            .wait_ready(&self.bus, &self.info, id, self.opts.reset_timeout)?;
        self.reset_id = id;
        if self.info.lockstep() {
            // It publishes nothing more until this sample is answered.
            self.pending = Some(s);
        }
        let off = self.change(&x0, s.state());
        self.record(
            "reset",
            off <= 0.05,
            format!(
                "READY after {:.2} s at x = {} (asked {}; off by {:.1} % of the state range, bound 5 %)",
                (self.link.now_ns() - t0) as f64 * 1e-9,
                vector(s.state()),
                vector(&x0),
                off * 100.0
            ),
        );
        Ok(())
    }

    /// Samples for `--rate-seconds`, each answered with zero: well-formed, at the
    /// advertised rate, each action applied by the next sample.
    fn rate(&mut self) -> Result<(), Error> {
        let samples = self.zero_input_samples()?;
        self.record_rate(&samples);
        // Zero input's drift over the step's horizon, for the step response to beat.
        self.drift = samples
            .windows(STEP_PERIODS + 1)
            .map(|w| self.change(w[0].0.state(), w[STEP_PERIODS].0.state()))
            .fold(0.0, f64::max);
        Ok(())
    }

    /// Samples for `--rate-seconds` (at least enough for the step's horizon), each
    /// answered with zero, with the time that answer was sent; records whether they are
    /// well-formed.
    pub(super) fn zero_input_samples(&mut self) -> Result<Vec<(DriverSample, u64)>, Error> {
        let zero = vec![0.0; self.n_u()];
        // A lockstep driver has no rate to measure: enough samples for the step's horizon.
        let seconds = if self.info.lockstep() {
            0.0
        } else {
            self.opts.rate_seconds
        };
        let t_end = self.link.now_ns() + Duration::from_secs_f64(seconds).as_nanos() as u64;
        let mut samples: Vec<(DriverSample, u64)> = Vec::new();
        let mut problems: Vec<String> = Vec::new();
        while self.link.now_ns() < t_end || samples.len() < STEP_PERIODS + 2 {
            let s = self.sample()?;
            let received = self.link.now_ns();
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
        Ok(samples)
    }

    /// Records the rate the driver kept over `samples`: mean period, lateness, missed
    /// periods, actions applied by the next sample.
    fn record_rate(&mut self, samples: &[(DriverSample, u64)]) {
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
    }

    /// A small step for [`STEP_PERIODS`] periods, from rest.
    fn step(&mut self) -> Result<(), Error> {
        let u = self.action(self.opts.step);
        let s0 = self.sample()?;
        let mut sent = self.act(&u, &s0)?;
        let mut shown = StepShown::default();
        let mut s = s0;
        for _ in 0..STEP_PERIODS {
            s = self.sample()?;
            shown.add(&s, sent, &u);
            sent = self.act(&u, &s)?;
        }
        self.t_last_action = self.link.now_ns();
        self.last_action = sent;
        let response = self.change(s0.state(), s.state());
        let bound = (5.0 * self.drift).max(1e-3);
        self.record(
            "step response",
            response > bound && shown.ok(),
            format!(
                "u = {} for {STEP_PERIODS} periods: x {} → {}, a change of {:.2} % of the state range (bound: > {:.2} %, five times zero input's); {}",
                vector(&u),
                vector(s0.state()),
                vector(s.state()),
                response * 100.0,
                bound * 100.0,
                shown.describe()
            ),
        );
        Ok(())
    }

    /// Actions stop after the step: zero and WATCHDOG within two periods.
    fn watchdog(&mut self) -> Result<(), Error> {
        let period = self.period_ns();
        let t_a = self.t_last_action as f64;
        // The driver decides at sample instants; allow for its jitter.
        let tolerance = (0.1 * period).max(1e6);
        let mut due = t_a + 2.0 * period + tolerance;
        // The sample that first shows the last action taken: one that arrived late (a
        // loaded host, a link) starts the driver's two periods later.
        let mut taken = false;
        let mut taken_late: Option<f64> = None;
        let mut late: Vec<String> = Vec::new();
        let mut last_nonzero: Option<f64> = None;
        let mut first_zero: Option<f64> = None;
        let first = self.sample()?;
        let trips_before = first.watchdog_trips;
        let mut next = Some(first);
        let trips_after = loop {
            let s = match next.take() {
                Some(s) => s,
                None => self.sample()?,
            };
            let t = s.t_sample_ns as f64;
            if !taken && s.last_command >= self.last_action {
                taken = true;
                if t - period > t_a {
                    taken_late = Some((t - period - t_a) / period);
                    due = t + period + tolerance;
                }
            }
            let zero = applies_zero(&s);
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
            if t > due + 3.0 * period {
                break s.watchdog_trips;
            }
        };
        let after =
            |t: Option<f64>| t.map_or("-".to_string(), |t| format!("{:.2}", (t - t_a) / period));
        let arrived = taken_late.map_or(String::new(), |p| {
            format!(" (it arrived late: taken at least {p:.2} periods after it was sent)")
        });
        let tripped = trips_after > trips_before;
        self.record(
            "watchdog",
            late.is_empty() && tripped,
            if late.is_empty() {
                format!(
                    "zero applied from between {} and {} periods after the last action{arrived} (bound: by 2 after it was taken) with WATCHDOG; watchdog_trips {trips_before} → {trips_after} (must grow)",
                    after(last_nonzero.filter(|&t| first_zero.is_none_or(|z| t < z))),
                    after(first_zero)
                )
            } else {
                format!("still acting more than 2 periods after the last action{arrived}: {}", late.join("; "))
            },
        );
        Ok(())
    }

    /// Sends `cmd` answering the next sample; returns that sample and the sample that
    /// shows the command taken. A lockstep driver's next sample answers it (and the next
    /// probe answers that one). A real-time driver's command may arrive a period late or
    /// more (a loaded host, a network link): the samples are read until `taken(before,
    /// sample, seq)` holds, for at most [`TAKEN_PERIODS`] periods. Timing is the
    /// sample-rate check's business; these checks are about what the driver does with a
    /// command once it has it.
    fn probe(
        &mut self,
        cmd: DriverCommand,
        taken: fn(&DriverSample, &DriverSample, u64) -> bool,
    ) -> Result<(DriverSample, DriverSample), Error> {
        let before = self.sample()?;
        let seq = self.link.send_raw(DriverCommand {
            sample_seq: before.seq,
            ..cmd
        })?;
        let mut after = self.sample()?;
        if self.info.lockstep() {
            // The next probe answers it.
            self.pending = Some(after);
            return Ok((before, after));
        }
        for _ in 1..TAKEN_PERIODS {
            if taken(&before, &after, seq) {
                break;
            }
            after = self.sample()?;
        }
        Ok((before, after))
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
    fn out_of_range(&mut self) -> Result<(), Error> {
        let n = self.n_u();
        let (lo, hi) = (self.info.u_min[..n].to_vec(), self.info.u_max[..n].to_vec());
        let span: Vec<f64> = (0..n).map(|j| hi[j] - lo[j]).collect();
        let above: Vec<f64> = (0..n).map(|j| hi[j] + 10.0 * span[j]).collect();
        let below: Vec<f64> = (0..n).map(|j| lo[j] - 10.0 * span[j]).collect();
        let mut wrong = Vec::new();
        for (u, want) in [(above, hi.clone()), (below, lo.clone())] {
            let (before, after) = self.probe(self.action_command(&u, n), applied)?;
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
            vector(&hi),
            vector(&lo)
        );
        self.record_problems("out-of-range actions", wrong, ok);
        Ok(())
    }

    /// NaN, ±inf and a wrong `n_u`, each after a valid action: rejected, zero applied.
    fn non_finite(&mut self) -> Result<(), Error> {
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
            let (_, armed) = self.probe(self.action_command(&valid, n), applied)?;
            let mut u = valid.clone();
            u[0] = value;
            let (before, after) = self.probe(self.action_command(&u, n_u), rejected)?;
            let counted = after.rejected - before.rejected;
            let zero = applies_zero(&after);
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
