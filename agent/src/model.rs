//! The learned process model `x' = f̂(x, u)` of MLAC and RMAC (§3.3.1, Algorithm 2
//! line 13), and of VGBP (Eq. 6.12).
//!
//! The approximator maps `[x, u]` to the state *increment* `x' − x` (angle components
//! wrapped), and the prediction is `x + Δx̂` wrapped. This is the same model — the
//! Jacobian `∂f̂/∂u = ∂Δx̂/∂u` is unchanged — but the regression target stays smooth when
//! the pendulum crosses ±π, where `x'` itself jumps by 2π.
//!
//! The model is time-invariant also for a finite horizon (footnote 2 of §4.2): given an
//! actor/critic input `(x, k)` ([`crate::horizon::Input`]) it reads the state part, and its
//! prediction is `(f̂(x, u), k + 1)` — the known dynamics of time, a discrete-time
//! integrator (§4.3.1) — so that the critic can be read at the predicted input. `∂f̂/∂u`
//! is that of the state part (time does not depend on the action).

use plant::angle::wrap;
use plant::{MAX_ACTION, MAX_STATE};

use crate::approx::{Differentiable, MAX_IN, MAX_OUT};

/// Which samples a memory-based model fits to ([`ProcessModel::evaluate`]).
#[derive(Clone, Copy)]
enum Neighbours {
    /// The nearest to `[x, u]`.
    Input,
    /// The nearest to `x`, found by a scan ([`Differentiable::value_and_jacobian_near`]).
    State,
    /// The nearest to `x`, found through an index and fitted nearest first
    /// ([`Differentiable::value_and_jacobian_near_indexed`]).
    StateIndexed,
}

/// A learned process model around a differentiable approximator.
pub struct ProcessModel {
    f: Box<dyn Differentiable>,
    angle_mask: Vec<bool>,
    /// Learning rate `α_p` (zero for LLR, which learns by storing samples).
    rate: f64,
}

/// One model prediction: the next state and the input Jacobian `∂f̂/∂u`.
pub struct Prediction {
    /// Predicted next state `x̃' = f̂(x, u)`, followed by `k + 1` if `x` carried time `k`.
    pub x_next: [f64; MAX_STATE],
    /// `∂f̂/∂u`, row-major `n × m`.
    pub du: [f64; MAX_STATE * MAX_ACTION],
}

/// The process model's affine fit around one point ([`ProcessModel::local_fit`]).
pub struct LocalFit {
    /// The predicted increment `Δx̂ = f̂(x, u) − x` (angle components unwrapped).
    pub dx: [f64; MAX_STATE],
    /// `∂Δx̂/∂x`, row-major `n × n`.
    pub dx_dx: [f64; MAX_STATE * MAX_STATE],
    /// `∂Δx̂/∂u`, row-major `n × m`.
    pub dx_du: [f64; MAX_STATE * MAX_ACTION],
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

    /// `[x, u]`, of the state part of `x`.
    fn input(&self, x: &[f64], u: &[f64]) -> [f64; MAX_IN] {
        let n = self.n();
        debug_assert!(
            x.len() == n || x.len() == n + 1,
            "a state, or a state and time"
        );
        let mut xu = [0.0; MAX_IN];
        xu[..n].copy_from_slice(&x[..n]);
        xu[n..n + u.len()].copy_from_slice(u);
        xu
    }

    /// `f̂(x, u)` and `∂f̂/∂u`; `x` may carry time `k` after the state, and the prediction
    /// then carries `k + 1`.
    pub fn predict(&self, x: &[f64], u: &[f64]) -> Prediction {
        self.predict_with(x, u, Neighbours::Input)
    }

    /// As [`Self::predict`], with an LLR model's neighbours chosen by the state alone,
    /// whatever `u`: "obtain X and Y from M^P for x_{k+1}" (Algorithm 7, line 12), before
    /// the action is known. Queried at one action instead (say `u = 0`), the neighbours
    /// all share that action wherever the policy has given it — as the first trial's
    /// does everywhere, `∂V/∂x` being zero — the local fit has no slope along `u`
    /// (`∂f̂/∂u = 0`, the smallest-norm solution of §3.5.2), and Eq. 6.21 answers `u = 0`
    /// again: the greedy policy can stay at the start state until those samples leave
    /// the memory.
    pub fn predict_near_state(&self, x: &[f64], u: &[f64]) -> Prediction {
        self.predict_with(x, u, Neighbours::State)
    }

    /// `Δx̂` and `∂Δx̂/∂[x, u]` (row-major `n × (n + m)`) at `(x, u)`, a memory-based
    /// model fitted to the neighbours `near`.
    fn evaluate(
        &self,
        x: &[f64],
        u: &[f64],
        near: Neighbours,
    ) -> ([f64; MAX_OUT], [f64; MAX_OUT * MAX_IN]) {
        let (n, m) = (self.n(), u.len());
        let xu = self.input(x, u);
        let mut dx = [0.0; MAX_OUT];
        let mut jac = [0.0; MAX_OUT * MAX_IN];
        let (y, j) = (&mut dx[..n], &mut jac[..n * (n + m)]);
        let xu = &xu[..n + m];
        match near {
            Neighbours::Input => self.f.value_and_jacobian(xu, y, j),
            Neighbours::State => self.f.value_and_jacobian_near(xu, n, y, j),
            Neighbours::StateIndexed => self.f.value_and_jacobian_near_indexed(xu, n, y, j),
        }
        (dx, jac)
    }

