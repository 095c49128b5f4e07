//! The basis functions' per-axis factors: `B` is diagonal, so each Gaussian is a
//! product of one-dimensional factors, evaluated once per centre coordinate.

use super::super::MAX_IN;
use super::Rbf;

/// Per-axis factors of one evaluation, every axis's centres side by side.
pub(super) struct Axes {
    n: usize,
    /// Axis `j`'s centres are at `off[j]..off[j + 1]` of `g` and `r`.
    pub(super) off: [usize; MAX_IN + 1],
    /// One-dimensional Gaussian of each axis at each of its centres.
    g: Vec<f64>,
    /// `B⁻¹ (x − c)` per axis and centre.
    pub(super) r: Vec<f64>,
    /// `Σ_i g_j[i]` per axis (guarded against underflow far outside the grid).
    sums: [f64; MAX_IN],
    /// `Σⱼ φ̃ⱼ = Π_axes Σ_i g_j[i]`.
    norm: f64,
}

impl Axes {
    /// Axis `j`'s Gaussians.
    pub(super) fn g(&self, j: usize) -> &[f64] {
        &self.g[self.off[j]..self.off[j + 1]]
    }

    /// Axis `j`'s `B⁻¹ (x − c)`.
    fn r(&self, j: usize) -> &[f64] {
        &self.r[self.off[j]..self.off[j + 1]]
    }

    /// Replaces `r_j[i]` by `r_j[i] − mean_r_j`, `mean_r_j = Σ_i g_j[i] r_j[i] / Σ_i g_j[i]`:
    /// the normalisation's part of the gradient (Eq. 6.15), which is separable —
    /// `Σ_i φ_i r_j[i_j]` over the whole grid equals that one-axis mean.
    pub(super) fn centre_r(&mut self) {
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
    pub(super) fn for_each(&self, mut visit: impl FnMut(usize, f64, &[usize])) {
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
    pub(super) fn axes(&self, x: &[f64]) -> Axes {
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
    pub(super) fn features(&self, x: &[f64], visit: impl FnMut(usize, f64, &[usize])) {
        self.axes(x).for_each(visit);
    }
}
