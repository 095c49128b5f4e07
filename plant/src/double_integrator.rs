//! A linear double integrator `ẍ = u`, state `[p, v]`: with a quadratic reward its optimal
//! policy is the LQR gain, so learners can be checked against a Riccati solution.

use crate::Dynamics;

/// `ṗ = v`, `v̇ = u / mass`.
#[derive(Clone, Debug, PartialEq)]
pub struct DoubleIntegrator {
    /// Mass \[kg\] (the input is a force in N).
    pub mass: f64,
}

impl Default for DoubleIntegrator {
    fn default() -> Self {
        Self { mass: 1.0 }
    }
}

impl Dynamics for DoubleIntegrator {
    fn state_dim(&self) -> usize {
        2
    }
    fn action_dim(&self) -> usize {
        1
    }
    fn derivative(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = u[0] / self.mass;
    }
}