    fn predict_with(&self, x: &[f64], u: &[f64], near: Neighbours) -> Prediction {
        let (n, m) = (self.n(), u.len());
        let (dx, jac) = self.evaluate(x, u, near);
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
        if let Some(&k) = x.get(n) {
            p.x_next[n] = k + 1.0;
        }
        p
    }

    /// The model's affine fit around `(x, u)`, its neighbours chosen by the state (as
    /// [`Self::predict_near_state`], found through the memory's index of the states and
    /// fitted nearest first: [`Differentiable::value_and_jacobian_near_indexed`]): the
    /// increment `Δx̂ = f̂(x, u) − x` and its Jacobians `∂Δx̂/∂x` (`n × n`) and `∂Δx̂/∂u`
    /// (`n × m`), row-major, of the state part of `x`.
    pub fn local_fit(&self, x: &[f64], u: &[f64]) -> LocalFit {
        let (n, m) = (self.n(), u.len());
        let (dx, jac) = self.evaluate(x, u, Neighbours::StateIndexed);
        let mut fit = LocalFit {
            dx: [0.0; MAX_STATE],
            dx_dx: [0.0; MAX_STATE * MAX_STATE],
            dx_du: [0.0; MAX_STATE * MAX_ACTION],
        };
        fit.dx[..n].copy_from_slice(&dx[..n]);
        for i in 0..n {
            let row = &jac[i * (n + m)..(i + 1) * (n + m)];
            fit.dx_dx[i * n..(i + 1) * n].copy_from_slice(&row[..n]);
            fit.dx_du[i * m..(i + 1) * m].copy_from_slice(&row[n..]);
        }
        fit
    }

    /// `(stored, capacity)` if the model is memory-based.
    pub fn fill(&self) -> Option<(usize, usize)> {
        self.f.fill()
    }

    /// Learns from the observed transition `(x, u) → x'` (of their state parts, if they
    /// carry time).
    pub fn learn(&mut self, x: &[f64], u: &[f64], x_next: &[f64]) {
        let n = self.n();
        let xu = self.input(x, u);
        let mut dx = [0.0; MAX_OUT];
        increment(&self.angle_mask, x, x_next, &mut dx[..n]);
        self.f.fit(&xu[..n + u.len()], &dx[..n], self.rate);
    }
}

/// `to − from` of the first `out.len()` components (the state part, if `from` and `to`
/// carry time), angle components wrapped.
pub fn increment(angle_mask: &[bool], from: &[f64], to: &[f64], out: &mut [f64]) {
    for i in 0..out.len() {
        let d = to[i] - from[i];
        out[i] = if angle_mask[i] { wrap(d) } else { d };
    }
}

use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

impl Persist for ProcessModel {
    fn save(&self, s: &mut Snapshot) {
        s.scope("model", |s| self.f.save(s));
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.scope("model", |r| self.f.restore(r))
    }
}

#[cfg(test)]
mod tests {
    use super::ProcessModel;
    use crate::approx::llr::{Eviction, Llr, LlrParams, Search};
    use crate::testing;

    /// Given `(x, k)` the model predicts from the state part and advances time by one.
    #[test]
    fn a_prediction_carries_time() {
        let model = testing::model(0.5);
        let p = model.predict(&[0.2], &[1.0]);
        assert_eq!((p.x_next[0], p.x_next[1], p.du[0]), (0.7, 0.0, 0.5));
        let p = model.predict(&[0.2, 3.0], &[1.0]);
        assert_eq!((p.x_next[0], p.x_next[1], p.du[0]), (0.7, 4.0, 0.5));
    }

    /// An LLR model of `x' = x + 0.5 u` whose samples near `x = 0.3` were all taken with
    /// `u = 0` but one, taken with `u = 2` (as after a first trial in which the policy gave
    /// `u = 0` and exploration acted once). Queried at `(x, u = 0)` its neighbours (K = 3)
    /// are the `u = 0` samples and `∂f̂/∂u = 0`, so VGBP's Eq. 6.21 would give `u = 0`
    /// again; with the neighbours chosen by the state (Algorithm 7 line 12)
    /// `∂f̂/∂u = 0.5`, the true input gain.
    #[test]
    fn near_the_state_the_input_gain_is_found() {
        let llr = Llr::new(&LlrParams {
            memory: 10,
            neighbours: 3,
            weights: vec![1.0, 1.0],
            periodic: vec![false, false],
            outputs: 1,
            bounds: None,
            eviction: Eviction::Oldest,
            search: Search::KdTree,
            clip_to_neighbours: false,
        });
        let mut model = ProcessModel::new(Box::new(llr), vec![false], 0.0);
        for (x, u) in [(0.31, 0.0), (0.29, 0.0), (0.3, 2.0), (0.3, 0.0)] {
            model.learn(&[x], &[u], &[x + 0.5 * u]);
        }
        assert_eq!(model.predict(&[0.3], &[0.0]).du[0], 0.0);
        let p = model.predict_near_state(&[0.3], &[0.0]);
        assert!((p.du[0] - 0.5).abs() < 1e-6, "∂f̂/∂u = {}", p.du[0]);
        assert!((p.x_next[0] - 0.3).abs() < 1e-6);
    }
}
