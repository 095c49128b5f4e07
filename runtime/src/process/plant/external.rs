//! The plant process with an external driver (`[clock.external]` in its settings,
//! written by `rig run --plant external`; the contract is `docs/driver.md`).
//!
//! The driver samples, applies actions and resets; it knows nothing of trials. This
//! process is the episode master between it and the observer and agent: before each
//! trial it asks the driver to reset and waits until the driver reports READY; it turns
//! each driver sample into a [`wire::Measurement`] (header, reward `ρ(x_k, u)` with the
//! action the driver reports in effect over the period) and forwards each of the agent's
//! actions to the driver at once. A driver that measures positions only (NaN velocities,
//! `docs/driver.md`) needs `--sensor angle`: its measurements carry NaN rewards and
//! [`flags::ESTIMATED_REWARD`], and the observer computes `ρ(x̂_k, u_k)` from its
//! estimate; its start samples take the velocities of `x0` (READY is at rest there).
//!
//! A driver that provides the reward (`provides::REWARD` in its info) gives each period's
//! reward and the trial's ending with the sample that closes it: the measurement carries
//! that reward and [`flags::DRIVER_REWARD`]; *terminated* ends the trial at a terminal
//! state (`END | TERMINAL`: nothing is bootstrapped past it), *truncated* ends it as the
//! task's time limit does (`END`: the learners bootstrap through it).
//!
//! The driver is the clock. When the agent answers late — the driver's next sample shows
//! that the action was not applied by then — the trial goes on and the miss is counted
//! in [`wire::Measurement::deadline_misses`]. When the loop loses the driver's timing —
//! samples missing before the newest (whole periods passed, also counted as misses), a
//! sample whose instant comes more than 1.5 periods after the previous one's (the
//! driver's clock slipped), or a sample reaching this process more than a period after
//! its instant (a network that held it back) — that sample is a gap ([`flags::GAP`]): the attempt ends there, cut
//! short, without the transition into it, and the trial is run again ([`super::Ended`]).

use std::time::Duration;

use crate::process::{NodeError, Result};
use ::plant::episode::{Step, TimeLimit};
use ::plant::safety::{SafetyCounts, SafetyLayer};
use ::plant::schedule::Trial;
use driver::contract::{DriverInfo, DriverSample, status};
use driver::link::DriverLink;
use wire::flags;

use super::super::{PlantSettings, SILENCE, STARTUP};
use super::link::{Link, TrialHeader, end_flags};
use super::{Ended, Gap, Trials};
use crate::clock::ExternalDriver;

/// The episode master for an external driver.
pub struct ExternalPlant {
    link: Link,
    driver: DriverLink,
    info: DriverInfo,
    reset_timeout: Duration,
    /// How long the driver may be silent (it publishes every period, also while it
    /// resets).
    silence: Duration,
    /// The rig's side of safety: actions are clamped (non-finite ones never reach the
    /// driver) and the operating range is watched here too; the driver does its own.
    safety: SafetyLayer,
    /// Whether the driver measures positions only (NaN velocities), as its first sample
    /// of the run showed.
    positions_only: Option<bool>,
    /// The samples of the trial.
    limit: TimeLimit,
    /// Whether a gap cuts the attempt short (`learn_across_gaps` not set).
    cut_gaps: bool,
}

impl ExternalPlant {
    /// Connects to driver `d`: waits for its info (its `timeout`), checks it against the
    /// task, then waits for the observer (and recorder) to listen.
    pub(super) fn connect(
        mut link: Link,
        d: &ExternalDriver,
        args: &PlantSettings,
    ) -> Result<Self> {
        let driver_id = d.id.as_str();
        let driver = DriverLink::connect(&link.bus, driver_id)?;
        let timeout = d.timeout;
        let serve = driver::link::how_to_serve(&link.task, driver_id, None);
        let info = driver.wait_info(&link.bus, timeout, false, &serve)?;
        driver::link::check_info(driver_id, &info, &link.task)?;
        link.out
            .wait_for_receivers(args.node.receivers, STARTUP, &link.bus)?;
        if info.provides_reward() {
            link.run_flags |= flags::DRIVER_REWARD;
        }
        Ok(Self {
            safety: SafetyLayer::new(&link.task),
            limit: TimeLimit::new(link.task.steps_per_trial()),
            silence: info.silence_limit(d.timeout),
            reset_timeout: d.reset_timeout,
            link,
            driver,
            info,
            positions_only: None,
            cut_gaps: true,
        })
    }

    /// Whether a gap cuts the attempt short (the default) or the trial learns across it.
    pub(super) fn cutting_gaps(mut self, cut: bool) -> Self {
        self.cut_gaps = cut;
        self
    }

