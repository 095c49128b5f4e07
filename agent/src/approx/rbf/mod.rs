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

mod axes;
mod gradient;
#[cfg(test)]
mod tests;

use super::{Approximator, MAX_IN, MAX_OUT, Traced};
use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};
use axes::Axes;

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
