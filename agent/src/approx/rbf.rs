//! Normalised Gaussian radial basis functions on a grid (§3.5.1):
//! `V(x) = θᵀ φ(x)`, `φᵢ = φ̃ᵢ / Σⱼ φ̃ⱼ` (Eq. 3.12), `φ̃ᵢ = exp(−½ (x−cᵢ)ᵀ B⁻¹ (x−cᵢ))`
//! (Eq. 3.13), with the analytic gradient
//! `∇φᵢ = −φᵢ [B⁻¹(x−cᵢ) + Σⱼ∇φ̃ⱼ / Σⱼφ̃ⱼ]` (§3.5.1, Eq. 6.15).
//!
//! **Centres**: an equidistant grid over the task's state range; along a periodic (angle)
//! axis the `c` centres are spaced `2π / c` apart and `x − cᵢ` is wrapped, so the
//! approximation is continuous across ±π.
//!
//! **Widths from the "intersection"** of Table 3.1 (and §6.4.1: "the value of the
//! non-normalised BF is 0.5 at the point where neighbouring BFs intersect"): two
//! neighbouring Gaussians a spacing `Δ` apart intersect halfway, so
//! `exp(−½ (Δ/2)² / b) = h`, i.e. `b = Δ² / (−8 ln h)` on the diagonal of `B`.
//!
//! **Bounded outputs** (an actor's action bounds): the value is saturated, and
//! [`Approximator::shift`] first cuts its step so that the saturated value at `x` plus
//! the step stays within the bounds — the counterpart of §3.5.2's saturating the actor memory's outputs
//! "directly after the update". Without it, SAC (Eq. 3.1) drives the parameters of a
//! saturated actor without limit: only exploration pointing *into* the action range
//! survives saturation (`Δu = sat(π + Δu) − π`), and the mostly negative TD errors of an
//! optimistically initialised critic then push `π` ever further out, leaving a policy
//! stuck at ±3 V (`rig learn --algo sac --approx rbf`, 30 runs: last three greedy
//! evaluations −3256 → −830). MLAC is unaffected (−861 → −857): its gradient pulls a
//! saturated action back in through `∇_u ρ`.
//!
//! `B` is diagonal, so `φ̃` is a product of one-dimensional factors and `Σⱼ φ̃ⱼ` a
//! product of one-dimensional sums: an evaluation costs one exponential per centre
//! coordinate, not per centre.

use super::{Approximator, Differentiable, MAX_IN, MAX_OUT, Traced};

/// Grid and width of an RBF approximator.
#[derive(Clone, Debug, PartialEq)]
pub struct RbfParams {
    /// Number of centres along each input.
    pub centres: Vec<usize>,
    /// Input range covered, `(low, high)` per input.
    pub range: Vec<(f64, f64)>,
    /// Which inputs are angles (periodic grid).
    pub periodic: Vec<bool>,
    /// Intersection height `h ∈ (0, 1)` of neighbouring basis functions.
    pub intersection: f64,
    /// Output dimension.
    pub outputs: usize,
    /// Initial value of every parameter.
    pub initial: f64,
    /// Optional output bounds: the value is saturated, and shifts stop at the bounds.
    pub bounds: Option<(Vec<f64>, Vec<f64>)>,
}

/// A normalised RBF approximator.
pub struct Rbf {
    n: usize,
    m: usize,
    counts: Vec<usize>,
    centres: Vec<Vec<f64>>,
    /// Diagonal of `B⁻¹`.
    inv_b: Vec<f64>,
    period: Vec<f64>,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    /// Parameters, `m` per basis function.
    theta: Vec<f64>,
    trace: Vec<f64>,
}

/// Per-axis factors of one evaluation.
struct Axes {
    /// `g[j][i]`: one-dimensional Gaussian of axis `j` at centre `i`.
    g: Vec<Vec<f64>>,
    /// `B⁻¹ (x − c)` per axis and centre.
    r: Vec<Vec<f64>>,
}

