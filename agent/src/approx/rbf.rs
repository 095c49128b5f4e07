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
    centres: Vec<Vec<f64>>,
    /// Diagonal of `B⁻¹`.
    inv_b: Vec<f64>,
    period: Vec<f64>,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    /// Parameters, `m` per basis function.
    theta: Vec<f64>,
    trace: Vec<f64>,
}

/// Per-axis factors of one evaluation, every axis's centres side by side.
struct Axes {
    n: usize,
    /// Axis `j`'s centres are at `off[j]..off[j + 1]` of `g` and `r`.
    off: [usize; MAX_IN + 1],
    /// One-dimensional Gaussian of each axis at each of its centres.
    g: Vec<f64>,
    /// `B⁻¹ (x − c)` per axis and centre.
    r: Vec<f64>,
    /// `Σ_i g_j[i]` per axis (guarded against underflow far outside the grid).
    sums: [f64; MAX_IN],
    /// `Σⱼ φ̃ⱼ = Π_axes Σ_i g_j[i]`.
    norm: f64,
}

impl Axes {
    /// Axis `j`'s Gaussians.
    fn g(&self, j: usize) -> &[f64] {
        &self.g[self.off[j]..self.off[j + 1]]
    }

    /// Axis `j`'s `B⁻¹ (x − c)`.
    fn r(&self, j: usize) -> &[f64] {
        &self.r[self.off[j]..self.off[j + 1]]
    }

    /// Replaces `r_j[i]` by `r_j[i] − mean_r_j`, `mean_r_j = Σ_i g_j[i] r_j[i] / Σ_i g_j[i]`:
    /// the normalisation's part of the gradient (Eq. 6.15), which is separable —
    /// `Σ_i φ_i r_j[i_j]` over the whole grid equals that one-axis mean.
    fn centre_r(&mut self) {
        for j in 0..self.n {
            let mean = self
                .g(j)
                .iter()
                .zip(self.r(j))
                .map(|(g, r)| g * r)
                .sum::<f64>()
                / self.sums[j];
            let range = self.off[j]..self.off[j + 1];
            self.r[range].iter_mut().for_each(|r| *r -= mean);
        }
    }

