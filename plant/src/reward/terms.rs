//! Reward terms beyond the quadratic form, each with its value and its analytic
//! gradient. Every term depends on the state alone or on the action alone, component by
//! component, so that the reward stays separable, `ρ(x, u) = ρ_x(x) + Σ_j ρ_j(u_j)`, as
//! VGBP's closed-form action assumes (Eq. 6.10, [`super::Reward::best_action`]).

use crate::region::Region;

/// One term of `ρ(x, u)` beyond the quadratic form.
#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    /// `−Σ_i w_i (1 − cos(x_i − x_r,i))`: a periodic cost of angles, flat far from the
    /// reference where the quadratic form is steep (Gymnasium's Acrobot, Doya 2000's
    /// pendulum).
    Cosine {
        /// `w_i ≥ 0` per state component (0 for those that are not angles).
        weights: Vec<f64>,
        /// The reference `x_r`.
        reference: Vec<f64>,
    },
    /// `bonus` for every sample whose state lies in `region`: a goal worth reaching and
    /// staying in. Its gradient is zero (wherever it is defined).
    Goal {
        /// Where the bonus is paid.
        region: Region,
        /// The reward per sample inside.
        bonus: f64,
        /// Which state components are angles.
        angles: Vec<bool>,
    },
    /// `−Σ_j c_j |u_j|`: an action cost proportional to the action's size (a motor's
    /// current, a thruster's fuel), beside the quadratic `uᵀ P u`.
    AbsAction {
        /// `c_j ≥ 0` per action component.
        weights: Vec<f64>,
    },
}

impl Term {
    /// The term's value at state `x` (0 for an action term).
    pub fn state_value(&self, x: &[f64]) -> f64 {
        match self {
            Term::Cosine { weights, reference } => -weights
                .iter()
                .zip(x.iter().zip(reference))
                .map(|(w, (xi, ri))| w * (1.0 - (xi - ri).cos()))
                .sum::<f64>(),
            Term::Goal {
                region,
                bonus,
                angles,
            } => {
                if region.contains(x, angles) {
                    *bonus
                } else {
                    0.0
                }
            }
            Term::AbsAction { .. } => 0.0,
        }
    }

    /// The term's value at action `u` (0 for a state term).
    pub fn action_value(&self, u: &[f64]) -> f64 {
        match self {
            Term::AbsAction { weights } => -weights
                .iter()
                .zip(u)
                .map(|(c, uj)| c * uj.abs())
                .sum::<f64>(),
            _ => 0.0,
        }
    }

    /// Adds `∂/∂x` of the term at `x` to `out`.
    pub fn add_grad_x(&self, x: &[f64], out: &mut [f64]) {
        if let Term::Cosine { weights, reference } = self {
            for i in 0..weights.len() {
                out[i] -= weights[i] * (x[i] - reference[i]).sin();
            }
        }
    }

    /// `∂/∂u_j` of the term at `u_j` (`−c_j sign(u_j)`, 0 at `u_j = 0`, for
    /// [`Term::AbsAction`]; 0 for a state term).
    pub fn action_slope(&self, j: usize, u_j: f64) -> f64 {
        match self {
            Term::AbsAction { weights } if u_j != 0.0 => -weights[j] * u_j.signum(),
            _ => 0.0,
        }
    }

    /// Whether the term depends on the action.
    pub fn is_action_term(&self) -> bool {
        matches!(self, Term::AbsAction { .. })
    }

    /// Appends the term's canonical bytes to `b` (the task's hash): a tag byte — 1
    /// cosine, 2 absolute action cost, 3 goal bonus — then its numbers as little-endian
    /// `f64` (the goal: its region, [`Region::digest`], then the bonus).
    pub fn digest(&self, b: &mut Vec<u8>) {
        let nums = |b: &mut Vec<u8>, v: &[f64]| {
            v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()))
        };
        match self {
            Term::Cosine { weights, .. } => {
                b.push(1);
                nums(b, weights);
            }
            Term::AbsAction { weights } => {
                b.push(2);
                nums(b, weights);
            }
            Term::Goal { region, bonus, .. } => {
                b.push(3);
                region.digest(b);
                nums(b, &[*bonus]);
            }
        }
    }
}