impl Rbf {
    /// A grid of normalised RBFs with all parameters at `initial`.
    ///
    /// # Panics
    /// On inconsistent parameters (validated beforehand by the configuration).
    pub fn new(p: &RbfParams) -> Self {
        let n = p.centres.len();
        assert!((1..=MAX_IN).contains(&n) && p.range.len() == n && p.periodic.len() == n);
        assert!(p.intersection > 0.0 && p.intersection < 1.0);
        let mut centres = Vec::new();
        let mut inv_b = Vec::new();
        let mut period = Vec::new();
        for j in 0..n {
            let (lo, hi) = p.range[j];
            let c = p.centres[j].max(1);
            let (spacing, cs): (f64, Vec<f64>) = if p.periodic[j] {
                let d = (hi - lo) / c as f64;
                (d, (0..c).map(|i| lo + i as f64 * d).collect())
            } else if c == 1 {
                (hi - lo, vec![0.5 * (lo + hi)])
            } else {
                let d = (hi - lo) / (c - 1) as f64;
                (d, (0..c).map(|i| lo + i as f64 * d).collect())
            };
            let b = spacing * spacing / (-8.0 * p.intersection.ln());
            centres.push(cs);
            inv_b.push(1.0 / b);
            period.push(if p.periodic[j] { hi - lo } else { 0.0 });
        }
        let total: usize = p.centres.iter().product();
        Self {
            n,
            m: p.outputs,
            counts: p.centres.clone(),
            centres,
            inv_b,
            period,
            bounds: p.bounds.clone(),
            theta: vec![p.initial; total * p.outputs],
            trace: vec![0.0; total],
        }
    }

    /// Number of basis functions.
    pub fn len(&self) -> usize {
        self.trace.len()
    }

    /// Whether there are no basis functions (never: at least one per axis).
    pub fn is_empty(&self) -> bool {
        self.trace.is_empty()
    }

    /// Writes the normalised basis functions `φ(x)` (Eq. 3.12) into `phi`, one entry per
    /// basis function — the feature vector of LSTD (Eq. 6.16) and SARSA (Eq. 6.4).
    pub fn basis(&self, x: &[f64], phi: &mut [f64]) {
        self.features(x, |i, v, _| phi[i] = v);
    }

    /// The parameters `θ`, `m` per basis function (`θ[i·m + o]` weighs `φᵢ` in output `o`).
    pub fn parameters(&self) -> &[f64] {
        &self.theta
    }

    /// The parameters, for learners that set them directly (LSTD, Eq. 6.19; SARSA,
    /// Eq. 6.5).
    pub fn parameters_mut(&mut self) -> &mut [f64] {
        &mut self.theta
    }

    fn axes(&self, x: &[f64]) -> Axes {
        let mut g = Vec::with_capacity(self.n);
        let mut r = Vec::with_capacity(self.n);
        for ((cs, &xj), (&p, &inv_b)) in self
            .centres
            .iter()
            .zip(x)
            .zip(self.period.iter().zip(&self.inv_b))
        {
            let (gj, rj): (Vec<f64>, Vec<f64>) = cs
                .iter()
                .map(|&c| {
                    let mut d = xj - c;
                    if p > 0.0 {
                        d -= p * (d / p).round();
                    }
                    ((-0.5 * d * d * inv_b).exp(), d * inv_b)
                })
                .unzip();
            g.push(gj);
            r.push(rj);
        }
        Axes { g, r }
    }

    /// Calls `visit(i, φᵢ(x))` for every basis function, plus returns the per-axis
    /// factors for gradients.
    fn features(&self, x: &[f64], mut visit: impl FnMut(usize, f64, &[usize])) -> Axes {
        let axes = self.axes(x);
        // Normalisation: Σ φ̃ = Π_j Σ_i g_j[i]; guard against underflow far outside.
        let norm: f64 = axes
            .g
            .iter()
            .map(|g| g.iter().sum::<f64>().max(f64::MIN_POSITIVE))
            .product();
        let mut idx = [0usize; MAX_IN];
        for i in 0..self.trace.len() {
            let mut v = 1.0;
            for (g, &i) in axes.g.iter().zip(&idx[..self.n]) {
                v *= g[i];
            }
            visit(i, v / norm, &idx[..self.n]);
            for j in (0..self.n).rev() {
                idx[j] += 1;
                if idx[j] < self.counts[j] {
                    break;
                }
                idx[j] = 0;
            }
        }
        axes
    }

    /// `step`, cut so that the saturated value at `x` plus the step stays within the
    /// output bounds.
    fn saturated_step(&self, x: &[f64], step: &[f64]) -> [f64; MAX_OUT] {
        let mut s = [0.0; MAX_OUT];
        s[..self.m].copy_from_slice(&step[..self.m]);
        if let Some((lo, hi)) = &self.bounds {
            let mut y = [0.0; MAX_OUT];
            self.value(x, &mut y[..self.m]);
            for o in 0..self.m {
                s[o] = (y[o] + step[o]).clamp(lo[o], hi[o]) - y[o];
            }
        }
        s
    }

