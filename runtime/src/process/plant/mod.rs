//! The plant process: the simulated system ([`plant::Plant`]), clock and episode master.

use std::sync::Arc;

use ::plant::delay::Actuator;
use ::plant::safety::SafetyCounts;
use ::plant::sensor::Sensor;
use ::plant::{MAX_STATE, Plant, Task};
use anyhow::{Result, bail};
use wire::{Action, Bus, Header, MAX_U, Measurement, Truth, flags, now_ns, topic};

use super::{ProcessArgs, SILENCE, STARTUP, pack, wire_err};

/// Runs the plant side of a run: every trial of the configuration, greedy evaluation
/// trials where due (one from each of the task's start states), then announces the end
/// of the run. The system is simulated here, or, with `--driver ID`, is an external
/// driver's ([`super::external`]). A trial that leaves the task's operating range ends
/// early with [`flags::END`] | [`flags::TERMINAL`]; the simulated time counts only
/// samples run.
///
/// What is published is the configured sensor's output (`[observer] sensor`,
/// [`crate::experiment::sensor`], its noise from the run seed exactly as in process); the
/// true state stays here and, when the sensor does not measure all of it, goes out on
/// the evaluation topic [`topic::TRUTH`], for the supervisor alone.
pub fn run(args: &ProcessArgs) -> Result<()> {
    // The clock one level above the observer and the agent: its sampling instant is not
    // held up by their compute on the same core.
    super::set_rt_priority(
        args.scheduling
            .rt_priority
            .map(|p| p.saturating_add(1).min(99)),
    )?;
    if args.scheduling.pin_cpus {
        super::pin(super::Cpus::Clock)?;
    }
    let cfg = args.config()?;
    let task = Arc::new(Task::new(cfg.system));
    let bus = Bus::join(&args.run_id, "plant").map_err(wire_err)?;
    let actions = bus.rx::<Action>(topic::ACTION).map_err(wire_err)?;
    let out = bus
        .tx::<Measurement>(topic::MEASUREMENT)
        .map_err(wire_err)?;
    let run_seed = ::agent::seed::run_seed(cfg.run.seed, args.run_index);
    let sensor = crate::experiment::sensor(&task, &cfg.observer, run_seed);
    let truth = match sensor {
        Sensor::Full => None,
        Sensor::Angle(_) => Some(bus.tx::<Truth>(topic::TRUTH).map_err(wire_err)?),
    };
    let link = Link {
        y: vec![0.0; task.state_dim()],
        sensor,
        truth,
        task: task.clone(),
        bus,
        out,
        actions,
        seq: args.first_seq,
        u_next: vec![f64::NAN; task.action_dim()],
        delay_s: 0.0,
        latencies: Vec::new(),
        cycles: Vec::new(),
        misses: 0,
        run_flags: 0,
    };
    let mut runner: Box<dyn Trials> = match &args.driver {
        Some(_) if cfg.observer.mode == ::agent::config::ObserverMode::Predictive => bail!(
            "predictive timing (`observer.mode = \"predictive\"`) needs the simulated plant: an external driver applies each action as it arrives (use `--observer-mode direct`)"
        ),
        Some(id) => Box::new(super::external::Bridge::connect(link, id, args)?),
        None => {
            link.out
                .wait_for_receivers(args.receivers, STARTUP, &link.bus)
                .map_err(wire_err)?;
            if args.timing == "realtime"
                && (cfg.run.delay_ms != 0.0 || !cfg.run.delay_from.is_empty())
            {
                bail!(
                    "`run.delay_ms`/`run.delay_from` apply in lockstep only: in real time the delays are real"
                );
            }
            let realtime = (args.timing == "realtime").then(|| {
                let period_ns = (task.ts * 1e9 / args.speed).round() as u64;
                Clock {
                    period_ns,
                    next_ns: now_ns() + period_ns,
                    speed: args.speed,
                    spin_ns: args.scheduling.spin_us * 1000,
                }
            });
            Box::new(PlantLoop {
                pipelined: cfg.observer.mode == ::agent::config::ObserverMode::Predictive,
                plant: Plant::new(task.clone()),
                link,
                realtime,
                record_cycles: args.cycles_out.is_some(),
                actuator: crate::experiment::actuator(&task, &cfg, run_seed),
            })
        }
    };
    let eval_every = cfg.run.eval_every;
    let t_sim = |trials: u64, skipped: usize| task.sim_time(trials, skipped as u64);
    // A resumed run continues after trial `--after-trial`, whose simulated time tells how
    // many samples the trials before it skipped.
    let after = u64::from(args.after_trial);
    if !(args.sim_time.is_finite() && args.sim_time >= 0.0) {
        bail!("`--sim-time` {} is not a time", args.sim_time);
    }
    let mut skipped = task.skipped_samples(after, args.sim_time) as usize;
    for trial in after + 1..=u64::from(cfg.run.trials) {
        let x0 = task.initial_states[(trial as usize - 1) % task.initial_states.len()].clone();
        skipped += runner.trial(trial, &x0, 0, t_sim(trial - 1, skipped))?;
        if eval_every > 0 && trial.is_multiple_of(u64::from(eval_every)) {
            for x0 in &task.initial_states {
                runner.trial(trial, x0, flags::GREEDY, t_sim(trial, skipped))?;
            }
        }
    }
    eprintln!("safety: {}", runner.safety());
    let p = runner.link();
    // The end of the run, stamped with the run's final simulated and monotonic time.
    let header = Header {
        seq: p.seq,
        flags: flags::SHUTDOWN | p.run_flags,
        t_sim: t_sim(u64::from(cfg.run.trials), skipped),
        ..Header::default()
    };
    let now = now_ns();
    p.out
        .send(Measurement {
            header,
            t_sample_ns: now,
            t_publish_ns: now,
            deadline_misses: p.misses,
            ..Measurement::default()
        })
        .map_err(wire_err)?;
    if let Some(path) = &args.latency_out {
        let text: String = p.latencies.iter().map(|ns| format!("{ns}\n")).collect();
        std::fs::write(path, text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &args.cycles_out {
        let mut text = String::from(CYCLES_HEADER);
        text.push('\n');
        for c in &p.cycles {
            text.push_str(&format!("{},{},{},{}\n", c[0], c[1], c[2], c[3]));
        }
        std::fs::write(path, text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// Runs trials: the simulation ([`PlantLoop`]) or an external driver
/// ([`super::external::Bridge`]).
pub(super) trait Trials {
    /// One trial from `x0`; `mode` is 0 (learning) or [`flags::GREEDY`]; `t0` is the
    /// simulated time at its start. Returns how many of the trial's samples were not run
    /// because it left the operating range.
    fn trial(&mut self, trial: u64, x0: &[f64], mode: u64, t0: f64) -> Result<usize>;
    /// The run topics.
    fn link(&mut self) -> &mut Link;
    /// How often the plant side's safety measures acted.
    fn safety(&mut self) -> SafetyCounts;
}

/// The plant process's end of the run topics: measurements out, actions in.
pub(super) struct Link {
    pub(super) task: Arc<Task>,
    pub(super) bus: Bus,
    pub(super) out: wire::Tx<Measurement>,
    /// What the plant measures of the true state.
    sensor: Sensor,
    /// The last measurement `y_k`.
    y: Vec<f64>,
    /// Ground truth for the supervisor, when the sensor does not measure the full state.
    truth: Option<wire::Tx<Truth>>,
    pub(super) actions: wire::Rx<Action>,
    /// The next sample's sequence number.
    pub(super) seq: u64,
    /// What the next measurement reports as [`Measurement::u_next`] (NaN: not known).
    u_next: Vec<f64>,
    /// What the next measurement reports as [`Measurement::delay_s`].
    delay_s: f64,
    /// Publish-to-action time of every sample \[ns\].
    pub(super) latencies: Vec<u64>,
    /// Realtime: per sample `[seq, t_sample_ns, t_woke_ns, t_action_ns]` (see
    /// [`CYCLES_HEADER`]).
    pub(super) cycles: Vec<[u64; 4]>,
    /// Deadlines missed so far (realtime, external driver).
    pub(super) misses: u64,
    /// Flags of every message from here on: [`flags::ESTIMATED_REWARD`] once a driver
    /// turned out to measure positions only.
    pub(super) run_flags: u64,
}

impl Link {
    /// Publishes a sample of the true state `x`: the ground truth first (if published),
    /// then the sensor's measurement of `x` — at a trial start `x` itself, as in process
    /// (the state is known there; the sensor, and its noise stream, are not used).
    /// Returns when the measurement was published (monotonic ns).
    pub(super) fn publish(
        &mut self,
        header: Header,
        reward: f64,
        x: &[f64],
        u_applied: &[f64],
        t_sample_ns: u64,
    ) -> Result<u64> {
        let n = self.task.state_dim();
        let header = Header {
            flags: header.flags | self.run_flags,
            ..header
        };
        if header.flags & flags::START != 0 {
            self.y.copy_from_slice(&x[..n]);
        } else {
            self.sensor.measure(&x[..n], &mut self.y);
        }
        if let Some(truth) = &self.truth {
            truth
                .send(Truth {
                    header,
                    n_x: n as u64,
                    x: pack(&x[..n]),
                    t_sample_ns,
                })
                .map_err(wire_err)?;
        }
        let m = Measurement {
            header,
            n_x: n as u64,
            n_u: self.task.action_dim() as u64,
            reward,
            y: pack(&self.y),
            u_applied: pack(u_applied),
            u_next: pack(&self.u_next),
            delay_s: self.delay_s,
            t_sample_ns,
            t_publish_ns: now_ns(),
            deadline_misses: self.misses,
        };
        self.out.send(m).map_err(wire_err)?;
        self.seq += 1;
        Ok(m.t_publish_ns)
    }

    /// From now on the rewards are the observer's, from its estimate: the driver measures
    /// positions only ([`flags::ESTIMATED_REWARD`]). That needs a sensor that leaves the
    /// velocities to the observer (`--sensor angle`).
    pub(super) fn estimate_rewards(&mut self, driver_id: &str) -> Result<()> {
        if matches!(self.sensor, Sensor::Full) {
            bail!(
                "driver {driver_id:?} measures positions only (its velocities are NaN): run with `--sensor angle` and an observer that estimates them (`--observer finite-difference` or `--observer predictive`)"
            );
        }
        self.run_flags |= flags::ESTIMATED_REWARD;
        Ok(())
    }

    /// Checks that action `a` answers sample `seq`.
    pub(super) fn check_answer(a: &Action, seq: u64) -> Result<()> {
        if a.header.seq != seq {
            bail!(
                "action for sample {} arrived while waiting for sample {seq}",
                a.header.seq
            );
        }
        Ok(())
    }
}

/// Columns of the plant's per-sample timing file (`--cycles-out`, realtime): the sample's
/// sequence number, its nominal sampling instant, when the plant actually woke for it,
/// and when the plant found the action answering it (0: not within the period — a
/// deadline miss). Monotonic ns.
pub const CYCLES_HEADER: &str = "seq,t_sample_ns,t_woke_ns,t_action_ns";

/// The simulated system, lockstep or realtime.
struct PlantLoop {
    plant: Plant,
    link: Link,
    /// The sampling clock, in realtime timing.
    realtime: Option<Clock>,
    /// Realtime: keep every sample's timing ([`Link::cycles`]).
    record_cycles: bool,
    /// Lockstep: when actions take effect (timing, delays).
    actuator: Actuator,
    /// Predictive timing (`observer.mode`): in real time, the action that answers sample
    /// `k` is applied at `t_{k+1}` for the whole interval.
    pipelined: bool,
}

/// The actions that arrived within one realtime interval, with their arrival times.
/// One per trial, cleared at every instant: the loop allocates nothing per interval.
struct Arrivals {
    /// `(t_arrival_ns, u)` in order of arrival.
    list: Vec<(u64, [f64; MAX_U])>,
    /// When the answer to the interval's sample arrived.
    answered: Option<u64>,
    /// The sequence number of the trial's first sample: an action answering an earlier
    /// one (a late answer to the last trial's END sample) is not this trial's.
    first_seq: u64,
}

impl Arrivals {
    fn new(first_seq: u64) -> Self {
        Self {
            list: Vec::with_capacity(8),
            answered: None,
            first_seq,
        }
    }

    /// Starts the next interval.
    fn clear(&mut self) {
        self.list.clear();
        self.answered = None;
    }

    /// Notes action `a`, arrived at `t_a`; it answers the interval's sample if its
    /// sequence number is `waiting_for`. An answer to the previous trial is dropped.
    fn push(&mut self, a: &Action, t_a: u64, waiting_for: u64) {
        if a.header.seq < self.first_seq {
            return;
        }
        self.list.push((t_a, a.u));
        if a.header.seq == waiting_for {
            self.answered = Some(t_a);
        }
    }
}

/// Headers of one trial's samples.
pub(super) struct TrialHeader {
    pub(super) trial: u64,
    /// 0 (learning) or [`flags::GREEDY`].
    pub(super) mode: u64,
    /// Simulated time at the trial's start \[s\].
    pub(super) t0: f64,
    /// Sample time \[s\].
    pub(super) ts: f64,
}

impl TrialHeader {
    /// The header of sample `step` of the trial, with sequence number `seq`.
    pub(super) fn at(&self, seq: u64, step: usize, flags: u64) -> Header {
        Header {
            seq,
            trial: self.trial,
            step: step as u64,
            flags: flags | self.mode,
            t_sim: self.t0 + step as f64 * self.ts,
        }
    }
}

/// Absolute sampling deadlines on the monotonic clock.
struct Clock {
    period_ns: u64,
    next_ns: u64,
    speed: f64,
    /// How long before each instant the plant spins instead of sleeping \[ns\].
    spin_ns: u64,
}

/// The last stretch before a sampling instant in which the realtime plant only reads the
/// clock: no transport call, whose duration varies, runs into the instant. An action
/// that arrives within it is found after the instant — for the answer, a deadline miss
/// \[ns\].
const APPROACH_NS: u64 = 20_000;

/// Sleeps, then spins the last `spin_ns`, until monotonic time `t_ns`: the sleep may
/// overshoot (the operating system's wake-up latency, on a virtual machine up to
/// milliseconds), the spin does not.
fn sleep_until(t_ns: u64, spin_ns: u64) {
    loop {
        let now = now_ns();
        if now >= t_ns {
            return;
        }
        let left = t_ns - now;
        if left > spin_ns + 100_000 {
            std::thread::sleep(std::time::Duration::from_nanos(left - spin_ns));
        } else {
            std::hint::spin_loop();
        }
    }
}

impl PlantLoop {
    /// Publishes the current sample and waits for the action that answers it.
    fn exchange(&mut self, header: Header, reward: f64) -> Result<Vec<f64>> {
        let l = &mut self.link;
        match self.actuator.next_action() {
            Some(u) => l.u_next.copy_from_slice(u),
            None => l.u_next.fill(f64::NAN),
        }
        l.delay_s = if header.flags & (flags::START | flags::PRIMED) != 0 {
            0.0
        } else {
            self.actuator.last_delay()
        };
        let t_publish_ns = l.publish(
            header,
            reward,
            self.plant.state(),
            self.plant.applied_action(),
            now_ns(),
        )?;
        let a = l.actions.recv(&l.bus, SILENCE).map_err(wire_err)?;
        l.latencies.push(now_ns() - t_publish_ns);
        Link::check_answer(&a, header.seq)?;
        Ok(a.u[..l.task.action_dim()].to_vec())
    }

    /// The flags that end a trial after this sample: [`flags::END`] on the last sample,
    /// [`flags::END`] | [`flags::TERMINAL`] when the operating range was left.
    fn end_flags(&self, last: bool) -> u64 {
        if self.plant.terminated() {
            flags::END | flags::TERMINAL
        } else if last {
            flags::END
        } else {
            0
        }
    }

    /// Publishes the current sample without waiting (realtime).
    fn publish(&mut self, header: Header, reward: f64, t_sample_ns: u64) -> Result<u64> {
        self.link.publish(
            header,
            reward,
            self.plant.state(),
            self.plant.applied_action(),
            t_sample_ns,
        )
    }

    /// One trial in real time: the plant samples at absolute deadlines; in direct timing
    /// every action that arrives within an interval is applied from its arrival on (the
    /// previous one held until then); in predictive timing the last action that arrived
    /// within an interval is applied at the next sample instant, for the whole next
    /// interval (none arrived: the previous one is held). An interval in which the action
    /// for its sample did not arrive is a missed deadline. The reward of an interval is `ρ(x_k, u)` with the action in effect
    /// at its end. An interval without any action trips the plant's watchdog
    /// ([`plant::safety::Supervisor::period`]): zero from its
    /// end on, until an action arrives. A late answer to the previous trial's last sample
    /// is dropped, not applied in this one. Nothing is allocated per interval.
    fn realtime_trial(&mut self, trial: u64, x0: &[f64], mode: u64, t0: f64) -> Result<usize> {
        let steps = self.link.task.steps_per_trial();
        let (period_ns, speed, spin_ns) = {
            let c = self.realtime.as_ref().expect("realtime");
            (c.period_ns, c.speed, c.spin_ns)
        };
        self.plant.reset(x0);
        let m = self.link.task.action_dim();
        let mut u_hold = vec![0.0; m];
        // Predictive timing: the action applied from the coming sample instant on.
        let mut pending: Option<[f64; MAX_U]> = None;
        let mut arrivals = Arrivals::new(self.link.seq);
        if self.pipelined {
            self.link.u_next.clone_from(&u_hold);
        }
        let header = TrialHeader {
            trial,
            mode,
            t0,
            ts: self.link.task.ts,
        };
        let mut first = flags::START;
        if self.pipelined {
            // The first interval's action u_0 from the known start state, before the clock
            // starts (observer::timing, trial start); the start instant moves on by one
            // period for it.
            let h = header.at(self.link.seq, 0, flags::START);
            self.publish(h, 0.0, now_ns())?;
            let a = loop {
                let a = self
                    .link
                    .actions
                    .recv(&self.link.bus, SILENCE)
                    .map_err(wire_err)?;
                // A late answer to the last trial's final sample is stale here: skip it.
                if a.header.seq >= h.seq {
                    break a;
                }
            };
            Link::check_answer(&a, h.seq)?;
            u_hold = a.u[..self.link.task.action_dim()].to_vec();
            self.link.u_next.clone_from(&u_hold);
            let c = self.realtime.as_mut().expect("realtime");
            c.next_ns = c.next_ns.max(now_ns()) + c.period_ns;
            first = flags::PRIMED;
        }
        // Room for the trial's timing records now, before the clock runs: a vector that
        // grows within the loop copies itself at a sampling instant.
        self.link.latencies.reserve(steps + 2);
        if self.record_cycles {
            self.link.cycles.reserve(steps + 2);
        }
        let mut t_k = self.realtime.as_ref().expect("realtime").next_ns;
        sleep_until(t_k, spin_ns);
        let mut woke = now_ns();
        self.publish(header.at(self.link.seq, 0, first), 0.0, t_k)?;
        let mut ended_after = None;
        // An action received only after the instant it was waited for.
        let mut late: Option<(u64, Action)> = None;
        for k in 0..=steps {
            let waiting_for = self.link.seq - 1;
            let deadline = t_k + period_ns;
            // Collect the actions arriving in [t_k, deadline). The plant waits for them
            // (`Rx::wait_until`: woken by an arrival, or at `spin_ns` before the deadline,
            // to the high-resolution timer's precision); in those last `spin_ns` it polls
            // without sleeping, and in the last `APPROACH_NS` it only reads the clock, so
            // that the next sampling instant depends neither on when the operating system
            // wakes it nor on the transport.
            arrivals.clear();
            if let Some((t_a, a)) = late.take() {
                arrivals.push(&a, t_a.min(deadline), waiting_for);
            }
            loop {
                let now = now_ns();
                if now + APPROACH_NS >= deadline {
                    break;
                }
                let Some(a) = self.link.actions.try_recv().map_err(wire_err)? else {
                    let left = deadline - now;
                    if left > spin_ns {
                        self.link
                            .actions
                            .wait_until(deadline - spin_ns)
                            .map_err(wire_err)?;
                    } else {
                        std::hint::spin_loop();
                    }
                    continue;
                };
                let t_a = now_ns();
                if t_a >= deadline {
                    // Received across the instant (the call was held up): the next
                    // interval's.
                    late = Some((t_a, a));
                    break;
                }
                arrivals.push(&a, t_a, waiting_for);
            }
            while now_ns() < deadline {
                std::hint::spin_loop();
            }
            let woke_next = now_ns();
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
            if let Some(skipped) = ended_after {
                // The END sample's answer only acknowledges learning; the trial is over.
                self.realtime.as_mut().expect("realtime").next_ns = deadline;
                return Ok(skipped);
            }
            // Integrate the interval piecewise, in simulated seconds.
            let sim = |dt_ns: u64| dt_ns as f64 * 1e-9 * speed;
            let mut t = t_k;
            let mut x_k = [0.0; MAX_STATE];
            let n = self.link.task.state_dim();
            x_k[..n].copy_from_slice(self.plant.state());
            if self.pipelined {
                if let Some(u) = pending.take() {
                    u_hold.copy_from_slice(&u[..m]);
                }
                pending = arrivals.list.last().map(|&(_, u)| u);
            } else {
                for (t_a, u) in &arrivals.list {
                    self.plant.advance(&u_hold, sim(t_a - t));
                    u_hold.copy_from_slice(&u[..m]);
                    t = *t_a;
                }
            }
            self.plant.advance(&u_hold, sim(deadline - t));
            if self.plant.safety().period(!arrivals.list.is_empty()) {
                // No action for a whole period: the safe action from this instant on.
                u_hold.fill(0.0);
                pending = None;
            }
            if self.pipelined {
                let next = pending.as_ref().map_or(&u_hold[..], |u| &u[..m]);
                self.link.u_next.copy_from_slice(next);
            }
            let r = self.plant.reward_of_transition(
                self.link
                    .task
                    .reward
                    .reward(&x_k[..n], self.plant.applied_action()),
            );
            woke = woke_next;
            t_k = deadline;
            let end = self.end_flags(k + 1 == steps);
            self.publish(header.at(self.link.seq, k + 1, end), r, t_k)?;
            if end != 0 {
                ended_after = Some(steps - k - 1);
            }
        }
        unreachable!("the loop returns after the END sample's answer")
    }
}

impl Trials for PlantLoop {
    fn trial(&mut self, trial: u64, x0: &[f64], mode: u64, t0: f64) -> Result<usize> {
        if self.realtime.is_some() {
            return self.realtime_trial(trial, x0, mode, t0);
        }
        let task = self.link.task.clone();
        let steps = task.steps_per_trial();
        self.plant.reset(x0);
        self.actuator.reset();
        let header = TrialHeader {
            trial,
            mode,
            t0,
            ts: task.ts,
        };
        let mut u = self.exchange(header.at(self.link.seq, 0, flags::START), 0.0)?;
        if self.pipelined {
            // The answer to the start state is the first interval's action u_0; told so,
            // the agent answers u_1 (observer::timing, trial start).
            self.actuator.prime(&u);
            u = self.exchange(header.at(self.link.seq, 0, flags::PRIMED), 0.0)?;
        }
        for k in 0..steps {
            let r = self.actuator.interval(&mut self.plant, &u);
            let end = self.end_flags(k + 1 == steps);
            u = self.exchange(header.at(self.link.seq, k + 1, end), r)?;
            if self.plant.terminated() {
                return Ok(steps - k - 1);
            }
        }
        Ok(0)
    }

    fn link(&mut self) -> &mut Link {
        &mut self.link
    }

    fn safety(&mut self) -> SafetyCounts {
        self.plant.safety().counts()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn action(seq: u64, u: f64) -> Action {
        let mut a = Action::default();
        a.header.seq = seq;
        a.n_u = 1;
        a.u[0] = u;
        a
    }

    /// A late answer to the previous trial's END sample is not applied in the next
    /// trial; the answer to the interval's sample is marked; `clear` starts afresh.
    #[test]
    fn arrivals_keep_this_trials_actions() {
        let mut arrivals = Arrivals::new(10);
        arrivals.push(&action(9, 0.0), 100, 10);
        assert!(arrivals.list.is_empty() && arrivals.answered.is_none());
        arrivals.push(&action(10, 1.5), 200, 10);
        arrivals.push(&action(11, -2.0), 300, 10);
        assert_eq!(arrivals.answered, Some(200));
        let applied: Vec<(u64, f64)> = arrivals.list.iter().map(|(t, u)| (*t, u[0])).collect();
        assert_eq!(applied, [(200, 1.5), (300, -2.0)]);
        arrivals.clear();
        assert!(arrivals.list.is_empty() && arrivals.answered.is_none());
        arrivals.push(&action(11, -2.0), 400, 11);
        assert_eq!(arrivals.answered, Some(400));
    }
}
