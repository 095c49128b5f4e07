//! Least-squares temporal difference learning, LSTD(λ) (Boyan, 2002; §6.3.2,
//! Eq. 6.16–6.19), for a critic that is linear in its parameters: `V(x) = θᵀ φ(x)` with
//! the normalised RBFs `φ` of §3.5.1.
//!
//! ```text
//! z_k     = λγ z_{k−1} + φ(x_k)                        Eq. 6.16  (z_0 = φ(x_0))
//! A_{k+1} = A_k + z_k (φ(x_k) − γ φ(x_{k+1}))ᵀ          Eq. 6.17  (A_0 = a₀ I)
//! b_{k+1} = b_k + z_k r_{k+1}                            Eq. 6.18  (b_0 = 0)
//! θ       = A⁻¹ b                                        Eq. 6.19
//! ```
//!
//! `A` and `b` accumulate over the whole run; `θ` is solved at the end of every trial, as
//! in §6.4.1 ("updated at the end of every trial, which gives steadier behaviour") — so
//! within a trial the value function, and the policy read from it, stay fixed. There is
//! no learning rate. With `θ = 0` before the first solve and `b_0 = 0`, the initial value
//! function is 0: optimistic, since every reward is negative (§6.4.1). An optional prior
//! `θ_0` (`b_0 = A_0 θ_0`, [`crate::config::LstdPrior`]) draws rarely visited basis
//! functions towards `θ_0` instead.
//!
//! Cost: one rank-one update of the `p × p` matrix `A` per sample and one LU solve per
//! trial (`p = 400` on the pendulum: about 27 µs and 4 ms on this machine).

use nalgebra::{DMatrix, DVector};

use crate::approx::rbf::Rbf;
use crate::critic::{Critic, Next, ValueWithGradient};

/// An LSTD(λ) critic on a scalar RBF approximator.
pub struct Lstd {
    v: Rbf,
    a: DMatrix<f64>,
    b: DVector<f64>,
    z: DVector<f64>,
    /// `φ(x_k)`, then `φ(x_k) − γ φ(x_{k+1})`.
    phi: DVector<f64>,
    /// `φ(x_{k+1})`, reused as the next sample's `φ(x_k)` when the states match.
    phi_next: DVector<f64>,
    x_next: Vec<f64>,
    failed_solves: u64,
}

impl Lstd {
    /// LSTD on the basis functions of `v` (a scalar RBF approximator whose parameters
    /// become `θ`), with `A_0 = a0 · I` and `b_0 = A_0 θ_0`: `θ_0 = 0` (the thesis) or the
    /// given prior, which is then also `θ` until the first solve.
    ///
    /// # Panics
    /// If `v` is not scalar, `a0` is not positive (validated by the configuration), or
    /// the prior's length is not the number of basis functions.
    pub fn new(mut v: Rbf, a0: f64, prior: Option<Vec<f64>>) -> Self {
        use crate::approx::Approximator;
        assert_eq!(v.output_dim(), 1, "an LSTD critic is scalar");
        assert!(a0 > 0.0, "A_0 must be invertible");
        let p = v.len();
        let theta0 = prior.unwrap_or_else(|| vec![0.0; p]);
        assert_eq!(theta0.len(), p, "one prior value per basis function");
        v.parameters_mut().copy_from_slice(&theta0);
        Self {
            v,
            a: DMatrix::identity(p, p) * a0,
            b: DVector::from_vec(theta0) * a0,
            z: DVector::zeros(p),
            phi: DVector::zeros(p),
            phi_next: DVector::zeros(p),
            x_next: Vec::new(),
            failed_solves: 0,
        }
    }

    /// How many end-of-trial solves found `A` singular (and kept the previous `θ`).
    pub fn failed_solves(&self) -> u64 {
        self.failed_solves
    }

    fn value(&self, phi: &DVector<f64>) -> f64 {
        self.v
            .parameters()
            .iter()
            .zip(phi.iter())
            .map(|(t, f)| t * f)
            .sum()
    }
}

impl Critic for Lstd {
    fn function(&self) -> &ValueWithGradient {
        &self.v
    }

    fn start_trial(&mut self) {
        self.z.fill(0.0);
        self.x_next.clear();
    }

    fn observe(&mut self, x: &[f64], r: f64, next: Next, gamma: f64, lambda: f64) -> f64 {
        if self.x_next.as_slice() == x {
            std::mem::swap(&mut self.phi, &mut self.phi_next);
        } else {
            self.v.basis(x, self.phi.as_mut_slice());
        }
        self.x_next.clear();
        // A known terminal value enters as reward, with φ(x_{k+1}) = 0 (Eq. 4.3).
        let r = match next {
            Next::State(x_next) => {
                self.v.basis(x_next, self.phi_next.as_mut_slice());
                self.x_next.extend_from_slice(x_next);
                r
            }
            Next::Terminal(tau) => {
                self.phi_next.fill(0.0);
                r + gamma * tau
            }
        };
        // z_k = λγ z_{k−1} + φ(x_k)                                          (Eq. 6.16)
        self.z.axpy(1.0, &self.phi, lambda * gamma);
        let td = r + gamma * self.value(&self.phi_next) - self.value(&self.phi);
        // A ← A + z (φ(x_k) − γ φ(x_{k+1}))ᵀ,  b ← b + z r                   (Eq. 6.17–6.18)
        self.phi.axpy(-gamma, &self.phi_next, 1.0);
        self.a.ger(1.0, &self.z, &self.phi, 1.0);
        self.b.axpy(r, &self.z, 1.0);
        td
    }

    fn update(&mut self, _td: f64) {}