    fn clamp(&self, y: &mut [f64]) {
        if let Some((lo, hi)) = &self.bounds {
            for o in 0..y.len() {
                y[o] = y[o].clamp(lo[o], hi[o]);
            }
        }
    }
}

impl Approximator for Rbf {
    fn input_dim(&self) -> usize {
        self.n
    }
    fn output_dim(&self) -> usize {
        self.m
    }
    fn value(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let m = self.m;
        self.features(x, |i, phi, _| {
            for (y, t) in y.iter_mut().zip(&self.theta[i * m..(i + 1) * m]) {
                *y += t * phi;
            }
        });
        self.clamp(y);
    }
    fn shift(&mut self, x: &[f64], step: &[f64]) {
        let step = &self.saturated_step(x, step);
        let mut phis = Vec::with_capacity(self.trace.len());
        self.features(x, |_, phi, _| phis.push(phi));
        for (i, phi) in phis.into_iter().enumerate() {
            for (t, s) in self.theta[i * self.m..(i + 1) * self.m]
                .iter_mut()
                .zip(step)
            {
                *t += s * phi;
            }
        }
    }
    fn fit(&mut self, x: &[f64], target: &[f64], rate: f64) {
        let mut y = [0.0; MAX_OUT];
        // The error is taken on the unbounded value, as a gradient step should.
        let bounds = self.bounds.take();
        self.value(x, &mut y[..self.m]);
        self.bounds = bounds;
        let mut step = [0.0; MAX_OUT];
        for o in 0..self.m {
            step[o] = rate * (target[o] - y[o]);
        }
        let m = self.m;
        self.shift(x, &step[..m]);
    }
}

impl Differentiable for Rbf {
    fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]) {
        let (n, m) = (self.n, self.m);
        // First pass: value and Σᵢ φᵢ rᵢ per axis is separable: Σ_i φ_i r_j[i_j] equals
        // Σ_i g_j[i] r_j[i] / Σ_i g_j[i].
        y.fill(0.0);
        jac.fill(0.0);
        let axes = self.axes(x);
        let mean_r: Vec<f64> = (0..n)
            .map(|j| {
                let s: f64 = axes.g[j].iter().sum::<f64>().max(f64::MIN_POSITIVE);
                axes.g[j]
                    .iter()
                    .zip(&axes.r[j])
                    .map(|(g, r)| g * r)
                    .sum::<f64>()
                    / s
            })
            .collect();
        self.features(x, |i, phi, idx| {
            for o in 0..m {
                let t = self.theta[i * m + o];
                y[o] += t * phi;
                for j in 0..n {
                    // ∂φᵢ/∂x_j = −φᵢ (r_j[i_j] − mean_r_j)
                    jac[o * n + j] -= t * phi * (axes.r[j][idx[j]] - mean_r[j]);
                }
            }
        });
        if let Some((lo, hi)) = &self.bounds {
            for o in 0..m {
                if y[o] <= lo[o] || y[o] >= hi[o] {
                    jac[o * n..(o + 1) * n].fill(0.0);
                }
            }
        }
        self.clamp(y);
    }
}

impl Traced for Rbf {
    fn visit(&mut self, x: &[f64], decay: f64) {
        for z in &mut self.trace {
            *z *= decay;
        }
        let mut phis = Vec::with_capacity(self.trace.len());
        self.features(x, |_, phi, _| phis.push(phi));
        for (z, phi) in self.trace.iter_mut().zip(phis) {
            *z += phi;
        }
    }
    fn apply_td(&mut self, step: f64) {
        super::linear_td_step(&mut self.theta, &self.trace, step);
    }
    fn clear_traces(&mut self) {
        self.trace.fill(0.0);
    }
}

use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

