//! Quadratic rewards with their gradients.
//!
//! `ρ(x, u) = −eᵀ Q e − uᵀ P u` with the error `e = x − x_r`, angle components wrapped to
//! [-π, π): Eq. 3.16 and 6.20 (pendulum, `x_r = 0`), Eq. 5.1 (arm, Case I) and Eq. 5.2
//! (arm, Case II, reference `x_r`). Every weighting matrix in the thesis is diagonal, so
//! `Q` and `P` are stored as their diagonals. MLAC (Eq. 3.9) and VGBP (Eq. 6.10) use
//! `∂ρ/∂u = −2 P u` and `∂ρ/∂x = −2 Q e`.

use crate::angle::wrap;

/// `ρ(x, u) = −eᵀ Q e − uᵀ P u`, `e = x − x_r` (angles wrapped).
#[derive(Clone, Debug, PartialEq)]
pub struct QuadraticReward {
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
}

impl QuadraticReward {
    /// The error `e = x − x_r`, angle components wrapped (Eq. 5.2).
    #[inline]
    pub fn error(&self, x: &[f64], i: usize) -> f64 {
        let e = x[i] - self.reference[i];
        if self.angle_mask[i] { wrap(e) } else { e }
    }

    /// `ρ(x, u)`.
    pub fn reward(&self, x: &[f64], u: &[f64]) -> f64 {
        let mut r = self.state_reward(x);
        for j in 0..self.p.len() {
            r -= self.p[j] * u[j] * u[j];
        }
        r
    }

    /// `−eᵀ Q e`, the state part of `ρ`.
    pub fn state_reward(&self, x: &[f64]) -> f64 {
        self.weighted_error(&self.q, x)
    }

    /// The terminal reward of a finite horizon, `τ_N(x) = −eᵀ Q_N e` (§4.4: `−xᵀQx`).
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

    /// Writes `∂ρ/∂u = −2 P u` into `out`.
    pub fn grad_u(&self, u: &[f64], out: &mut [f64]) {
        for j in 0..self.p.len() {
            out[j] = -2.0 * self.p[j] * u[j];
        }
    }

    /// Writes `∂ρ/∂x = −2 Q e` into `out`.
    pub fn grad_x(&self, x: &[f64], out: &mut [f64]) {
        for i in 0..self.q.len() {
            out[i] = -2.0 * self.q[i] * self.error(x, i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pendulum() -> QuadraticReward {
        QuadraticReward {
            q: vec![5.0, 0.1],
            p: vec![1.0],
            reference: vec![0.0, 0.0],
            terminal: vec![5.0, 0.1],
            angle_mask: vec![true, false],
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
        let r = QuadraticReward {
            q: vec![5.0, 5.0, 0.1, 0.1],
            p: vec![1.0, 1.0],
            reference: vec![1.1, -0.5, 0.0, 0.0],
            terminal: vec![5.0, 5.0, 0.1, 0.1],
            angle_mask: vec![true, true, false, false],
        };
        let x = [-3.0, 1.0, 0.3, -0.2];
        let u = [0.4, -1.2];
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
            assert!((fd - gu[j]).abs() < 1e-5);
        }
    }

    #[test]
    fn case_ii_error_is_wrapped() {
        let r = QuadraticReward {
            q: vec![1.0, 0.0, 0.0, 0.0],
            p: vec![0.0, 0.0],
            reference: vec![3.0, 0.0, 0.0, 0.0],
            terminal: vec![1.0, 0.0, 0.0, 0.0],
            angle_mask: vec![true, true, false, false],
        };
        // -3 and 3 are 2π - 6 ≈ 0.283 apart on the circle, not 6.
        let e = r.error(&[-3.0, 0.0, 0.0, 0.0], 0);
        assert!((e - (2.0 * std::f64::consts::PI - 6.0)).abs() < 1e-12);
    }
}
