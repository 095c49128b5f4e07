//! A motor driver for the rig in Rust: the template for swapping the simulated plant
//! for real hardware (`docs/driver.md`).
//!
//! [`driver::serve`] does the driver contract — the clock, clamping and
//! rejection, the watchdog, resets, the iceoryx2 services; a driver only says how to read
//! its sensors, drive its actuator and brake to rest: one `impl Device`. Here the
//! "hardware" is the simulated pendulum ([`Simulated`]) behind a stand-in amplifier and
//! encoder; replace the bodies marked HARDWARE with your I/O.
//!
//! ```sh
//! cargo run --release -p driver --example motor_driver -- lab-pendulum  # the driver
//! rig check-driver --driver lab-pendulum                                # conformant?
//! rig run --plant external --driver lab-pendulum                        # learn on it
//! ```

use driver::{Device, Serving, Simulated, serve};
use plant::{SystemName, Task};

/// The pendulum's DC motor: an amplifier taking a voltage, an encoder giving the angle,
/// a velocity estimate.
struct Motor {
    /// HARDWARE: your amplifier and encoder handles; the simulation stands in for them.
    sim: Simulated,
}

impl Device for Motor {
    fn task(&self) -> &Task {
        // The thesis's pendulum task: Ts 30 ms, ±3 V (`rig check-driver` compares).
        self.sim.task()
    }

    fn sample(&mut self, t_ns: u64, x: &mut [f64]) {
        // HARDWARE: read the encoder (angle from upright, wrapped to [−π, π)) and the
        // velocity (a tachometer, or a filtered finite difference of the angle).
        self.sim.sample(t_ns, x);
    }

    fn apply(&mut self, t_ns: u64, u: &[f64]) {
        // HARDWARE: write u[0] volts to the amplifier. `serve` has clamped it to ±3 V,
        // rejected non-finite values and applies zero when actions stop.
        self.sim.apply(t_ns, u);
    }

    fn reset_action(&mut self, x: &[f64], x0: &[f64], u: &mut [f64]) {
        // Brake toward the start state (the bottom): a PD law on the measured state.
        self.sim.reset_action(x, x0, u);
    }

    fn at_rest(&self, x: &[f64], x0: &[f64]) -> bool {
        self.sim.at_rest(x, x0)
    }
}

fn main() -> anyhow::Result<()> {
    let id = std::env::args().nth(1).unwrap_or_else(|| "pendulum".into());
    let mut motor = Motor {
        sim: Simulated::new(SystemName::Pendulum, 1.0)?,
    };
    eprintln!("motor driver {id:?}: Ctrl-C to stop");
    let how = Serving {
        stop_after: None,
        spin_ns: 1_000_000,
        verbose: true,
    };
    let served = serve(&mut motor, &id, &how)?;
    eprintln!(
        "stopped after {} samples, {} periods missed",
        served.samples, served.missed
    );
    Ok(())
}
