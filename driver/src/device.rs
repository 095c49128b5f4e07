//! The driver's side of the driver contract (`docs/driver.md`), in Rust: [`serve`] makes
//! a process the driver of a [`Device`] — the clock (a sample every period on
//! `CLOCK_MONOTONIC`), the safety layer of the actuator (clamping, rejection and the
//! watchdog of [`plant::safety::Supervisor`]) and resets — so that a driver for a real
//! motor is one `impl Device` for its amplifier and encoder.
//!
//! [`Simulated`] is such a device: the pendulum of Appendix A.1 integrated over the real
//! elapsed time, piecewise between action arrivals, as the Python example driver
//! (`examples/python_driver/`) does; `rig sim-driver` serves it and
//! `driver/examples/motor_driver.rs` shows the template.

use std::sync::Arc;

use crate::contract::{
    DRIVER_QOS, DriverCommand, DriverInfo, DriverSample, VERSION, kind, service, status, topic,
};
use anyhow::{Result, anyhow};
use plant::angle::wrap;
use plant::safety::{Admission, Supervisor};
use plant::sensor::Sensor;
use plant::{Plant, SystemName, Task};
use wire::{MAX_U, MAX_X, now_ns};

/// The hardware behind a driver (or a simulation of it). [`serve`] calls it from one
/// thread, in time order.
pub trait Device {
    /// The task the device is: its system, dimensions, sample time and action limits —
    /// what the driver advertises and the rig requires to be the thesis's.
    fn task(&self) -> &Task;

    /// Simulated seconds per monotonic-clock second: 1 for hardware.
    fn time_scale(&self) -> f64 {
        1.0
    }

    /// Writes the state at monotonic time `t_ns` (now) into `x` (`n_x` components, angles
    /// wrapped to [−π, π)): hardware reads its sensors; a simulation integrates up to
    /// `t_ns` with the action in effect. A device that measures positions only writes
    /// NaN for every velocity, and the rig estimates them (docs/driver.md).
    fn sample(&mut self, t_ns: u64, x: &mut [f64]);

    /// Puts action `u` into effect from monotonic time `t_ns` (now) until the next call.
    /// [`serve`] only passes finite actions within the task's limits.
    fn apply(&mut self, t_ns: u64, u: &[f64]);

    /// During a reset, at a sample instant with state `x`: the action (to be clamped to
    /// the limits) that brings the device toward rest at `x0`.
    fn reset_action(&mut self, x: &[f64], x0: &[f64], u: &mut [f64]);

    /// Whether state `x` is at rest at `x0`, by the device's own tolerance; a reset is
    /// done after [`REST_SAMPLES`] such samples in a row.
    fn at_rest(&self, x: &[f64], x0: &[f64]) -> bool;
}

/// Consecutive samples at rest that end a reset.
pub const REST_SAMPLES: u32 = 3;

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
    let name = task.name.as_str().as_bytes();
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

/// A simulated device: a [`Task`]'s system integrated with RK4 over the real elapsed
/// time (times `speed`), piecewise between action arrivals, with the steps of the
/// in-process plant ([`Plant::advance`]). It resets as hardware would: braked toward
/// the start state by a PD law on each position–velocity pair (`x = [positions,
/// velocities]`, one action per position), `u_i = K_p e_i + K_d ė_i` with the gains of
/// [`Simulated::brake_gains`], until at rest within 0.02 (rad or m) and 0.05 (per s).
///
/// [`Simulated::measuring_positions_only`] makes it an encoder-only setup, as the
/// physical pendulum of §6.4.1: its samples carry the positions quantised to the
/// encoder's counts and NaN velocities (not measured), and the rig's observer estimates
/// them. Its reset brake still acts on the simulation's true state (a hardware driver
/// would brake on its own velocity estimate).
pub struct Simulated {
    plant: Plant,
    /// What the samples report of the true state.
    sensor: Sensor,
    u: [f64; MAX_U],
    /// Monotonic time the simulation has reached.
    t_ns: u64,
    speed: f64,
    gains: (f64, f64),
}

