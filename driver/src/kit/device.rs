//! The hardware behind a driver, as the driver kit sees it: the [`Device`] trait that a
//! motor driver implements — read the sensors, apply an action, the reset brake — and
//! that [`crate::kit::serve`] runs the driver contract (`docs/driver.md`) for.

use plant::Task;

/// The hardware behind a driver (or a simulation of it). [`serve`](crate::kit::serve) calls it from one
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
    /// [`serve`](crate::kit::serve) only passes finite actions within the task's limits.
    fn apply(&mut self, t_ns: u64, u: &[f64]);

    /// During a reset, at a sample instant with state `x`: the action (to be clamped to
    /// the limits) that brings the device toward rest at `x0`.
    fn reset_action(&mut self, x: &[f64], x0: &[f64], u: &mut [f64]);

    /// Whether state `x` is at rest at `x0`, by the device's own tolerance; a reset is
    /// done after [`REST_SAMPLES`] such samples in a row.
    fn at_rest(&self, x: &[f64], x0: &[f64]) -> bool;

    /// Whether the device computes the reward and the trial's endings itself (a
    /// simulator with its own reward, such as a Gymnasium environment): the driver then
    /// advertises [`provides::REWARD`](crate::contract::provides::REWARD) and each
    /// sample that closes a period of a trial carries [`Device::outcome`]. Default: no,
    /// the rig computes the task's reward.
    fn provides_reward(&self) -> bool {
        false
    }

    /// With [`Device::provides_reward`]: the reward of the period that closed at the
    /// state just sampled, and how the trial ends there. Called once per such sample,
    /// right after [`Device::sample`].
    fn outcome(&mut self) -> Outcome {
        Outcome::default()
    }
}

/// What a period of a trial came to, by the device's own reward ([`Device::outcome`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outcome {
    /// The period's reward (finite: the rig refuses any other).
    pub reward: f64,
    /// [`ending`](crate::contract::ending) bits: 0 (the trial goes on),
    /// `TERMINATED` or `TRUNCATED`.
    pub ending: u64,
}

/// Consecutive samples at rest that end a reset.
pub const REST_SAMPLES: u32 = 3;
