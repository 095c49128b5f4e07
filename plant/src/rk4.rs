//! Fixed-step fourth-order Runge–Kutta integration with a zero-order-hold input.
//!
//! The thesis samples at `Ts` (30 ms for the pendulum) and holds the action over the
//! interval. [`crate::Simulation::substeps`] RK4 steps of `Ts / substeps` are taken per sample
//! (20 for the pendulum: 1.5 ms steps);
//! the choice is justified by the test `halving_the_substep_changes_little` in
//! [`crate::task`]: halving the sub-step changes a 3 s trajectory by less than 1e-6.

use crate::{Dynamics, MAX_STATE};

/// Advances `x` by one RK4 step of length `h` with the action `u` held constant.
pub fn step(f: &dyn Dynamics, x: &mut [f64], u: &[f64], h: f64) {
    let n = x.len();
    debug_assert!(n <= MAX_STATE);
    let mut k1 = [0.0; MAX_STATE];
    let mut k2 = [0.0; MAX_STATE];
    let mut k3 = [0.0; MAX_STATE];
    let mut k4 = [0.0; MAX_STATE];
    let mut tmp = [0.0; MAX_STATE];
    f.derivative(x, u, &mut k1[..n]);
    for i in 0..n {
        tmp[i] = x[i] + 0.5 * h * k1[i];
    }
    f.derivative(&tmp[..n], u, &mut k2[..n]);
    for i in 0..n {
        tmp[i] = x[i] + 0.5 * h * k2[i];
    }
    f.derivative(&tmp[..n], u, &mut k3[..n]);
    for i in 0..n {
        tmp[i] = x[i] + h * k3[i];
    }
    f.derivative(&tmp[..n], u, &mut k4[..n]);
    for i in 0..n {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}
