//! [`Simulated`]: a built-in system of the plant crate as a [`Device`] — the pendulum of
//! Appendix A.1 (or an arm, the double integrator) integrated over the real elapsed
//! time, piecewise between action arrivals, as the Python example driver
//! (`examples/python_driver/`) does. `rig sim-driver` serves it;
//! `driver/examples/motor_driver.rs` shows the template for hardware.

use std::sync::Arc;

use plant::angle::wrap;
use plant::sensor::Sensor;
use plant::{Plant, SystemName, Task};
use wire::{MAX_U, now_ns};

use crate::Error;

use crate::kit::device::Device;
use crate::kit::serve::Lockstep;

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
    /// Served in lockstep ([`crate::kit::serve_lockstep`]): time passes only by
    /// [`Lockstep::step`], never with the wall clock.
    lockstep: bool,
}

impl Simulated {
    /// The reset brake's gains `(K_p, K_d)` for `system` (action units per position
    /// unit, and per velocity unit), or why it cannot be reset by one: the vertical arm's
    /// start state `[−1.1, 1, 0, 0]` needs 5.5 N m against gravity at joint 1, beyond the
    /// ±1 N m limit — a state it cannot rest in.
    pub fn brake_gains(system: SystemName) -> Result<(f64, f64), Error> {
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
            SystemName::ArmVertical => Err(Error::CannotRest),
        }
    }

    /// `system` at its first start state, running `speed` times faster than real time.
    pub fn new(system: SystemName, speed: f64) -> Result<Self, Error> {
        Self::of(Task::new(system), speed)
    }

    /// `task` (one with a built-in simulation: a task file's `[simulation]`) at its first
    /// start state, running `speed` times faster than real time.
    pub fn of(task: Task, speed: f64) -> Result<Self, Error> {
        let Some(sim) = &task.simulation else {
            return Err(Error::NoSimulation(task.name.clone()));
        };
        let gains = Self::brake_gains(sim.system)?;
        if !(speed.is_finite() && speed > 0.0 && speed <= 1000.0) {
            return Err(Error::Speed(speed));
        }
        Ok(Self {
            plant: Plant::new(Arc::new(task)),
            sensor: Sensor::Full,
            u: [0.0; MAX_U],
            t_ns: now_ns(),
            speed,
            gains,
            lockstep: false,
        })
    }

    /// For [`crate::kit::serve_lockstep`]: time passes one period per [`Lockstep::step`], not
    /// with the wall clock, and resets place the system at once.
    pub fn in_lockstep(mut self) -> Self {
        self.lockstep = true;
        self
    }

    /// Samples report the positions only, quantised to `counts_per_rev` counts per
    /// revolution (no noise), and NaN velocities.
    pub fn measuring_positions_only(mut self, counts_per_rev: u32) -> Result<Self, Error> {
        if counts_per_rev == 0 {
            return Err(Error::NoCounts);
        }
        let mask = &self.plant.task().angle_mask;
        self.sensor = Sensor::angle(mask, counts_per_rev, 0.0, 0);
        Ok(self)
    }

    /// Integrates up to monotonic time `t_ns` with the action in effect (in lockstep:
    /// nothing, [`Lockstep::step`] integrates).
    fn advance(&mut self, t_ns: u64) {
        if t_ns > self.t_ns && !self.lockstep {
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

impl Lockstep for Simulated {
    fn place(&mut self, x0: &[f64]) {
        self.plant.reset(x0);
    }

    /// [`Plant::step`]: the in-process plant's sample period, exactly.
    fn step(&mut self) {
        let m = self.plant.task().action_dim();
        self.plant.step(&self.u[..m]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kit::device::REST_SAMPLES;

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
