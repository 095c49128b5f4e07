//! The driver's state between sample instants: commands as they arrive, the decisions
//! of a sample instant (a reset's progress, the watchdog), the sample it publishes.

use plant::Task;
use plant::safety::{Admission, SafetyLayer};
use wire::{MAX_U, MAX_X};

use crate::contract::{DriverCommand, DriverSample, kind, status};
use crate::kit::device::{Device, REST_SAMPLES};

/// A whole period's worth of the driver's state between sample instants.
pub(super) struct Driver {
    pub(super) n_x: usize,
    pub(super) n_u: usize,
    pub(super) status: u64,
    pub(super) reset_id: u64,
    pub(super) target: [f64; MAX_X],
    pub(super) at_rest: u32,
    pub(super) last_command: u64,
    /// The action in effect.
    pub(super) u: [f64; MAX_U],
    pub(super) action_this_period: bool,
    pub(super) acted_since_reset: bool,
    pub(super) safety: SafetyLayer,
    /// Commands rejected for other reasons than a non-finite action (those the
    /// safety layer counts): wrong dimensions, unknown kind, an action while not READY.
    pub(super) other_rejected: u64,
    pub(super) verbose: bool,
}

impl Driver {
    /// A driver of `task` as it starts: no reset yet (actions are not applied), zero in
    /// effect.
    pub(super) fn new(task: &Task, verbose: bool) -> Self {
        Self {
            n_x: task.state_dim(),
            n_u: task.action_dim(),
            status: 0,
            reset_id: 0,
            target: [0.0; MAX_X],
            at_rest: 0,
            last_command: 0,
            u: [0.0; MAX_U],
            action_this_period: false,
            acted_since_reset: false,
            safety: SafetyLayer::new(task),
            other_rejected: 0,
            verbose,
        }
    }

    pub(super) fn log(&self, text: impl FnOnce() -> String) {
        if self.verbose {
            eprintln!("driver: {}", text());
        }
    }

    /// Puts `u` into effect now.
    pub(super) fn set(&mut self, device: &mut impl Device, t_ns: u64, u: &[f64]) {
        self.u[..self.n_u].copy_from_slice(u);
        device.apply(t_ns, &self.u[..self.n_u]);
    }

    /// One command, at its arrival `t_ns` (docs/driver.md, "Commands").
    pub(super) fn command(&mut self, device: &mut impl Device, t_ns: u64, c: &DriverCommand) {
        match c.kind {
            kind::ACTION if self.status & status::READY == 0 => self.other_rejected += 1,
            kind::ACTION if c.n_u as usize != self.n_u => {
                self.other_rejected += 1;
                self.set(device, t_ns, &[0.0; MAX_U][..self.n_u]);
                self.log(|| format!("rejected command {}: n_u {}", c.seq, c.n_u));
            }
            kind::ACTION => {
                let mut u = [0.0; MAX_U];
                let admitted = self.safety.admit(&c.u[..self.n_u], &mut u[..self.n_u]);
                self.set(device, t_ns, &u[..self.n_u]);
                if admitted == Admission::Rejected {
                    self.log(|| format!("rejected command {}: u {:?}", c.seq, c.u));
                    return;
                }
                self.last_command = c.seq;
                self.action_this_period = true;
                self.acted_since_reset = true;
                self.status &= !status::WATCHDOG;
            }
            kind::RESET => {
                let x0 = &c.x0[..self.n_x];
                if c.n_x as usize != self.n_x || x0.iter().any(|v| !v.is_finite()) {
                    self.other_rejected += 1;
                    self.log(|| format!("rejected reset {}: n_x {}, x0 {x0:?}", c.seq, c.n_x));
                    return;
                }
                self.status = status::RESETTING;
                self.reset_id = c.seq;
                self.target = c.x0;
                self.at_rest = 0;
                self.log(|| format!("reset {} to {x0:?}", c.seq));
            }
            _ => self.other_rejected += 1,
        }
    }

    /// The decisions of a sample instant with state `x` (docs/driver.md, "What the
    /// driver does", step 3): a reset's progress, or the watchdog.
    pub(super) fn decide(&mut self, device: &mut impl Device, t_ns: u64, x: &[f64]) {
        if self.status & status::RESETTING != 0 {
            let target = self.target;
            let x0 = &target[..self.n_x];
            self.at_rest = if device.at_rest(x, x0) {
                self.at_rest + 1
            } else {
                0
            };
            let mut out = [0.0; MAX_U];
            if self.at_rest >= REST_SAMPLES {
                self.ready(x);
            } else {
                let mut u = [0.0; MAX_U];
                device.reset_action(x, x0, &mut u[..self.n_u]);
                // Clamped; a non-finite reset action (the device's bug) is the safe one.
                device.task().saturate(&u[..self.n_u], &mut out[..self.n_u]);
            }
            self.set(device, t_ns, &out[..self.n_u]);
        } else if self.status & status::READY != 0 && self.acted_since_reset {
            let fresh = std::mem::take(&mut self.action_this_period);
            if self.safety.period(fresh) && self.status & status::WATCHDOG == 0 {
                self.status |= status::WATCHDOG;
                self.set(device, t_ns, &[0.0; MAX_U][..self.n_u]);
                self.log(|| "watchdog: no action for a period, applying zero".into());
            }
        }
    }