    fn end_trial(&mut self) {
        // θ = A⁻¹ b                                                          (Eq. 6.19)
        match self.a.clone().lu().solve(&self.b) {
            Some(theta) if theta.iter().all(|t| t.is_finite()) => {
                self.v.parameters_mut().copy_from_slice(theta.as_slice());
            }
            _ => self.failed_solves += 1,
        }
    }
}

use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

/// `A`, `b`, `z` and `θ` (in the RBF); the basis-function caches are recomputed.
impl Persist for Lstd {
    fn save(&self, s: &mut Snapshot) {
        s.scope("lstd", |s| {
            self.v.save(s);
            s.f64s("a", self.a.as_slice());
            s.f64s("b", self.b.as_slice());
            s.f64s("z", self.z.as_slice());
            s.u64s("failed_solves", &[self.failed_solves]);
        });
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.scope("lstd", |r| {
            self.v.restore(r)?;
            r.f64s_into("a", self.a.as_mut_slice())?;
            r.f64s_into("b", self.b.as_mut_slice())?;
            r.f64s_into("z", self.z.as_mut_slice())?;
            self.failed_solves = r.u64s("failed_solves")?.first().copied().unwrap_or(0);
            self.x_next.clear();
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::approx::rbf::RbfParams;
    use crate::approx::scalar;

    fn grid(centres: usize) -> Rbf {
        Rbf::new(&RbfParams {
            centres: vec![centres],
            range: vec![(0.0, 1.0)],
            periodic: vec![false],
            intersection: 0.5,
            outputs: 1,
            initial: 0.0,
            bounds: None,
        })
    }

    /// One hand-computed step: with a single basis function `φ ≡ 1`, one transition
    /// gives `A = a₀ + 1 − γ`, `b = r`, `θ = r / (a₀ + 1 − γ)`.
    #[test]
    fn one_transition_by_hand() {
        let mut c = Lstd::new(grid(1), 0.5, None);
        c.start_trial();
        let td = c.observe(&[0.2], -2.0, Next::State(&[0.7]), 0.9, 0.3);
        assert_eq!(td, -2.0, "θ = 0 before the first solve");
        assert_eq!(
            scalar(c.function(), &[0.5]),
            0.0,
            "θ fixed within the trial"
        );
        c.end_trial();
        let want = -2.0 / (0.5 + 1.0 - 0.9);
        assert!((scalar(c.function(), &[0.5]) - want).abs() < 1e-12);
    }

    /// With a prior `θ_0` (`b_0 = A_0 θ_0`): `θ = θ_0` before any data; one transition
    /// (φ ≡ 1) gives `A = a₀ + 1 − γ`, `b = a₀ θ_0 + r`.
    #[test]
    fn a_prior_is_theta_before_data_and_a_ridge_target_after() {
        let mut c = Lstd::new(grid(1), 0.5, Some(vec![-4.0]));
        assert_eq!(scalar(c.function(), &[0.5]), -4.0);
        c.start_trial();
        let td = c.observe(&[0.2], -2.0, Next::State(&[0.7]), 0.9, 0.3);
        assert!((td - (-2.0 + 0.9 * -4.0 + 4.0)).abs() < 1e-12);
        c.end_trial();
        let want = (0.5 * -4.0 + -2.0) / (0.5 + 1.0 - 0.9);
        assert!((scalar(c.function(), &[0.5]) - want).abs() < 1e-12);
    }

    /// A terminal transition (Eq. 4.3): `φ(x_{k+1}) = 0` and `τ_N` joins the reward, so
    /// `A = a₀ + 1`, `b = r + γ τ_N`.
    #[test]
    fn terminal_value_enters_as_reward() {
        let mut c = Lstd::new(grid(1), 0.5, None);
        c.start_trial();
        let td = c.observe(&[0.2], -2.0, Next::Terminal(-4.0), 0.9, 0.3);
        assert_eq!(td, -2.0 + 0.9 * -4.0);
        c.end_trial();
        let want = (-2.0 + 0.9 * -4.0) / (0.5 + 1.0);
        assert!((scalar(c.function(), &[0.5]) - want).abs() < 1e-12);
    }

    /// Two transitions with λ > 0: `z_1 = λγ φ + φ`, so (φ ≡ 1)
    /// `A = a₀ + (1 + (1 + λγ))(1 − γ)`, `b = r₁ + (1 + λγ) r₂`.
    #[test]
    fn traces_accumulate_within_a_trial() {
        let (g, l) = (0.9, 0.5);
        let mut c = Lstd::new(grid(1), 0.5, None);
        c.start_trial();
        c.observe(&[0.1], -1.0, Next::State(&[0.2]), g, l);
        c.observe(&[0.2], -3.0, Next::State(&[0.3]), g, l);
        c.end_trial();
        let a = 0.5 + (1.0 + (1.0 + l * g)) * (1.0 - g);
        let b = -1.0 + (1.0 + l * g) * -3.0;
        assert!((scalar(c.function(), &[0.0]) - b / a).abs() < 1e-12);
    }

    /// On a deterministic chain with constant reward the solution converges to the true
    /// value `r / (1 − γ)` (A_0's bias fades as samples accumulate).
    #[test]
    fn converges_to_the_value_of_a_constant_reward() {
        let g = 0.8;
        let mut c = Lstd::new(grid(5), 0.5, None);
        for _ in 0..200 {
            c.start_trial();
            for k in 0..20 {
                let x = (k % 5) as f64 / 4.0;
                let x2 = ((k + 1) % 5) as f64 / 4.0;
                c.observe(&[x], -1.0, Next::State(&[x2]), g, 0.3);
            }
            c.end_trial();
        }
        for x in [0.0, 0.3, 0.5, 1.0] {
            let v = scalar(c.function(), &[x]);
            assert!((v + 5.0).abs() < 0.02, "V({x}) = {v}, want −5");
        }
    }
}