    /// Whether sample `s` has the positions only. The first sample of the run decides
    /// (positions only: the rewards become the observer's, [`Link::estimate_rewards`]);
    /// a driver that changes what it measures is an error.
    fn positions_only(&mut self, s: &DriverSample) -> Result<bool> {
        let now = s.positions_only();
        match self.positions_only {
            None if now => self.link.estimate_rewards(&self.driver.id)?,
            Some(before) if before != now => {
                return Err(NodeError::MeasuresChanged {
                    driver: self.driver.id.clone(),
                    seq: s.seq,
                    before,
                    now,
                });
            }
            _ => {}
        }
        self.positions_only = Some(now);
        Ok(now)
    }

    /// The newest driver sample after sample `after`, checked: right dimensions, finite,
    /// still READY from reset `reset_id`.
    fn next_sample(&mut self, after: u64, reset_id: u64) -> Result<DriverSample> {
        loop {
            let mut s = self.driver.next_sample(&self.link.bus, self.silence)?;
            if let Some(newer) = self.driver.latest_sample()? {
                s = newer;
            }
            s.validate(&self.info).map_err(|why| NodeError::Sample {
                driver: self.driver.id.clone(),
                why,
            })?;
            self.positions_only(&s)?;
            if !s.has(status::READY) || s.reset_id != reset_id {
                return Err(NodeError::LeftTrial {
                    driver: self.driver.id.clone(),
                    seq: s.seq,
                    status: s.status,
                    reset_id: s.reset_id,
                    expected: reset_id,
                });
            }
            if s.seq > after {
                return Ok(s);
            }
        }
    }

    /// Waits for the agent's answer to the sample just published (sequence number
    /// `seq`, published at `t_publish_ns`).
    fn action(&mut self, seq: u64, t_publish_ns: u64) -> Result<Vec<f64>> {
        let l = &mut self.link;
        let a = l.actions.recv(&l.bus, SILENCE)?;
        l.t_action_ns = l.time.now_ns();
        l.latencies.push(l.t_action_ns - t_publish_ns);
        Link::check_answer(&a, seq)?;
        Ok(a.u[..l.task.action_dim()].to_vec())
    }
}

impl ExternalPlant {
    /// Resets the driver to `x0` and publishes the start sample (`header`) when it is
    /// READY there. Returns the READY sample, the reset's id and when the start sample
    /// was published.
    fn start(&mut self, x0: &[f64], header: &TrialHeader) -> Result<(DriverSample, u64, u64)> {
        let reset_id = self.driver.reset(x0)?;
        let s = self
            .driver
            .wait_ready(&self.link.bus, &self.info, reset_id, self.reset_timeout)?;
        // READY means at rest at x0: a driver that does not measure the velocities has
        // brought them to x0's.
        let mut start = s.state().to_vec();
        if self.positions_only(&s)? {
            let half = start.len() / 2;
            start[half..].copy_from_slice(&x0[half..]);
        }
        let t_publish = self.link.publish(
            header.at(self.link.seq, 0, flags::START),
            0.0,
            &start,
            s.applied(),
            s.t_sample_ns,
        )?;
        Ok((s, reset_id, t_publish))
    }

    /// The gap before `next`, the sample after `s` that reached this process at
    /// `arrived`, if gaps cut trials ([`gap_between`]).
    fn gap(&self, s: &DriverSample, next: &DriverSample, arrived: u64) -> Option<Gap> {
        let clocked = !self.info.lockstep();
        let gap = gap_between(s, next, arrived, self.info.period_ns, clocked);
        gap.filter(|_| self.cut_gaps)
    }

    /// One period after driver sample `s` (of reset `reset_id`), published at
    /// `t_publish`: the agent's answer, made safe into `u`, goes to the driver; returns
    /// the driver's next sample, what the period came to, and whether a gap came first.
    fn period(
        &mut self,
        s: &DriverSample,
        t_publish: u64,
        reset_id: u64,
        u: &mut [f64],
    ) -> Result<(DriverSample, Step, Option<Gap>)> {
        let requested = self.action(self.link.seq - 1, t_publish)?;
        self.safety.admit(&requested, u);
        let command = self.driver.act(u, s.seq)?;
        let next = self.next_sample(s.seq, reset_id)?;
        let gap = self.gap(s, &next, self.link.time.now_ns());
        // Periods that passed without a measurement, and an action the driver had not
        // applied by the next sample, are missed deadlines.
        self.link.misses += next.seq - s.seq - 1 + u64::from(next.last_command != command);
        // Leaving the task's operating range ends the trial with its penalty (§6.4.2); no
        // further action is sent, so the driver's watchdog applies zero.
        let left = self.safety.check(next.measured());
        let step = if self.info.provides_reward() {
            self.driver_step(&next, left)
        } else {
            // ρ(x_k, u): unknown here if the velocities are not measured (the observer
            // computes it from its estimate, flags::ESTIMATED_REWARD).
            let reward = if self.positions_only == Some(true) {
                f64::NAN
            } else {
                self.link.task.reward.reward(s.state(), next.applied())
            };
            self.limit.step(left.unwrap_or(reward), left.is_some())
        };
        Ok((next, step, gap))
    }