    /// The reset is done at state `x`: READY, no action since (the caller applies zero).
    pub(super) fn ready(&mut self, x: &[f64]) {
        self.status = status::READY;
        self.action_this_period = false;
        self.acted_since_reset = false;
        self.safety.start_trial();
        self.log(|| format!("reset {} done at {x:?}", self.reset_id));
    }

    /// Puts into sample `s` the reward and ending of the period it closes, from a device
    /// that provides them, if `closes_period`: it closes a period of a trial (not a
    /// reset's READY sample).
    pub(super) fn outcome(
        &self,
        device: &mut impl Device,
        s: &mut DriverSample,
        closes_period: bool,
    ) {
        if closes_period && device.provides_reward() {
            let o = device.outcome();
            s.reward = o.reward;
            s.ending = o.ending;
        }
    }

    /// Whether the sample taken now closes a period of a trial on a real-time clock:
    /// READY, with an action applied since the reset.
    pub(super) fn in_trial(&self) -> bool {
        self.status & status::READY != 0 && self.acted_since_reset
    }

    /// The sample of instant `seq` at `t_ns` with state `x`, before this instant's
    /// decisions (`u_applied`: the action in effect at `t_ns`).
    pub(super) fn sample(&self, seq: u64, t_ns: u64, x: &[f64]) -> DriverSample {
        let counts = self.safety.counts();
        let mut s = DriverSample {
            seq,
            t_sample_ns: t_ns,
            status: self.status,
            reset_id: self.reset_id,
            last_command: self.last_command,
            n_x: self.n_x as u64,
            n_u: self.n_u as u64,
            u_applied: self.u,
            clamped: counts.clamped,
            rejected: counts.rejected + self.other_rejected,
            watchdog_trips: counts.watchdog_trips,
            ..Default::default()
        };
        s.x[..self.n_x].copy_from_slice(x);
        s
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use plant::SystemName;

    /// A device that records what it was asked, with a state set by the test.
    struct Probe {
        task: Task,
        x: Vec<f64>,
        applied: Vec<(u64, Vec<f64>)>,
    }

    impl Device for Probe {
        fn task(&self) -> &Task {
            &self.task
        }
        fn sample(&mut self, _: u64, x: &mut [f64]) {
            x.copy_from_slice(&self.x);
        }
        fn apply(&mut self, t: u64, u: &[f64]) {
            self.applied.push((t, u.to_vec()));
        }
        fn reset_action(&mut self, _: &[f64], _: &[f64], u: &mut [f64]) {
            u[0] = 10.0; // beyond the limit: clamped
        }
        fn at_rest(&self, x: &[f64], x0: &[f64]) -> bool {
            x == x0
        }
    }

    /// An action command `seq` of one component `u`.
    pub(in crate::kit::serve) fn action(seq: u64, u: f64) -> DriverCommand {
        let mut c = DriverCommand {
            seq,
            kind: kind::ACTION,
            n_u: 1,
            ..Default::default()
        };
        c.u[0] = u;
        c
    }

    fn reset(seq: u64, x0: [f64; 2]) -> DriverCommand {
        let mut c = DriverCommand {
            seq,
            kind: kind::RESET,
            n_x: 2,
            ..Default::default()
        };
        c.x0[..2].copy_from_slice(&x0);
        c
    }

    /// The contract's sequence on one device: actions before a reset are ignored, the
    /// reset brakes (clamped) until three samples at rest, then actions apply (clamped,
    /// non-finite rejected), and a silent period engages the watchdog.
    #[test]
    fn commands_resets_and_the_watchdog_follow_the_contract() {
        let task = Task::new(SystemName::Pendulum);
        let mut dev = Probe {
            task: Task::new(SystemName::Pendulum),
            x: vec![0.5, 0.0],
            applied: vec![],
        };
        let mut d = Driver::new(&task, false);
        d.command(&mut dev, 1, &action(1, 1.0));
        assert_eq!((d.status, d.other_rejected, dev.applied.len()), (0, 1, 0));
        d.command(&mut dev, 2, &reset(2, [3.0, 0.0]));
        assert_eq!((d.status, d.reset_id), (status::RESETTING, 2));
        d.command(&mut dev, 3, &action(3, 1.0));
        assert_eq!(d.other_rejected, 2, "ignored while resetting");
        d.decide(&mut dev, 4, &[0.5, 0.0]);
        assert_eq!(
            dev.applied.last().unwrap(),
            &(4, vec![3.0]),
            "brake, clamped"
        );
        dev.x = vec![3.0, 0.0];
        for k in 0..REST_SAMPLES {
            assert_eq!(d.status, status::RESETTING, "{k} samples at rest");
            d.decide(&mut dev, 5 + u64::from(k), &[3.0, 0.0]);
        }
        assert_eq!(d.status, status::READY);
        assert_eq!(dev.applied.last().unwrap().1, vec![0.0]);
        // READY, no action yet: no watchdog.
        d.decide(&mut dev, 10, &[3.0, 0.0]);
        assert_eq!(d.status, status::READY);
        d.command(&mut dev, 11, &action(11, 5.0));
        assert_eq!(
            (d.u[0], d.last_command, d.safety.counts().clamped),
            (3.0, 11, 1)
        );
        d.command(&mut dev, 12, &action(12, f64::NAN));
        assert_eq!(
            (d.u[0], d.last_command),
            (0.0, 11),
            "rejected: zero applies"
        );
        let s = d.sample(7, 13, &[3.0, 0.0]);
        assert_eq!((s.rejected, s.clamped, s.u_applied[0]), (3, 1, 0.0));
        d.command(&mut dev, 14, &action(14, -1.0));
        d.decide(&mut dev, 15, &[3.0, 0.0]);
        assert_eq!(d.status, status::READY, "an action this period");
        d.decide(&mut dev, 16, &[3.0, 0.0]);
        assert_eq!(d.status, status::READY | status::WATCHDOG);
        assert_eq!(dev.applied.last().unwrap(), &(16, vec![0.0]));
        assert_eq!(d.safety.counts().watchdog_trips, 1);
        d.command(&mut dev, 17, &action(17, 0.5));
        assert_eq!(d.status, status::READY, "the next action clears it");
        let mut wrong = action(18, 0.5);
        wrong.n_u = 2;
        d.command(&mut dev, 18, &wrong);
        assert_eq!((d.u[0], d.other_rejected), (0.0, 3));
    }

    /// A device that provides the reward and endings: a sample that closes a period of a
    /// trial carries them; a reset's READY sample, and any sample of a device that does
    /// not provide them, carries zero.
    #[test]
    fn samples_carry_the_outcome_of_a_device_that_provides_it() {
        struct Scored(Probe);
        impl Device for Scored {
            fn task(&self) -> &Task {
                &self.0.task
            }
            fn sample(&mut self, t: u64, x: &mut [f64]) {
                self.0.sample(t, x)
            }
            fn apply(&mut self, t: u64, u: &[f64]) {
                self.0.apply(t, u)
            }
            fn reset_action(&mut self, x: &[f64], x0: &[f64], u: &mut [f64]) {
                self.0.reset_action(x, x0, u)
            }
            fn at_rest(&self, x: &[f64], x0: &[f64]) -> bool {
                self.0.at_rest(x, x0)
            }
            fn provides_reward(&self) -> bool {
                true
            }
            fn outcome(&mut self) -> crate::Outcome {
                crate::Outcome {
                    reward: -2.5,
                    ending: crate::contract::ending::TRUNCATED,
                }
            }
        }
        let task = Task::new(SystemName::Pendulum);
        let probe = || Probe {
            task: Task::new(SystemName::Pendulum),
            x: vec![0.0, 0.0],
            applied: vec![],
        };
        let mut dev = Scored(probe());
        let mut d = Driver::new(&task, false);
        d.command(&mut dev, 1, &reset(1, [0.0, 0.0]));
        d.ready(&[0.0, 0.0]);
        let mut s = d.sample(1, 2, &[0.0, 0.0]);
        d.outcome(&mut dev, &mut s, d.in_trial());
        assert_eq!((s.reward, s.ending), (0.0, 0), "the READY sample");
        d.command(&mut dev, 3, &action(3, 1.0));
        let mut s = d.sample(2, 4, &[0.0, 0.0]);
        d.outcome(&mut dev, &mut s, d.in_trial());
        assert_eq!((s.reward, s.ending), (-2.5, 2));
        let mut plain = probe();
        let mut s = d.sample(3, 5, &[0.0, 0.0]);
        d.outcome(&mut plain, &mut s, true);
        assert_eq!((s.reward, s.ending), (0.0, 0), "a device without a reward");
    }
}
