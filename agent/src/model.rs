//! The learned process model `x' = f̂(x, u)` of MLAC and RMAC (§3.3.1, Algorithm 2
//! line 13), and of VGBP (Eq. 6.12).
//!
//! The approximator maps `[x, u]` to the state *increment* `x' − x` (angle components
//! wrapped), and the prediction is `x + Δx̂` wrapped. This is the same model — the
//! Jacobian `∂f̂/∂u = ∂Δx̂/∂u` is unchanged — but the regression target stays smooth when
//! the pendulum crosses ±π, where `x'` itself jumps by 2π.

use plant::angle::wrap;
use plant::{MAX_ACTION, MAX_STATE};

use crate::approx::{Differentiable, MAX_IN, MAX_OUT};

/// A learned process model around a differentiable approximator.
pub struct ProcessModel {
    f: Box<dyn Differentiable>,
    angle_mask: Vec<bool>,
    /// Learning rate `α_p` (zero for LLR, which learns by storing samples).
    rate: f64,
}

/// One model prediction: the next state and the input Jacobian `∂f̂/∂u`.
pub struct Prediction {
    /// Predicted next state `x̃' = f̂(x, u)`.
    pub x_next: [f64; MAX_STATE],
    /// `∂f̂/∂u`, row-major `n × m`.
    pub du: [f64; MAX_STATE * MAX_ACTION],
}

impl ProcessModel {
    /// A model learning with rate `α_p` into `f` (inputs `[x, u]`, outputs `Δx`).
    pub fn new(f: Box<dyn Differentiable>, angle_mask: Vec<bool>, rate: f64) -> Self {
        Self {
            f,
            angle_mask,
            rate,
        }
    }

    fn n(&self) -> usize {
        self.angle_mask.len()
    }

    fn input(&self, x: &[f64], u: &[f64]) -> [f64; MAX_IN] {
        let mut xu = [0.0; MAX_IN];
        xu[..x.len()].copy_from_slice(x);
        xu[x.len()..x.len() + u.len()].copy_from_slice(u);
        xu
    }

    /// `f̂(x, u)` and `∂f̂/∂u`.
    pub fn predict(&self, x: &[f64], u: &[f64]) -> Prediction {
        let (n, m) = (self.n(), u.len());
        let xu = self.input(x, u);
        let mut dx = [0.0; MAX_OUT];
        let mut jac = [0.0; MAX_OUT * MAX_IN];
        self.f
            .value_and_jacobian(&xu[..n + m], &mut dx[..n], &mut jac[..n * (n + m)]);
        let mut p = Prediction {
            x_next: [0.0; MAX_STATE],
            du: [0.0; MAX_STATE * MAX_ACTION],
        };
        for i in 0..n {
            let v = x[i] + dx[i];
            p.x_next[i] = if self.angle_mask[i] { wrap(v) } else { v };
            for j in 0..m {
                p.du[i * m + j] = jac[i * (n + m) + n + j];
            }
        }
        p
    }

    /// `(stored, capacity)` if the model is memory-based.
    pub fn fill(&self) -> Option<(usize, usize)> {
        self.f.fill()
    }

    /// Learns from the observed transition `(x, u) → x'`.
    pub fn learn(&mut self, x: &[f64], u: &[f64], x_next: &[f64]) {
        let n = self.n();
        let xu = self.input(x, u);
        let mut dx = [0.0; MAX_OUT];
        increment(&self.angle_mask, x, x_next, &mut dx[..n]);
        self.f.fit(&xu[..n + u.len()], &dx[..n], self.rate);
    }
}

/// `to − from`, angle components wrapped.
pub fn increment(angle_mask: &[bool], from: &[f64], to: &[f64], out: &mut [f64]) {
    for i in 0..out.len() {
        let d = to[i] - from[i];
        out[i] = if angle_mask[i] { wrap(d) } else { d };
    }
}
