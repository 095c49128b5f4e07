//! The reward `ρ(x, u)` with its gradients: the thesis's quadratic form and the terms a
//! task file may add to it ([`Term`]).
//!
//! `ρ(x, u) = −eᵀ Q e − uᵀ P u + Σ terms` with the error `e = x − x_r`, angle components
//! wrapped to [-π, π): Eq. 3.16 and 6.20 (pendulum, `x_r = 0`), Eq. 5.1 (arm, Case I)
//! and Eq. 5.2 (arm, Case II, reference `x_r`). Every weighting matrix in the thesis is
//! diagonal, so `Q` and `P` are stored as their diagonals; the thesis's tasks have no
//! other terms. MLAC (Eq. 3.9) and VGBP (Eq. 6.10) use `∂ρ/∂u` and `∂ρ/∂x`, derived
//! here from the terms' definitions: `−2 P u` and `−2 Q e` for the quadratic form, plus
//! each term's own ([`Term::add_grad_x`], [`Term::action_slope`]).

use crate::angle::wrap;

mod terms;

pub use terms::Term;

/// Bisection steps of [`Reward::best_action`]: the bracket of the action range halves
/// until it no longer shrinks in f64 (about 60 steps), at most this many.
const BISECTIONS: u32 = 200;

/// `ρ(x, u) = −eᵀ Q e − uᵀ P u + Σ terms`, `e = x − x_r` (angles wrapped).
#[derive(Clone, Debug, PartialEq)]
pub struct Reward {
    /// Diagonal of `Q` (state weights).
    pub q: Vec<f64>,
    /// Diagonal of `P` (action weights).
    pub p: Vec<f64>,
    /// Reference state `x_r` (zero for regulation tasks).
    pub reference: Vec<f64>,
    /// Diagonal of `Q_N`, the terminal reward's weights `τ_N(x) = −eᵀ Q_N e` (§4.4 uses
    /// `Q_N = Q`).
    pub terminal: Vec<f64>,
    /// Which state components are angles whose error is wrapped.
    pub angle_mask: Vec<bool>,
    /// The terms beyond the quadratic form, summed with it (none in the thesis's tasks).
    pub terms: Vec<Term>,
}

impl Reward {
    /// The error `e = x − x_r`, angle components wrapped (Eq. 5.2).
    #[inline]
    pub fn error(&self, x: &[f64], i: usize) -> f64 {
        let e = x[i] - self.reference[i];
        if self.angle_mask[i] { wrap(e) } else { e }
    }

    /// `ρ(x, u)`.
    pub fn reward(&self, x: &[f64], u: &[f64]) -> f64 {
        let mut r = self.weighted_error(&self.q, x);
        for j in 0..self.p.len() {
            r -= self.p[j] * u[j] * u[j];
        }
        for t in &self.terms {
            r += t.state_value(x) + t.action_value(u);
        }
        r
    }

    /// `ρ(x, 0)` less the action terms' value at zero (which is zero): the state part
    /// of `ρ`, `−eᵀ Q e` plus the state terms.
    pub fn state_reward(&self, x: &[f64]) -> f64 {
        let r = self.weighted_error(&self.q, x);
        self.terms.iter().fold(r, |r, t| r + t.state_value(x))
    }

    /// The terminal reward of a finite horizon, `τ_N(x) = −eᵀ Q_N e` (§4.4: `−xᵀQx`): the
    /// quadratic form's alone.
    pub fn terminal_reward(&self, x: &[f64]) -> f64 {
        self.weighted_error(&self.terminal, x)
    }

    /// `−eᵀ diag(w) e`.
    fn weighted_error(&self, w: &[f64], x: &[f64]) -> f64 {
        let mut r = 0.0;
        for i in 0..w.len() {
            let e = self.error(x, i);
            r -= w[i] * e * e;
        }
        r
    }

    /// Writes `∂ρ/∂u = −2 P u` plus the action terms' gradients into `out`.
    pub fn grad_u(&self, u: &[f64], out: &mut [f64]) {
        for j in 0..self.p.len() {
            out[j] = -2.0 * self.p[j] * u[j];
            for t in &self.terms {
                out[j] += t.action_slope(j, u[j]);
            }
        }
    }

