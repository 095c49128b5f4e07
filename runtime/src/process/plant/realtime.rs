//! The simulated plant in real time: it samples at absolute deadlines of `Ts / speed` on
//! the monotonic clock, whether the agent has answered or not.
//!
//! In direct timing every action that arrives within an interval is applied from its
//! arrival on (the previous one held until then); in predictive timing the last action
//! that arrived within an interval is applied at the next sample instant, for the whole
//! next interval (none arrived: the previous one is held). An interval in which the
//! action for its sample did not arrive is a missed deadline. The reward of an interval
//! is `ρ(x_k, u)` with the action in effect at its end. An interval without any action
//! trips the plant's watchdog ([`plant::safety::SafetyLayer::period`]): zero from its end
//! on, until an action arrives. A late answer to the previous trial's last sample is
//! dropped, not applied in this one. Nothing is allocated per interval.
//!
//! A sample the plant takes more than a period after its instant (the process was held
//! up: the agent can no longer answer it in its interval), or one at which the sample
//! before the last is still unanswered (its action more than a period past its deadline:
//! what a driver's watchdog allows), is a gap ([`flags::GAP`]): the attempt ends there,
//! cut short, and the trial is run again, from a fresh instant.

use std::time::Duration;

use crate::process::Result;
use ::plant::Plant;
use ::plant::episode::{Episode, Step};
use ::plant::safety::SafetyCounts;
use ::plant::schedule::Trial;
use wire::{Header, MAX_U, Monotonic, flags};

use super::super::SILENCE;
use super::arrivals::Arrivals;
use super::link::{Link, TrialHeader, end_flags};
use super::{Ended, Gap, Trials};

/// Absolute sampling deadlines on the monotonic clock, and the rules of real time that
/// read it: a trial's first instant, and gaps.
struct Deadlines {
    /// The time the deadlines are on.
    time: Monotonic,
    period_ns: u64,
    /// The next sampling instant \[ns\].
    next_ns: u64,
    /// How many times faster than real time.
    speed: f64,
    /// How long before each instant the plant spins instead of sleeping \[ns\].
    spin_ns: u64,
}

impl Deadlines {
    /// Deadlines every `period_ns` on `time`, the first a period from now.
    fn new(time: Monotonic, period_ns: u64, speed: f64, spin_ns: u64) -> Self {
        Self {
            next_ns: time.now_ns() + period_ns,
            time,
            period_ns,
            speed,
            spin_ns,
        }
    }

    /// Now, on the deadlines' time \[ns\].
    fn now_ns(&self) -> u64 {
        self.time.now_ns()
    }

    /// A trial's first instant: the next one, or now if that is more than a period past
    /// (after an attempt cut short by a late plant, the clock moves on to now).
    fn first_of_trial(&mut self) -> u64 {
        let now = self.now_ns();
        if now > self.next_ns + self.period_ns {
            self.next_ns = now;
        }
        self.next_ns
    }

    /// The sample of instant `t_k`, taken at `woke`, is a gap if it was taken more than
    /// a period after its instant or, `unanswered`, the sample before the last is still
    /// unanswered ([module documentation](self)).
    fn gap(&self, t_k: u64, woke: u64, unanswered: bool) -> Option<Gap> {
        let late_ns = woke.saturating_sub(t_k);
        (late_ns > self.period_ns || unanswered).then_some(Gap {
            missing: 0,
            span_ns: self.period_ns,
            late_ns,
            unanswered,
        })
    }

    /// Sleeps, then spins the last `spin_ns`, until instant `t_ns`: the sleep may
    /// overshoot (the operating system's wake-up latency, on a virtual machine up to
    /// milliseconds), the spin does not.
    fn sleep_until(&self, t_ns: u64) {
        loop {
            let now = self.now_ns();
            if now >= t_ns {
                return;
            }
            let left = t_ns - now;
            if left > self.spin_ns + 100_000 && !self.time.is_mock() {
                std::thread::sleep(std::time::Duration::from_nanos(left - self.spin_ns));
            } else {
                std::hint::spin_loop();
            }
        }
    }
}

/// The actions a realtime trial applies.
struct Held {
    /// The action in effect.
    u: Vec<f64>,
    /// Predictive timing: the action applied from the coming sample instant on.
    pending: Option<[f64; MAX_U]>,
}

impl Held {
    /// Integrates `plant` over the interval `[t_k, deadline)` with the actions of
    /// `arrivals` ([module documentation](self)), piecewise in simulated seconds
    /// (`speed` times the monotonic ones); `pipelined`: predictive timing.
    fn integrate(
        &mut self,
        plant: &mut Plant,
        arrivals: &Arrivals,
        (t_k, deadline): (u64, u64),
        speed: f64,
        pipelined: bool,
    ) {
        let m = self.u.len();
        let sim = |dt_ns: u64| dt_ns as f64 * 1e-9 * speed;
        let mut t = t_k;
        if pipelined {
            if let Some(u) = self.pending.take() {
                self.u.copy_from_slice(&u[..m]);
            }
            self.pending = arrivals.list.last().map(|&(_, u)| u);
        } else {
            for (t_a, u) in &arrivals.list {
                plant.advance(&self.u, sim(t_a - t));
                self.u.copy_from_slice(&u[..m]);
                t = *t_a;
            }
        }
        plant.advance(&self.u, sim(deadline - t));
        if plant.safety().period(!arrivals.list.is_empty()) {
            // No action for a whole period: the safe action from this instant on.
            self.u.fill(0.0);
            self.pending = None;
        }
    }