    /// Calls `visit(i, φᵢ, index of centre i along each axis)` for every basis function
    /// in grid order (the last axis fastest). `φ̃ᵢ` is the product of the axes' factors
    /// in axis order; the product over all axes but the last is formed once per row.
    fn for_each(&self, mut visit: impl FnMut(usize, f64, &[usize])) {
        let (n, last) = (self.n, self.n - 1);
        let row = self.g(last);
        let mut idx = [0usize; MAX_IN];
        let mut i = 0;
        loop {
            let mut prefix = 1.0;
            for j in 0..last {
                prefix *= self.g[self.off[j] + idx[j]];
            }
            for (k, &g) in row.iter().enumerate() {
                idx[last] = k;
                visit(i, prefix * g / self.norm, &idx[..n]);
                i += 1;
            }
            // The next row: advance the other axes' indices, the last but one fastest.
            let mut j = last;
            loop {
                if j == 0 {
                    return;
                }
                j -= 1;
                idx[j] += 1;
                if idx[j] < self.off[j + 1] - self.off[j] {
                    break;
                }
                idx[j] = 0;
            }
        }
    }
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
        assert!(
            p.centres.iter().all(|&c| c >= 1),
            "at least one centre per axis"
        );
        let mut centres = Vec::new();
        let mut inv_b = Vec::new();
        let mut period = Vec::new();
        for j in 0..n {
            let (lo, hi) = p.range[j];
            let c = p.centres[j];
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

    /// Writes the centre of basis function `i` (grid order, the last input fastest) into
    /// `c`.
    pub fn centre(&self, i: usize, c: &mut [f64]) {
        let mut rest = i;
        for j in (0..self.n).rev() {
            let cs = &self.centres[j];
            c[j] = cs[rest % cs.len()];
            rest /= cs.len();
        }
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
        let total: usize = self.centres.iter().map(Vec::len).sum();
        let (mut g, mut r) = (Vec::with_capacity(total), Vec::with_capacity(total));
        let mut off = [0; MAX_IN + 1];
        let (mut sums, mut norm) = ([0.0; MAX_IN], 1.0);
        for (j, (cs, &xj)) in self.centres.iter().zip(x).enumerate() {
            let (p, inv_b) = (self.period[j], self.inv_b[j]);
            for &c in cs {
                let mut d = xj - c;
                if p > 0.0 {
                    d -= p * (d / p).round();
                }
                g.push((-0.5 * d * d * inv_b).exp());
                r.push(d * inv_b);
            }
            off[j + 1] = g.len();
            sums[j] = g[off[j]..].iter().sum::<f64>().max(f64::MIN_POSITIVE);
            norm *= sums[j];
        }
        Axes {
            n: self.n,
            off,
            g,
            r,
            sums,
            norm,
        }
    }

    /// Calls `visit(i, φᵢ(x), centre index per axis)` for every basis function.
    fn features(&self, x: &[f64], visit: impl FnMut(usize, f64, &[usize])) {
        self.axes(x).for_each(visit);
    }

    /// `Σᵢ θᵢ φᵢ` at the factors `axes`, before any output bound.
    fn unbounded_value(&self, axes: &Axes, y: &mut [f64]) {
        let m = self.m;
        y.fill(0.0);
        if m <= MAX_OUT {
            // The sums in a local array: accumulating through `y` costs twice the time.
            let mut v = [0.0; MAX_OUT];
            axes.for_each(|i, phi, _| {
                for (v, t) in v[..m].iter_mut().zip(&self.theta[i * m..(i + 1) * m]) {
                    *v += t * phi;
                }
            });
            y[..m].copy_from_slice(&v[..m]);
        } else {
            // More outputs than the array holds (SARSA's Q on the arm has nine).
            axes.for_each(|i, phi, _| {
                for (y, t) in y.iter_mut().zip(&self.theta[i * m..(i + 1) * m]) {
                    *y += t * phi;
                }
            });
        }
    }

    /// [`Approximator::shift`] at the factors `axes` of its input: the step is first cut
    /// so that the saturated value plus the step stays within the output bounds.
    fn shift_at(&mut self, axes: &Axes, step: &[f64]) {
        let m = self.m;
        let mut s = [0.0; MAX_OUT];
        s[..m].copy_from_slice(&step[..m]);
        if let Some((lo, hi)) = &self.bounds {
            let mut y = [0.0; MAX_OUT];
            self.unbounded_value(axes, &mut y[..m]);
            self.clamp(&mut y[..m]);
            for o in 0..m {
                s[o] = (y[o] + step[o]).clamp(lo[o], hi[o]) - y[o];
            }
        }
        let theta = &mut self.theta;
        axes.for_each(|i, phi, _| {
            for (t, s) in theta[i * m..(i + 1) * m].iter_mut().zip(&s[..m]) {
                *t += s * phi;
            }
        });
    }

    /// `Σᵢ θᵢ φᵢ` and `Σᵢ −θᵢ φᵢ (r_j[i_j] − mean_r_j)` (Eq. 6.15) into `y` and `jac`, for
    /// `M` outputs and `N` inputs known at compile time — the operations, and their order,
    /// of [`Self::sums`].
    fn sums_fixed<const M: usize, const N: usize>(
        &self,
        axes: &Axes,
        y: &mut [f64],
        jac: &mut [f64],
    ) {
        let (mut v, mut dv) = ([0.0; M], [[0.0; N]; M]);
        axes.for_each(|i, phi, idx| {
            for o in 0..M {
                let t = self.theta[i * M + o];
                v[o] += t * phi;
                for j in 0..N {
                    dv[o][j] -= t * phi * axes.r[axes.off[j] + idx[j]];
                }
            }
        });
        y[..M].copy_from_slice(&v);
        for (o, d) in dv.iter().enumerate() {
            jac[o * N..(o + 1) * N].copy_from_slice(d);
        }
    }

    /// The sums of [`Self::sums_fixed`] for any shape: in local arrays where they fit,
    /// else in `y` and `jac` (zeroed by the caller).
    fn sums(&self, axes: &Axes, y: &mut [f64], jac: &mut [f64]) {
        let (n, m) = (self.n, self.m);
        let (mut local_v, mut local_dv) = ([0.0; MAX_OUT], [0.0; MAX_OUT * MAX_IN]);
        let (v, dv): (&mut [f64], &mut [f64]) = if m <= MAX_OUT {
            (&mut local_v[..m], &mut local_dv[..m * n])
        } else {
            (&mut y[..m], &mut jac[..m * n])
        };
        axes.for_each(|i, phi, idx| {
            for o in 0..m {
                let t = self.theta[i * m + o];
                v[o] += t * phi;
                for j in 0..n {
                    // ∂φᵢ/∂x_j = −φᵢ (r_j[i_j] − mean_r_j)
                    dv[o * n + j] -= t * phi * axes.r[axes.off[j] + idx[j]];
                }
            }
        });
        if m <= MAX_OUT {
            y[..m].copy_from_slice(&local_v[..m]);
            jac[..m * n].copy_from_slice(&local_dv[..m * n]);
        }
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
        self.unbounded_value(&self.axes(x), y);
        self.clamp(y);
    }
    fn shift(&mut self, x: &[f64], step: &[f64]) {
        let axes = self.axes(x);
        self.shift_at(&axes, step);
    }
    fn fit(&mut self, x: &[f64], target: &[f64], rate: f64) {
        // One evaluation of the factors for the error and the step. The error is taken
        // on the unbounded value, as a gradient step should.
        let (m, axes) = (self.m, self.axes(x));
        let mut y = [0.0; MAX_OUT];
        self.unbounded_value(&axes, &mut y[..m]);
        let mut step = [0.0; MAX_OUT];
        for o in 0..m {
            step[o] = rate * (target[o] - y[o]);
        }
        self.shift_at(&axes, &step[..m]);
    }
}

impl Differentiable for Rbf {
    fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]) {
        let (n, m) = (self.n, self.m);
        // ∂φᵢ/∂x_j = −φᵢ (r_j[i_j] − mean_r_j)                                (Eq. 6.15)
        let mut axes = self.axes(x);
        axes.centre_r();
        y.fill(0.0);
        jac.fill(0.0);
        // The common shapes with their sizes known to the compiler, so that the sums stay
        // in registers (critics: one output; models and reference models: n outputs).
        match (m, n) {
            (1, 2) => self.sums_fixed::<1, 2>(&axes, y, jac),
            (1, 3) => self.sums_fixed::<1, 3>(&axes, y, jac),
            (1, 4) => self.sums_fixed::<1, 4>(&axes, y, jac),
            (1, 5) => self.sums_fixed::<1, 5>(&axes, y, jac),
            (2, 2) => self.sums_fixed::<2, 2>(&axes, y, jac),
            (2, 3) => self.sums_fixed::<2, 3>(&axes, y, jac),
            (4, 6) => self.sums_fixed::<4, 6>(&axes, y, jac),
            _ => self.sums(&axes, y, jac),
        }
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
        let axes = self.axes(x);
        let trace = &mut self.trace;
        axes.for_each(|i, phi, _| trace[i] += phi);
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

    /// The traversal visits every basis function once, in grid order (last axis
    /// fastest), with `φᵢ = Π_j exp(−½ d_j² / b_j) / Σ` computed directly from the centres.
    #[test]
    fn features_in_grid_order() {
        let counts = [3usize, 4, 2];
        let rbf = Rbf::new(&RbfParams {
            centres: counts.to_vec(),
            range: vec![(-PI, PI), (-2.0, 2.0), (0.0, 1.0)],
            periodic: vec![true, false, false],
            intersection: 0.6,
            outputs: 1,
            initial: 0.0,
            bounds: None,
        });
        let x = [2.9, -0.7, 0.2];
        let gauss = |j: usize, c: f64| {
            let mut d = x[j] - c;
            if rbf.period[j] > 0.0 {
                d -= rbf.period[j] * (d / rbf.period[j]).round();
            }
            (-0.5 * d * d * rbf.inv_b[j]).exp()
        };
        let raw =
            |idx: &[usize]| -> f64 { (0..3).map(|j| gauss(j, rbf.centres[j][idx[j]])).product() };
        let mut all = Vec::new();
        for a in 0..counts[0] {
            for b in 0..counts[1] {
                for c in 0..counts[2] {
                    all.push(raw(&[a, b, c]));
                }
            }
        }
        let sum: f64 = all.iter().sum();
        let mut seen = 0;
        rbf.features(&x, |i, phi, idx| {
            assert_eq!(i, seen);
            assert_eq!(i, (idx[0] * counts[1] + idx[1]) * counts[2] + idx[2]);
            assert!((phi - all[i] / sum).abs() < 1e-15, "φ_{i}: {phi}");
            seen += 1;
        });
        assert_eq!(seen, 24);
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

    /// More outputs than the local sums hold (`MAX_OUT`; SARSA's Q on the arm has nine):
    /// the same sums, in the same order, as from the basis functions; the Jacobian by
    /// finite differences.
    #[test]
    fn more_outputs_than_max_out() {
        let m = MAX_OUT + 1;
        let rbf = pendulum_rbf(m);
        let x = [0.4, -3.0];
        let mut phi = vec![0.0; rbf.len()];
        rbf.basis(&x, &mut phi);
        let mut want = vec![0.0; m];
        for (i, p) in phi.iter().enumerate() {
            for o in 0..m {
                want[o] += rbf.theta[i * m + o] * p;
            }
        }
        let (mut y, mut y2, mut jac) = (vec![0.0; m], vec![0.0; m], vec![0.0; 2 * m]);
        rbf.value(&x, &mut y);
        assert_eq!(y, want);
        rbf.value_and_jacobian(&x, &mut y2, &mut jac);
        assert_eq!(y2, want);
        let h = 1e-6;
        let (mut ya, mut yb) = (vec![0.0; m], vec![0.0; m]);
        rbf.value(&[x[0], x[1] + h], &mut ya);
        rbf.value(&[x[0], x[1] - h], &mut yb);
        for o in 0..m {
            let fd = (ya[o] - yb[o]) / (2.0 * h);
            assert!(
                (fd - jac[o * 2 + 1]).abs() < 1e-5 * (1.0 + fd.abs()),
                "output {o}"
            );
        }
    }

    /// The fixed-shape sums equal the general ones bit for bit, for every fixed shape.
    #[test]
    fn fixed_shapes_equal_the_general_sums() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for (m, n) in [(1, 2), (1, 3), (1, 4), (1, 5), (2, 2), (2, 3), (4, 6)] {
            let mut rbf = Rbf::new(&RbfParams {
                centres: vec![4; n],
                range: vec![(-2.0, 2.0); n],
                periodic: (0..n).map(|j| j == 0).collect(),
                intersection: 0.6,
                outputs: m,
                initial: 0.0,
                bounds: None,
            });
            for t in &mut rbf.theta {
                *t = rng.random_range(-5.0..5.0);
            }
            let x: Vec<f64> = (0..n).map(|_| rng.random_range(-2.5..2.5)).collect();
            let (mut y, mut jac) = (vec![0.0; m], vec![0.0; m * n]);
            rbf.value_and_jacobian(&x, &mut y, &mut jac);
            let mut axes = rbf.axes(&x);
            axes.centre_r();
            let (mut y2, mut jac2) = (vec![0.0; m], vec![0.0; m * n]);
            rbf.sums(&axes, &mut y2, &mut jac2);
            assert_eq!((y, jac), (y2, jac2), "shape ({m}, {n})");
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
        assert!((axes.g(0)[1] - 0.5).abs() < 1e-12 && (axes.g(0)[2] - 0.5).abs() < 1e-12);
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