    /// Writes `∂ρ/∂x = −2 Q e` plus the state terms' gradients into `out`.
    pub fn grad_x(&self, x: &[f64], out: &mut [f64]) {
        for i in 0..self.q.len() {
            out[i] = -2.0 * self.q[i] * self.error(x, i);
        }
        for t in &self.terms {
            t.add_grad_x(x, out);
        }
    }

    /// `∂ρ/∂u_j` at `u_j` (the reward is separable: the other components do not enter).
    fn action_slope(&self, j: usize, u_j: f64) -> f64 {
        let terms: f64 = self.terms.iter().map(|t| t.action_slope(j, u_j)).sum();
        -2.0 * self.p[j] * u_j + terms
    }

    /// The `u_j` that maximises `ρ_j(u_j) + slope · u_j`, the action part of `ρ` plus a
    /// linear gain — VGBP's action (Eq. 6.10: `−∂ρ/∂u = γ ∂V/∂x ∂f̂/∂u`, `slope` its
    /// right-hand side). With the quadratic form alone it is Eq. 6.21's closed form
    /// `½ slope / P_jj`, unbounded (the caller saturates it); with action terms, the
    /// root of the decreasing `∂ρ/∂u_j + slope` in `[low, high]` by bisection (`P_jj > 0`
    /// and every action term concave: the reward is strictly concave in `u_j`).
    pub fn best_action(&self, j: usize, slope: f64, low: f64, high: f64) -> f64 {
        if !self.terms.iter().any(Term::is_action_term) {
            return 0.5 * slope / self.p[j];
        }
        let h = |v: f64| self.action_slope(j, v) + slope;
        if h(low) <= 0.0 {
            return low;
        }
        if h(high) >= 0.0 {
            return high;
        }
        let (mut a, mut b) = (low, high);
        for _ in 0..BISECTIONS {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            if h(m) > 0.0 { a = m } else { b = m }
        }
        0.5 * (a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pendulum() -> Reward {
        Reward {
            q: vec![5.0, 0.1],
            p: vec![1.0],
            reference: vec![0.0, 0.0],
            terminal: vec![5.0, 0.1],
            angle_mask: vec![true, false],
            terms: Vec::new(),
        }
    }

    #[test]
    fn eq_3_16_values() {
        let r = pendulum();
        assert_eq!(r.reward(&[0.0, 0.0], &[0.0]), 0.0);
        let down = r.reward(&[std::f64::consts::PI, 0.0], &[3.0]);
        assert!((down - (-5.0 * std::f64::consts::PI.powi(2) - 9.0)).abs() < 1e-12);
    }

    #[test]
    fn gradients_match_finite_differences() {
        let r = Reward {
            q: vec![5.0, 5.0, 0.1, 0.1],
            p: vec![1.0, 1.0],
            reference: vec![1.1, -0.5, 0.0, 0.0],
            terminal: vec![5.0, 5.0, 0.1, 0.1],
            angle_mask: vec![true, true, false, false],
            terms: Vec::new(),
        };
        assert_gradients(&r, [-3.0, 1.0, 0.3, -0.2], [0.4, -1.2]);
    }

    /// `∂ρ/∂x` and `∂ρ/∂u` of `r` at `(x, u)` against central differences.
    fn assert_gradients(r: &Reward, x: [f64; 4], u: [f64; 2]) {
        let h = 1e-6;
        let mut gx = [0.0; 4];
        let mut gu = [0.0; 2];
        r.grad_x(&x, &mut gx);
        r.grad_u(&u, &mut gu);
        for i in 0..4 {
            let (mut a, mut b) = (x, x);
            a[i] += h;
            b[i] -= h;
            let fd = (r.reward(&a, &u) - r.reward(&b, &u)) / (2.0 * h);
            assert!((fd - gx[i]).abs() < 1e-5, "x{i}: {fd} vs {}", gx[i]);
        }
        for j in 0..2 {
            let (mut a, mut b) = (u, u);
            a[j] += h;
            b[j] -= h;
            let fd = (r.reward(&x, &a) - r.reward(&x, &b)) / (2.0 * h);
            assert!((fd - gu[j]).abs() < 1e-5, "u{j}: {fd} vs {}", gu[j]);
        }
    }

    #[test]
    fn case_ii_error_is_wrapped() {
        let r = Reward {
            q: vec![1.0, 0.0, 0.0, 0.0],
            p: vec![0.0, 0.0],
            reference: vec![3.0, 0.0, 0.0, 0.0],
            terminal: vec![1.0, 0.0, 0.0, 0.0],
            angle_mask: vec![true, true, false, false],
            terms: Vec::new(),
        };
        // -3 and 3 are 2π - 6 ≈ 0.283 apart on the circle, not 6.
        let e = r.error(&[-3.0, 0.0, 0.0, 0.0], 0);
        assert!((e - (2.0 * std::f64::consts::PI - 6.0)).abs() < 1e-12);
    }

    /// A reward with every kind of term: the quadratic form, 1 − cos on both angles, an
    /// absolute action cost and a goal bonus.
    fn every_term() -> Reward {
        use crate::region::Region;
        let angles = vec![true, true, false, false];
        Reward {
            q: vec![0.5, 0.0, 0.1, 0.1],
            p: vec![0.2, 1.0],
            reference: vec![1.1, -0.5, 0.0, 0.0],
            terminal: vec![0.5, 0.0, 0.1, 0.1],
            angle_mask: angles.clone(),
            terms: vec![
                Term::Cosine {
                    weights: vec![2.0, 3.0, 0.0, 0.0],
                    reference: vec![1.1, -0.5, 0.0, 0.0],
                },
                Term::AbsAction {
                    weights: vec![0.7, 0.1],
                },
                Term::Goal {
                    region: Region::Ball {
                        centre: vec![1.1, -0.5, 0.0, 0.0],
                        radius: vec![0.3, 0.3, f64::INFINITY, f64::INFINITY],
                    },
                    bonus: 4.0,
                    angles,
                },
            ],
        }
    }

    /// Each term's value by hand, and ∂ρ/∂x, ∂ρ/∂u of all of them against central
    /// differences, at states inside and outside the goal and actions of both signs.
    #[test]
    fn every_terms_gradient_matches_finite_differences() {
        let r = every_term();
        let (x, u) = ([1.2, -0.45, 0.3, -0.2], [0.4, -1.2]);
        let e = [0.1f64, 0.05, 0.3, -0.2];
        let quadratic =
            -(0.5 * e[0] * e[0] + 0.1 * e[2] * e[2] + 0.1 * e[3] * e[3]) - (0.2 * 0.16 + 1.44);
        let cosine = -(2.0 * (1.0 - e[0].cos()) + 3.0 * (1.0 - e[1].cos()));
        let want = quadratic + cosine - (0.7 * 0.4 + 0.1 * 1.2) + 4.0;
        assert!(
            (r.reward(&x, &u) - want).abs() < 1e-12,
            "{}",
            r.reward(&x, &u)
        );
        assert_eq!(r.state_reward(&x), r.reward(&x, &[0.0, 0.0]));
        assert_gradients(&r, x, u);
        assert_gradients(&r, [-3.0, 2.5, 0.3, -0.2], [-0.4, 1.2]);
    }

    /// VGBP's action maximises `−p u² − c |u| + s u`: the soft threshold
    /// `sign(s) max(|s| − c, 0) / 2p`, within the bounds; the quadratic form alone gives
    /// Eq. 6.21's `s / 2p`, unbounded.
    #[test]
    fn the_best_action_is_the_soft_threshold_with_an_absolute_cost() {
        let r = every_term();
        let (p, c) = (0.2, 0.7);
        for s in [-2.0, -0.71, -0.3, 0.0, 0.5, 0.9, 1.5] {
            let want = f64::signum(s) * (f64::abs(s) - c).max(0.0) / (2.0 * p);
            let got = r.best_action(0, s, -2.0, 2.0);
            assert!(
                (got - want.clamp(-2.0, 2.0)).abs() < 1e-9,
                "s = {s}: {got} vs {want}"
            );
        }
        let q = pendulum();
        assert_eq!(q.best_action(0, 9.0, -3.0, 3.0), 4.5);
    }
}