    /// Predictive timing: the action applied from the coming instant on.
    fn next(&self) -> &[f64] {
        self.pending
            .as_ref()
            .map_or(&self.u[..], |u| &u[..self.u.len()])
    }
}

/// The simulated system in real time.
pub(super) struct RealtimePlant {
    episode: Episode,
    link: Link,
    deadlines: Deadlines,
    /// Keep every sample's timing ([`Link::cycles`]).
    record_cycles: bool,
    /// Predictive timing (`observer.mode`): the action that answers sample `k` is
    /// applied at `t_{k+1}` for the whole interval.
    pipelined: bool,
    /// Whether a sample taken more than a period late cuts the attempt short (`--gaps`).
    cut_gaps: bool,
}

impl RealtimePlant {
    /// Trials of `episode` in real time, a sample every `period` of monotonic `time`
    /// for a task of sampling time `ts` \[s\], published on `link`; the clock starts a
    /// period from now.
    pub(super) fn new(
        (link, episode): (Link, Episode),
        (ts, period): (f64, Duration),
        time: Monotonic,
        spin_us: u64,
        record_cycles: bool,
    ) -> Self {
        let speed = crate::clock::Clock::speed(ts, period);
        let deadlines = Deadlines::new(time, period.as_nanos() as u64, speed, spin_us * 1000);
        Self {
            pipelined: episode.actuator().is_pipelined(),
            episode,
            link,
            deadlines,
            record_cycles,
            cut_gaps: true,
        }
    }

    /// Whether a sample taken more than a period late cuts the attempt short
    /// (`--gaps cut`, the default) or the trial learns across it (`--gaps learn`).
    pub(super) fn cutting_gaps(mut self, cut: bool) -> Self {
        self.cut_gaps = cut;
        self
    }

    /// After a gap at sample `seq`: waits until the agent has answered it (it has caught
    /// up with the samples before), so that the next attempt starts on a loop that keeps
    /// time; the clock moves on to now.
    fn caught_up(&mut self, seq: u64) -> Result<()> {
        loop {
            let a = self.link.actions.recv(&self.link.bus, SILENCE)?;
            if a.header.seq >= seq {
                self.deadlines.next_ns = self.deadlines.now_ns();
                return Ok(());
            }
        }
    }

    /// Publishes the current sample without waiting.
    fn publish(&mut self, header: Header, reward: f64, t_sample_ns: u64) -> Result<u64> {
        let plant = self.episode.plant();
        self.link.publish(
            header,
            reward,
            plant.state(),
            plant.applied_action(),
            t_sample_ns,
        )
    }

    /// Predictive timing: the first interval's action `u_0` from the known start state
    /// (`h`, the start sample), before the clock starts (`observer::timing`, trial
    /// start), into `held`; the start instant moves on by one period for it.
    fn prime(&mut self, h: Header, held: &mut Held) -> Result<()> {
        self.publish(h, 0.0, self.deadlines.now_ns())?;
        let a = loop {
            let a = self.link.actions.recv(&self.link.bus, SILENCE)?;
            // A late answer to the last trial's final sample is stale here: skip it.
            if a.header.seq >= h.seq {
                break a;
            }
        };
        Link::check_answer(&a, h.seq)?;
        self.link.t_action_ns = self.deadlines.now_ns();
        let m = held.u.len();
        held.u.copy_from_slice(&a.u[..m]);
        self.link.u_next.clone_from(&held.u);
        let c = &mut self.deadlines;
        c.next_ns = c.next_ns.max(c.now_ns()) + c.period_ns;
        Ok(())
    }

    /// Notes how the interval from `t_k` (woken at `woke`), awaiting the answer to sample
    /// `waiting_for`, went: the answer's latency, or a deadline miss; its timing.
    fn account(&mut self, arrivals: &Arrivals, waiting_for: u64, t_k: u64, woke: u64) {
        let t_answer = match arrivals.answered {
            Some(t_a) => {
                self.link.latencies.push(t_a.saturating_sub(t_k));
                t_a
            }
            None => {
                self.link.misses += 1;
                0
            }
        };
        if self.record_cycles {
            self.link.cycles.push([waiting_for, t_k, woke, t_answer]);
        }
    }