impl Simulated {
    /// The reset brake's gains `(K_p, K_d)` for `system` (action units per position
    /// unit, and per velocity unit), or why it cannot be reset by one: the vertical arm's
    /// start state `[−1.1, 1, 0, 0]` needs 5.5 N m against gravity at joint 1, beyond the
    /// ±1 N m limit — a state it cannot rest in.
    pub fn brake_gains(system: SystemName) -> Result<(f64, f64)> {
        match system {
            // The Python example driver's gains: V/rad, V s/rad.
            SystemName::Pendulum => Ok((1.0, 0.7)),
            // N m/rad, N m s/rad: about 0.7 of critical damping on the first joint's
            // inertia (0.27 kg m²).
            SystemName::ArmHorizontal => Ok((1.0, 0.7)),
            // ±0.1 N m; the joints' friction (0.125 N m s/rad) adds damping.
            SystemName::Arm64 => Ok((0.1, 0.05)),
            // N/m, N s/m on the unit mass.
            SystemName::DoubleIntegrator => Ok((5.0, 3.0)),
            SystemName::ArmVertical => Err(anyhow!(
                "the simulated arm-vertical cannot rest at its start state [-1.1, 1, 0, 0]: gravity needs 5.5 N m at joint 1, beyond the ±1 N m limit"
            )),
        }
    }

    /// `system` at its first start state, running `speed` times faster than real time.
    pub fn new(system: SystemName, speed: f64) -> Result<Self> {
        let gains = Self::brake_gains(system)?;
        if !(speed.is_finite() && speed > 0.0 && speed <= 1000.0) {
            return Err(anyhow!("--speed {speed}: must be in (0, 1000]"));
        }
        Ok(Self {
            plant: Plant::new(Arc::new(Task::new(system))),
            sensor: Sensor::Full,
            u: [0.0; MAX_U],
            t_ns: now_ns(),
            speed,
            gains,
        })
    }

    /// Samples report the positions only, quantised to `counts_per_rev` counts per
    /// revolution (no noise), and NaN velocities.
    pub fn measuring_positions_only(mut self, counts_per_rev: u32) -> Result<Self> {
        if counts_per_rev == 0 {
            return Err(anyhow!("--counts-per-rev 0: must be at least 1"));
        }
        let mask = &self.plant.task().angle_mask;
        self.sensor = Sensor::angle(mask, counts_per_rev, 0.0, 0);
        Ok(self)
    }

    /// Integrates up to monotonic time `t_ns` with the action in effect.
    fn advance(&mut self, t_ns: u64) {
        if t_ns > self.t_ns {
            let m = self.plant.task().action_dim();
            let seconds = (t_ns - self.t_ns) as f64 * 1e-9 * self.speed;
            self.plant.advance(&self.u[..m], seconds);
            self.t_ns = t_ns;
        }
    }

    /// `x0 − x` per position (angles wrapped to [−π, π)) and per velocity: the pairs
    /// `(e_i, ė_i)`, one per action component.
    fn errors<'a>(&'a self, x: &'a [f64], x0: &'a [f64]) -> impl Iterator<Item = (f64, f64)> + 'a {
        let task = self.plant.task();
        let m = task.action_dim();
        (0..m).map(move |i| {
            let e = x0[i] - x[i];
            let e = if task.angle_mask[i] { wrap(e) } else { e };
            (e, x0[m + i] - x[m + i])
        })
    }
}

/// "At rest" tolerance of [`Simulated`]: position (rad or m) and velocity (per s).
const REST_POSITION: f64 = 0.02;
const REST_SPEED: f64 = 0.05;

impl Device for Simulated {
    fn task(&self) -> &Task {
        self.plant.task()
    }

    fn time_scale(&self) -> f64 {
        self.speed
    }

    fn sample(&mut self, t_ns: u64, x: &mut [f64]) {
        self.advance(t_ns);
        self.sensor.measure(self.plant.state(), x);
    }

    fn apply(&mut self, t_ns: u64, u: &[f64]) {
        self.advance(t_ns);
        self.u[..u.len()].copy_from_slice(u);
    }

