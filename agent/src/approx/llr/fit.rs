//! The local affine model at a query (§3.5.2): the centred ridge regression on the
//! neighbours, the saturation of outputs to their bounds, and the remembered last fit.

use std::cell::Ref;

use super::super::MAX_OUT;
use super::super::kdtree::{Candidate, MAX_DIM};
use super::super::solve::cholesky_solve;
use super::{Llr, same_bits};

/// Ridge added to the scaled-input covariance of a fit, per neighbour.
const RIDGE: f64 = 1e-9;

/// The local affine model at a query.
#[derive(Clone, Copy)]
pub(super) struct Fit {
    /// Prediction at the query.
    pub(super) y: [f64; MAX_OUT],
    /// Slope `∂y/∂x` in unscaled input units, row-major `m × n`.
    pub(super) jac: [f64; MAX_OUT * MAX_DIM],
}

/// The last local model fitted: at which scaled query (bits) and memory version.
pub(super) struct LastFit {
    pub(super) key: [u64; MAX_DIM],
    pub(super) version: u64,
    pub(super) fit: Fit,
}

impl Llr {
    /// The affine model fitted to the neighbours `nb` of the scaled query `q`, into
    /// `out` (its first `m` outputs and `m × n` slopes).
    pub(super) fn fit_local(&self, q: &[f64; MAX_DIM], nb: &[Candidate], out: &mut Fit) {
        // Monomorphised per input dimension, so that the small loops unroll.
        match self.n {
            1 => self.fit_in::<1>(q, nb, out),
            2 => self.fit_in::<2>(q, nb, out),
            3 => self.fit_in::<3>(q, nb, out),
            4 => self.fit_in::<4>(q, nb, out),
            5 => self.fit_in::<5>(q, nb, out),
            6 => self.fit_in::<6>(q, nb, out),
            7 => self.fit_in::<7>(q, nb, out),
            _ => self.fit_in::<MAX_DIM>(q, nb, out),
        }
    }

    fn fit_in<const N: usize>(&self, q: &[f64; MAX_DIM], nb: &[Candidate], out: &mut Fit) {
        let (n, m) = (N, self.m);
        debug_assert_eq!(n, self.n);
        if nb.is_empty() {
            out.y[..m].fill(0.0);
            out.jac[..m * n].fill(0.0);
            return;
        }
        let kf = nb.len() as f64;
        let period: &[f64; N] = self.period[..N].try_into().expect("n periods");
        // Inputs relative to the query (angles wrapped).
        let rel = |c: &Candidate| -> [f64; N] {
            let s = c.slot as usize;
            let p: &[f64; N] = self.inputs[s * N..(s + 1) * N]
                .try_into()
                .expect("n inputs");
            let mut d = [0.0; N];
            for j in 0..N {
                let mut v = p[j] - q[j];
                let per = period[j];
                if per > 0.0 {
                    if v >= 0.5 * per {
                        v -= per;
                    } else if v < -0.5 * per {
                        v += per;
                    }
                }
                d[j] = v;
            }
            d
        };
        // Means, then the centred normal equations S B = C, ridge-regularised.
        let (mut dm, mut ym) = ([0.0; N], [0.0; MAX_OUT]);
        for c in nb {
            let d = rel(c);
            for j in 0..N {
                dm[j] += d[j] / kf;
            }
            for (o, y) in self.output(c.slot).iter().enumerate() {
                ym[o] += y / kf;
            }
        }
        // `N × N` and `N × m` (row-major, in arrays sized for the largest `m`), so that
        // only what is used is zeroed.
        let mut s = [[0.0; N]; N];
        let s = s.as_flattened_mut();
        let mut cxy = [[0.0; MAX_OUT]; N];
        let cxy = cxy.as_flattened_mut();
        for c in nb {
            let d = rel(c);
            let y = self.output(c.slot);
            for a in 0..N {
                let da = d[a] - dm[a];
                for b in 0..=a {
                    s[a * n + b] += da * (d[b] - dm[b]);
                }
                for o in 0..m {
                    cxy[a * m + o] += da * (y[o] - ym[o]);
                }
            }
        }
        for a in 0..N {
            for b in 0..a {
                s[b * n + a] = s[a * n + b];
            }
            s[a * n + a] += RIDGE * kf;
        }
        if !cholesky_solve(s, n, cxy, m) {
            cxy.fill(0.0); // fall back to the neighbours' mean
        }
        for o in 0..m {
            let mut y = ym[o];
            for j in 0..N {
                let slope = cxy[j * m + o];
                y -= slope * dm[j];
                out.jac[o * n + j] = slope * self.weights[j];
            }
            if self.clip_to_neighbours {
                let (lo, hi) = nb
                    .iter()
                    .map(|c| self.output(c.slot)[o])
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                        (a.min(v), b.max(v))
                    });
                y = y.clamp(lo, hi);
            }
            out.y[o] = self.clamp(o, y);
        }
    }

    /// The local model at the scaled query `q`: the remembered one if it was fitted at
    /// `q` and the memory has not changed since, else a new fit, to `nb` if given (the K
    /// nearest samples), else to a search's.
    pub(super) fn fitted(&self, q: &[f64; MAX_DIM], nb: Option<&[Candidate]>) -> Ref<'_, Fit> {
        let key = q.map(f64::to_bits);
        {
            let mut last = self.last_fit.borrow_mut();
            if last.version != self.version || !same_bits(&last.key, &key) {
                match nb {
                    Some(nb) => self.fit_local(q, nb, &mut last.fit),
                    None => {
                        let mut nb = self.neighbours.take();
                        self.nearest(q, self.k, &mut nb);
                        self.fit_local(q, &nb, &mut last.fit);
                        self.neighbours.set(nb);
                    }
                }
                last.key = key;
                last.version = self.version;
            }
        }
        Ref::map(self.last_fit.borrow(), |last| &last.fit)
    }

    #[inline]
    pub(super) fn clamp(&self, o: usize, v: f64) -> f64 {
        match &self.bounds {
            Some((lo, hi)) => v.clamp(lo[o], hi[o]),
            None => v,
        }
    }
}