    /// The period closed by `next` of a driver that provides the reward: its reward
    /// and ending — terminated (or out of the operating range, `left`: its penalty) at a
    /// terminal state; truncated by the driver or by the task's time limit.
    fn driver_step(&mut self, next: &DriverSample, left: Option<f64>) -> Step {
        let mut step = self.limit.step(
            left.unwrap_or(next.reward),
            left.is_some() || next.terminated(),
        );
        step.truncated |= next.truncated() && !step.terminated;
        step
    }
}

impl Trials for ExternalPlant {
    fn trial(&mut self, trial: &Trial) -> Result<Ended> {
        let header = TrialHeader::new(trial, self.link.task.ts);
        let (mut s, reset_id, mut t_publish) = self.start(&trial.x0, &header)?;
        self.limit.reset();
        let mut u = vec![0.0; self.link.task.action_dim()];
        loop {
            let (next, step, gap) = self.period(&s, t_publish, reset_id, &mut u)?;
            // After a gap the sample only ends the attempt: no reward, nothing learned.
            let (marks, reward) = match gap {
                Some(_) => (flags::END | flags::GAP, 0.0),
                None => (end_flags(&step), step.reward),
            };
            t_publish = self.link.publish(
                header.at(self.link.seq, step.sample, marks),
                reward,
                next.state(),
                next.applied(),
                next.t_sample_ns,
            )?;
            s = next;
            if marks & flags::END != 0 {
                // The END sample's answer only acknowledges learning: nothing to apply
                // (the next trial's reset follows, and the driver's watchdog stops the
                // last action).
                self.action(self.link.seq - 1, t_publish)?;
                return Ok(match gap {
                    Some(g) => g.cut(trial, step.sample),
                    None => Ended::Done(self.limit.skipped()),
                });
            }
        }
    }

    fn link(&mut self) -> &mut Link {
        &mut self.link
    }

    fn safety(&mut self) -> SafetyCounts {
        self.safety.counts()
    }
}

/// Whether `next`, the sample after `s`, reached this process at `arrived` (monotonic ns)
/// after a gap: samples missing between them, or — for a driver on its own clock
/// (`clocked`) of period `period_ns` — its instant more than 1.5 periods after the
/// previous one's (the driver's clock slipped) or it more than a period after its instant
/// (a lockstep driver has no instants to keep).
fn gap_between(
    s: &DriverSample,
    next: &DriverSample,
    arrived: u64,
    period_ns: u64,
    clocked: bool,
) -> Option<Gap> {
    let gap = Gap {
        missing: next.seq - s.seq - 1,
        span_ns: next.t_sample_ns.saturating_sub(s.t_sample_ns),
        late_ns: arrived.saturating_sub(next.t_sample_ns),
        unanswered: false,
    };
    let slipped = clocked && (gap.span_ns > period_ns * 3 / 2 || gap.late_ns > period_ns);
    (gap.missing > 0 || slipped).then_some(gap)
}

#[cfg(test)]
mod tests {
    use super::*;

    use wire::MS;

    fn sample(seq: u64, t_ms: u64) -> DriverSample {
        DriverSample {
            seq,
            t_sample_ns: t_ms * MS,
            ..DriverSample::default()
        }
    }

    /// A driver's samples on the time line of their stamps, in milliseconds: the gap rule
    /// at its edges, for a clocked driver of period 10 ms and for a lockstep one.
    #[test]
    fn a_gap_is_a_missing_sample_a_slipped_instant_or_a_late_arrival() {
        let (s, period) = (sample(7, 100), 10 * MS);
        let clocked = |next: DriverSample, arrived_ms: u64| {
            gap_between(&s, &next, arrived_ms * MS, period, true)
        };
        // On time, and up to 1.5 periods apart and a period late: no gap.
        assert_eq!(clocked(sample(8, 110), 111), None);
        assert_eq!(clocked(sample(8, 115), 125), None);
        // A sample missing.
        let missing = clocked(sample(9, 120), 121).expect("a missing sample is a gap");
        assert_eq!((missing.missing, missing.span_ns), (1, 20 * MS));
        // The instant slipped past 1.5 periods; the sample a period late and a bit.
        assert!(clocked(sample(8, 116), 117).is_some());
        let late = clocked(sample(8, 110), 121).expect("arriving over a period late is a gap");
        assert_eq!(late.late_ns, 11 * MS);
        // In lockstep only missing samples count: instants and arrivals are not kept.
        let lockstep = |next: DriverSample, arrived_ms: u64| {
            gap_between(&s, &next, arrived_ms * MS, period, false)
        };
        assert_eq!(lockstep(sample(8, 500), 900), None);
        assert!(lockstep(sample(9, 110), 110).is_some());
    }
}