impl Persist for Rbf {
    fn save(&self, s: &mut Snapshot) {
        s.scope("rbf", |s| {
            s.f64s("theta", &self.theta);
            s.f64s("trace", &self.trace);
        });
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.scope("rbf", |r| {
            r.f64s_into("theta", &mut self.theta)?;
            r.f64s_into("trace", &mut self.trace)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    fn pendulum_rbf(outputs: usize) -> Rbf {
        let mut rbf = Rbf::new(&RbfParams {
            centres: vec![15, 10],
            range: vec![(-PI, PI), (-8.0 * PI, 8.0 * PI)],
            periodic: vec![true, false],
            intersection: 0.7,
            outputs,
            initial: 0.0,
            bounds: None,
        });
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for t in &mut rbf.theta {
            *t = rng.random_range(-10.0..10.0);
        }
        rbf
    }

    #[test]
    fn features_are_normalised() {
        let rbf = pendulum_rbf(1);
        let mut sum = 0.0;
        rbf.features(&[0.3, -4.0], |_, phi, _| sum += phi);
        assert!((sum - 1.0).abs() < 1e-12);
    }

    #[test]
    fn gradient_equals_finite_difference() {
        let rbf = pendulum_rbf(2);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..100 {
            let x = [rng.random_range(-PI..PI), rng.random_range(-30.0..30.0)];
            let (mut y, mut jac) = ([0.0; 2], [0.0; 4]);
            rbf.value_and_jacobian(&x, &mut y, &mut jac);
            let mut y0 = [0.0; 2];
            rbf.value(&x, &mut y0);
            assert_eq!(y, y0);
            for j in 0..2 {
                let h = 1e-6 * (1.0 + x[j].abs());
                let (mut a, mut b) = (x, x);
                a[j] += h;
                b[j] -= h;
                let (mut ya, mut yb) = ([0.0; 2], [0.0; 2]);
                rbf.value(&a, &mut ya);
                rbf.value(&b, &mut yb);
                for o in 0..2 {
                    let fd = (ya[o] - yb[o]) / (2.0 * h);
                    let an = jac[o * 2 + j];
                    assert!(
                        (fd - an).abs() < 1e-5 * (1.0 + an.abs()),
                        "∂y{o}/∂x{j}: fd {fd} analytic {an}"
                    );
                }
            }
        }
    }

    #[test]
    fn continuous_across_the_angle_wrap() {
        let rbf = pendulum_rbf(1);
        let (mut a, mut b) = ([0.0], [0.0]);
        rbf.value(&[PI - 1e-9, 2.0], &mut a);
        rbf.value(&[-PI + 1e-9, 2.0], &mut b);
        assert!((a[0] - b[0]).abs() < 1e-6);
    }

    #[test]
    fn intersection_sets_the_width() {
        let rbf = Rbf::new(&RbfParams {
            centres: vec![5],
            range: vec![(0.0, 4.0)],
            periodic: vec![false],
            intersection: 0.5,
            outputs: 1,
            initial: 0.0,
            bounds: None,
        });
        // Midway between centres 1 and 2 the non-normalised Gaussians are both 0.5.
        let axes = rbf.axes(&[1.5]);
        assert!((axes.g[0][1] - 0.5).abs() < 1e-12 && (axes.g[0][2] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn shift_stops_at_the_output_bounds() {
        let mut rbf = Rbf::new(&RbfParams {
            centres: vec![15, 10],
            range: vec![(-PI, PI), (-8.0 * PI, 8.0 * PI)],
            periodic: vec![true, false],
            intersection: 0.9,
            outputs: 1,
            initial: 0.0,
            bounds: Some((vec![-3.0], vec![3.0])),
        });
        let x = [0.5, 1.0];
        let raw = |rbf: &mut Rbf| {
            let bounds = rbf.bounds.take();
            let v = super::super::scalar(&*rbf, &x);
            rbf.bounds = bounds;
            v
        };
        // Pushing outwards approaches the bound but never crosses it...
        for _ in 0..2000 {
            rbf.shift(&x, &[-2.0]);
            assert!(raw(&mut rbf) >= -3.0 - 1e-12);
        }
        assert!(raw(&mut rbf) < -3.0 + 1e-6);
        // ...so a step back in takes effect at once.
        rbf.shift(&x, &[1.0]);
        assert!(super::super::scalar(&rbf, &x) > -3.0 + 0.01);
    }

    #[test]
    fn fit_converges_to_a_constant_target() {
        let mut rbf = pendulum_rbf(1);
        for _ in 0..200 {
            rbf.fit(&[1.0, 2.0], &[5.0], 0.5);
        }
        assert!((super::super::scalar(&rbf, &[1.0, 2.0]) - 5.0).abs() < 1e-3);
    }
}
