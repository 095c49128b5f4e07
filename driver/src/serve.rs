//! The driver's side of the driver contract (`docs/driver.md`): [`serve`] makes a
//! process the driver of a [`Device`] — the clock (a sample every period on
//! `CLOCK_MONOTONIC`), the safety layer of the actuator (clamping, rejection and the
//! watchdog of [`plant::safety::Supervisor`]) and resets — so that a driver for a real
//! motor is one `impl Device` for its amplifier and encoder.

use anyhow::{Result, anyhow};
use plant::Task;
use plant::safety::{Admission, Supervisor};
use wire::{MAX_U, MAX_X, now_ns};

use crate::contract::{
    DRIVER_QOS, DriverCommand, DriverInfo, DriverSample, VERSION, kind, service, status, topic,
};
use crate::device::{Device, REST_SAMPLES};

/// A whole period's worth of the driver's state between sample instants.
struct Driver {
    n_x: usize,
    n_u: usize,
    status: u64,
    reset_id: u64,
    target: [f64; MAX_X],
    at_rest: u32,
    last_command: u64,
    /// The action in effect.
    u: [f64; MAX_U],
    action_this_period: bool,
    acted_since_reset: bool,
    safety: Supervisor,
    /// Commands rejected for other reasons than a non-finite action (those the
    /// supervisor counts): wrong dimensions, unknown kind, an action while not READY.
    other_rejected: u64,
    verbose: bool,
}

impl Driver {
    /// A driver of `task` as it starts: no reset yet (actions are not applied), zero in
    /// effect.
    fn new(task: &Task, verbose: bool) -> Self {
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
            safety: Supervisor::new(task),
            other_rejected: 0,
            verbose,
        }
    }

    fn log(&self, text: impl FnOnce() -> String) {
        if self.verbose {
            eprintln!("driver: {}", text());
        }
    }

    /// Puts `u` into effect now.
    fn set(&mut self, device: &mut impl Device, t_ns: u64, u: &[f64]) {
        self.u[..self.n_u].copy_from_slice(u);
        device.apply(t_ns, &self.u[..self.n_u]);
    }

    /// One command, at its arrival `t_ns` (docs/driver.md, "Commands").
    fn command(&mut self, device: &mut impl Device, t_ns: u64, c: &DriverCommand) {
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
    fn decide(&mut self, device: &mut impl Device, t_ns: u64, x: &[f64]) {
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
                self.status = status::READY;
                self.action_this_period = false;
                self.acted_since_reset = false;
                self.safety.start_trial();
                self.log(|| format!("reset {} done at {x:?}", self.reset_id));
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

    /// The sample of instant `seq` at `t_ns` with state `x`, before this instant's
    /// decisions (`u_applied`: the action in effect at `t_ns`).
    fn sample(&self, seq: u64, t_ns: u64, x: &[f64]) -> DriverSample {
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

/// The [`DriverInfo`] of `device`, started at `t_start_ns`, with period `period_ns`.
fn info(device: &impl Device, period_ns: u64, t_start_ns: u64) -> DriverInfo {
    let task = device.task();
    let mut i = DriverInfo {
        version: VERSION,
        n_x: task.state_dim() as u64,
        n_u: task.action_dim() as u64,
        period_ns,
        time_scale: device.time_scale(),
        watchdog_periods: 1,
        t_start_ns,
        t_publish_ns: now_ns(),
        ..Default::default()
    };
    let name = task.name.as_bytes();
    i.system[..name.len()].copy_from_slice(name);
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

/// Serves `device` as driver `driver_id` until Ctrl-C or SIGTERM (or
/// [`Serving::stop_after`] samples): opens the three services of `docs/driver.md`,
/// publishes the info at start and every second, and at each sample instant
/// `t_start + k · period` samples the device, decides (reset progress, watchdog) and
/// publishes the sample; between sample instants it applies each command as it arrives.
pub fn serve(device: &mut impl Device, driver_id: &str, how: &Serving) -> Result<Served> {
    let task = device.task();
    let (n_x, n_u) = (task.state_dim(), task.action_dim());
    let scale = device.time_scale();
    if !(scale.is_finite() && scale > 0.0) {
        return Err(anyhow!("time scale {scale}: must be positive and finite"));
    }
    let period_ns = (task.ts / scale * 1e9).round() as u64;
    let bus = crate::contract::bus(driver_id).map_err(|e| anyhow!("driver {driver_id:?}: {e}"))?;
    let open = |t: &str, e: wire::Error| {
        if e.to_string().contains("ExceedsMaxSupportedPublishers") {
            anyhow!(
                "another driver {driver_id:?} is running: {} has its one publisher already",
                service(driver_id, t)
            )
        } else {
            anyhow!("driver {driver_id:?}: {e}")
        }
    };
    let infos = bus
        .tx_on::<DriverInfo>(&service(driver_id, topic::INFO), DRIVER_QOS)
        .map_err(|e| open(topic::INFO, e))?;
    let samples = bus
        .tx_on::<DriverSample>(&service(driver_id, topic::SAMPLE), DRIVER_QOS)
        .map_err(|e| open(topic::SAMPLE, e))?;
    let commands = bus
        .rx_on::<DriverCommand>(&service(driver_id, topic::COMMAND), DRIVER_QOS)
        .map_err(|e| open(topic::COMMAND, e))?;
    let wire_err = |e: wire::Error| anyhow!("driver {driver_id:?}: {e}");
    let mut d = Driver::new(task, how.verbose);
    let t_start = now_ns();
    device.apply(t_start, &d.u[..n_u]);
    infos
        .send(info(device, period_ns, t_start))
        .map_err(wire_err)?;
    let mut next_info = t_start + 1_000_000_000;
    let mut served = Served::default();
    let mut x = [0.0; MAX_X];
    let mut seq = 0;
    while !bus.interrupted() && how.stop_after.is_none_or(|n| served.samples < n) {
        let t_k = t_start + seq * period_ns;
        // Until the sample instant: each command at its arrival.
        loop {
            while let Some(c) = commands.try_recv().map_err(wire_err)? {
                d.command(device, now_ns(), &c);
            }
            let now = now_ns();
            if now >= t_k {
                break;
            }
            if t_k - now > how.spin_ns {
                commands.wait_until(t_k - how.spin_ns).map_err(wire_err)?;
            } else {
                std::hint::spin_loop();
            }
        }
        // Woken a whole period late or more: those periods were missed.
        let late = (now_ns() - t_k) / period_ns;
        if late > 0 {
            seq += late;
            served.missed += late;
            d.log(|| format!("missed {late} period(s)"));
        }
        let t_sample = now_ns();
        device.sample(t_sample, &mut x[..n_x]);
        let mut s = d.sample(seq, t_sample, &x[..n_x]);
        d.decide(device, t_sample, &x[..n_x]);
        s.status = d.status;
        s.t_publish_ns = now_ns();
        samples.send(s).map_err(wire_err)?;
        served.samples += 1;
        if t_sample >= next_info {
            infos
                .send(info(device, period_ns, t_start))
                .map_err(wire_err)?;
            next_info = t_sample + 1_000_000_000;
        }
        seq += 1;
    }
    // Stopping: the safe action.
    device.apply(now_ns(), &[0.0; MAX_U][..n_u]);
    Ok(served)
}

#[cfg(test)]
mod tests {
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

    fn action(seq: u64, u: f64) -> DriverCommand {
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
}
