//! The inverted pendulum of Appendix A.1: a DC motor swinging a point mass.
//!
//! `J φ̈ = M g l sin φ − (b + K²/R) φ̇ + (K/R) u`, with φ measured from the upright
//! position, state `x = [φ, φ̇]`, input `u` in volts (Table A.1).

use crate::Dynamics;

/// Physical parameters of Table A.1.
#[derive(Clone, Debug, PartialEq)]
pub struct Pendulum {
    /// Pendulum inertia `J` \[kg m²\].
    pub inertia: f64,
    /// Pendulum mass `M` \[kg\].
    pub mass: f64,
    /// Gravity `g` \[m/s²\].
    pub gravity: f64,
    /// Pendulum length `l` \[m\].
    pub length: f64,
    /// Viscous damping `b` \[N m s/rad\].
    pub damping: f64,
    /// Torque constant `K` \[N m/A\].
    pub torque_constant: f64,
    /// Rotor resistance `R` \[Ω\].
    pub resistance: f64,
}

impl Default for Pendulum {
    /// Table A.1.
    fn default() -> Self {
        Self {
            inertia: 1.91e-4,
            mass: 5.50e-2,
            gravity: 9.81,
            length: 4.20e-2,
            damping: 3e-6,
            torque_constant: 5.36e-2,
            resistance: 9.50,
        }
    }
}

impl Pendulum {
    /// Total energy `½ J φ̇² + M g l cos φ` (zero potential at the horizontal), conserved
    /// when damping, back-EMF and input are zero.
    pub fn energy(&self, x: &[f64]) -> f64 {
        0.5 * self.inertia * x[1] * x[1] + self.mass * self.gravity * self.length * x[0].cos()
    }
}

impl Dynamics for Pendulum {
    fn state_dim(&self) -> usize {
        2
    }
    fn action_dim(&self) -> usize {
        1
    }
    fn derivative(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        let (phi, omega) = (x[0], x[1]);
        let k_r = self.torque_constant / self.resistance;
        dx[0] = omega;
        dx[1] = (self.mass * self.gravity * self.length * phi.sin()
            - (self.damping + self.torque_constant * k_r) * omega
            + k_r * u[0])
            / self.inertia;
    }
}
