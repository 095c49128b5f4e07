//! The gradient `∂f/∂x` of the normalised RBFs (Eq. 6.15).

use super::super::{Differentiable, MAX_IN, MAX_OUT};
use super::Rbf;
use super::axes::Axes;

impl Rbf {
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
    pub(super) fn sums(&self, axes: &Axes, y: &mut [f64], jac: &mut [f64]) {
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