    /// The brake acts on the true state (`x` may lack the velocities).
    fn reset_action(&mut self, _: &[f64], x0: &[f64], u: &mut [f64]) {
        let (kp, kd) = self.gains;
        for (ui, (e, de)) in u.iter_mut().zip(self.errors(self.plant.state(), x0)) {
            *ui = kp * e + kd * de;
        }
    }

    fn at_rest(&self, _: &[f64], x0: &[f64]) -> bool {
        self.errors(self.plant.state(), x0)
            .all(|(e, de)| e.abs() < REST_POSITION && de.abs() < REST_SPEED)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The simulated pendulum falls from near the top as the in-process plant does.
    #[test]
    fn the_simulated_pendulum_integrates_as_the_plant() {
        let mut sim = Simulated::new(SystemName::Pendulum, 1.0).unwrap();
        let mut plant = Plant::new(Arc::new(Task::new(SystemName::Pendulum)));
        sim.plant.reset(&[0.3, 0.0]);
        plant.reset(&[0.3, 0.0]);
        let t0 = sim.t_ns;
        let mut x = [0.0; 2];
        sim.apply(t0, &[0.5]);
        sim.sample(t0 + 30_000_000, &mut x);
        plant.step(&[0.5]);
        for (a, b) in x.iter().zip(plant.state()) {
            assert!((a - b).abs() < 1e-9, "one period: the plant's step: {x:?}");
        }
        assert!(x[0] > 0.3, "falling away from the top: {x:?}");
    }

    /// An encoder-only simulation reports the angle in whole counts and no velocity.
    #[test]
    fn a_simulated_encoder_measures_the_angle_only() {
        let sim = Simulated::new(SystemName::Pendulum, 1.0).unwrap();
        assert!(sim.measuring_positions_only(0).is_err());
        let mut sim = Simulated::new(SystemName::Pendulum, 1.0)
            .unwrap()
            .measuring_positions_only(4096)
            .unwrap();
        sim.plant.reset(&[0.3, 0.0]);
        let t0 = sim.t_ns;
        let mut x = [0.0; 2];
        sim.sample(t0 + 30_000_000, &mut x);
        let q = std::f64::consts::TAU / 4096.0;
        let true_angle = sim.plant.state()[0];
        assert!(
            x[1].is_nan() && (x[0] - true_angle).abs() <= q / 2.0,
            "{x:?}"
        );
        assert_eq!(x[0], (x[0] / q).round() * q);
    }

    /// Every simulated system's reset brake brings it to rest at each start state from a
    /// state away from it (moving), within 20 s of simulated time; the vertical arm is
    /// refused with the reason.
    #[test]
    fn the_reset_brake_settles_every_simulated_system() {
        for system in [
            SystemName::Pendulum,
            SystemName::ArmHorizontal,
            SystemName::Arm64,
            SystemName::DoubleIntegrator,
        ] {
            let mut sim = Simulated::new(system, 1.0).unwrap();
            let task = Task::new(system);
            let ts_ns = (task.ts * 1e9) as u64;
            let (n, m) = (task.state_dim(), task.action_dim());
            for x0 in &task.initial_states {
                // Half a unit off in every position, moving.
                let start: Vec<f64> = (0..n).map(|i| x0[i] + 0.5).collect();
                sim.plant.reset(&start);
                let mut t = sim.t_ns;
                let (mut rest, mut x) = (0, vec![0.0; n]);
                for _ in 0..(20.0 / task.ts) as usize {
                    sim.sample(t, &mut x);
                    rest = if sim.at_rest(&x, x0) { rest + 1 } else { 0 };
                    if rest == REST_SAMPLES {
                        break;
                    }
                    let (mut u, mut applied) = (vec![0.0; m], vec![0.0; m]);
                    sim.reset_action(&x, x0, &mut u);
                    task.saturate(&u, &mut applied);
                    sim.apply(t, &applied);
                    t += ts_ns;
                }
                assert_eq!(
                    rest, REST_SAMPLES,
                    "{system}: at {x:?}, not at rest at {x0:?}"
                );
            }
        }
        let e = Simulated::new(SystemName::ArmVertical, 1.0).err().unwrap();
        assert!(e.to_string().contains("gravity"), "{e}");
        assert!(Simulated::new(SystemName::Pendulum, 0.0).is_err());
    }
}