    /// The interval `[t_k, deadline)` with the actions that arrived in it.
    fn interval(&mut self, arrivals: &Arrivals, held: &mut Held, span: (u64, u64)) -> Step {
        let (speed, pipelined) = (self.deadlines.speed, self.pipelined);
        let step = self
            .episode
            .step_with(|plant| held.integrate(plant, arrivals, span, speed, pipelined));
        if pipelined {
            self.link.u_next.copy_from_slice(held.next());
        }
        self.link.t_action_ns = arrivals.list.last().map_or(0, |&(t_a, _)| t_a);
        step
    }
}

impl Trials for RealtimePlant {
    fn trial(&mut self, trial: &Trial) -> Result<Ended> {
        let steps = self.link.task.steps_per_trial();
        self.episode.reset(&trial.x0);
        let mut held = Held {
            u: vec![0.0; self.link.task.action_dim()],
            pending: None,
        };
        let mut arrivals = Arrivals::new(self.link.seq, self.deadlines.time.clone());
        let header = TrialHeader::new(trial, self.link.task.ts);
        let mut first = flags::START;
        if self.pipelined {
            self.link.u_next.clone_from(&held.u);
            self.prime(header.at(self.link.seq, 0, flags::START), &mut held)?;
            arrivals.newest = self.link.seq - 1;
            first = flags::PRIMED;
        }
        // Room for the trial's timing records now, before the clock runs: a vector that
        // grows within the loop copies itself at a sampling instant.
        self.link.latencies.reserve(steps + 2);
        if self.record_cycles {
            self.link.cycles.reserve(steps + 2);
        }
        let mut t_k = self.deadlines.first_of_trial();
        self.deadlines.sleep_until(t_k);
        let mut woke = self.deadlines.now_ns();
        self.publish(header.at(self.link.seq, 0, first), 0.0, t_k)?;
        let mut ended = None;
        loop {
            let waiting_for = self.link.seq - 1;
            let deadline = t_k + self.deadlines.period_ns;
            let actions = &self.link.actions;
            arrivals.collect(actions, deadline, waiting_for, self.deadlines.spin_ns)?;
            let woke_next = self.deadlines.now_ns();
            self.account(&arrivals, waiting_for, t_k, woke);
            if let Some(end) = ended {
                // The END sample's answer only acknowledges learning; the trial is over.
                self.deadlines.next_ns = deadline;
                return Ok(end);
            }
            let step = self.interval(&arrivals, &mut held, (t_k, deadline));
            woke = woke_next;
            t_k = deadline;
            let unanswered = arrivals.newest + 1 < waiting_for;
            if let Some(gap) = self.deadlines.gap(t_k, woke, unanswered)
                && self.cut_gaps
            {
                // A gap: the sample only ends the attempt, without a reward to learn.
                let h = header.at(self.link.seq, step.sample, flags::END | flags::GAP);
                self.publish(h, 0.0, t_k)?;
                self.caught_up(h.seq)?;
                return Ok(gap.cut(trial, step.sample));
            }
            let h = header.at(self.link.seq, step.sample, end_flags(&step));
            self.publish(h, step.reward, t_k)?;
            if step.ended() {
                ended = Some(Ended::Done(self.episode.skipped()));
            }
        }
    }

    fn link(&mut self) -> &mut Link {
        &mut self.link
    }

    fn safety(&mut self) -> SafetyCounts {
        self.episode.plant_mut().safety().counts()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use wire::MS;

    /// Deadlines every 10 ms on a mock clock that starts at 0.
    fn deadlines() -> (Deadlines, wire::MockTime) {
        let (clock, time) = Monotonic::mock();
        (Deadlines::new(clock, 10 * MS, 1.0, 0), time)
    }

    /// A sample taken more than a period after its instant is a gap; one taken a
    /// period after it, or earlier, is not; nor is one whose predecessor is answered.
    #[test]
    fn a_sample_more_than_a_period_late_is_a_gap() {
        let (d, time) = deadlines();
        let t_k = d.next_ns;
        assert_eq!(t_k, 10 * MS);
        time.advance_to(t_k + 10 * MS);
        assert!(d.gap(t_k, d.now_ns(), false).is_none());
        time.advance(Duration::from_nanos(1));
        let gap = d.gap(t_k, d.now_ns(), false).expect("a gap");
        assert_eq!(
            (gap.late_ns, gap.span_ns, gap.missing),
            (10 * MS + 1, 10 * MS, 0)
        );
        assert!(d.gap(t_k, t_k + MS, true).is_some_and(|g| g.unanswered));
    }

    /// A trial starts at the next instant — unless that is more than a period past:
    /// then now; the deadlines' sleep returns at the instant.
    #[test]
    fn a_trial_starts_within_a_period_of_now() {
        let (mut d, time) = deadlines();
        time.advance_to(19 * MS);
        assert_eq!(d.first_of_trial(), 10 * MS);
        time.advance_to(20 * MS + 1);
        assert_eq!(d.first_of_trial(), 20 * MS + 1);
        time.step_each_reading(Duration::from_micros(1));
        d.sleep_until(25 * MS);
        assert!((25 * MS..25 * MS + 2_000).contains(&time.now_ns()));
    }
}
