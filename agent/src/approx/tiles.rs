//! Tile coding (§3.5.3): `T` tilings, each a uniform grid; a point activates one tile per
//! tiling and the prediction is the average `ŷ = (1/T) Σ θᵢ` of the active tiles'
//! parameters. The tilings are offset from each other by `1/T` of a tile width along
//! every axis ("equidistantly distributed", §3.6.1); a periodic (angle) axis wraps.
//!
//! Updates treat the binary features as having unit gradient, so a step of `α δ`
//! moves the prediction at `x` by exactly `α δ` — the learning rates of §3.6.1
//! (`α_a = 0.005`, `α_c = 0.1`) are in output units, like those of the other
//! approximators. Tile coding has no input gradient and is used by SAC only.
//!
//! With output bounds (the actor) the value is saturated and a shift moves the saturated
//! value at `x` no further than the bounds, as for [`super::rbf`] (see there for why SAC
//! needs it; `rig learn --algo sac --approx tiles`, 30 runs: last three greedy
//! evaluations −1086 → −857).

use super::{Approximator, MAX_OUT, Traced};

/// Tiling layout.
#[derive(Clone, Debug, PartialEq)]
pub struct TilesParams {
    /// Number of tilings `T`.
    pub tilings: usize,
    /// Tiles per axis in each tiling.
    pub tiles: Vec<usize>,
    /// Input range covered, `(low, high)` per input.
    pub range: Vec<(f64, f64)>,
    /// Which inputs are angles (wrapping tiles).
    pub periodic: Vec<bool>,
    /// Output dimension.
    pub outputs: usize,
    /// Optional output bounds: the value is saturated, and shifts stop at the bounds.
    pub bounds: Option<(Vec<f64>, Vec<f64>)>,
}

/// A tile-coding approximator.
pub struct Tiles {
    p: TilesParams,
    /// Cells per axis per tiling (one extra on non-periodic axes for the offsets).
    cells: Vec<usize>,
    per_tiling: usize,
    theta: Vec<f64>,
    trace: Vec<f64>,
}

impl Tiles {
    /// A tile coder with all parameters zero.
    pub fn new(p: &TilesParams) -> Self {
        assert!(
            p.tilings >= 1 && p.tiles.len() == p.range.len() && p.periodic.len() == p.range.len()
        );
        let cells: Vec<usize> = p
            .tiles
            .iter()
            .zip(&p.periodic)
            .map(|(&t, &per)| if per { t } else { t + 1 })
            .collect();
        let per_tiling = cells.iter().product();
        Self {
            p: p.clone(),
            cells,
            per_tiling,
            theta: vec![0.0; p.tilings * per_tiling * p.outputs],
            trace: vec![0.0; p.tilings * per_tiling],
        }
    }

    /// The active tile (feature index) of each tiling.
    fn active(&self, x: &[f64], out: &mut Vec<usize>) {
        out.clear();
        let t_count = self.p.tilings as f64;
        for t in 0..self.p.tilings {
            let mut index = 0;
            for (j, &xj) in x.iter().enumerate() {
                let (lo, hi) = self.p.range[j];
                let width = (hi - lo) / self.p.tiles[j] as f64;
                let offset = t as f64 / t_count * width;
                let cell = ((xj - lo + offset) / width).floor() as i64;
                let c = self.cells[j] as i64;
                let cell = if self.p.periodic[j] {
                    cell.rem_euclid(c)
                } else {
                    cell.clamp(0, c - 1)
                };
                index = index * self.cells[j] + cell as usize;
            }
            out.push(t * self.per_tiling + index);
        }
    }
}

impl Approximator for Tiles {
    fn input_dim(&self) -> usize {
        self.p.range.len()
    }
    fn output_dim(&self) -> usize {
        self.p.outputs
    }
    fn value(&self, x: &[f64], y: &mut [f64]) {
        let m = self.p.outputs;
        let mut act = Vec::with_capacity(self.p.tilings);
        self.active(x, &mut act);
        y.fill(0.0);
        for &i in &act {
            for (y, t) in y.iter_mut().zip(&self.theta[i * m..(i + 1) * m]) {
                *y += t / self.p.tilings as f64;
            }
        }
        if let Some((lo, hi)) = &self.p.bounds {
            for o in 0..m {
                y[o] = y[o].clamp(lo[o], hi[o]);
            }
        }
    }
    fn shift(&mut self, x: &[f64], step: &[f64]) {
        let m = self.p.outputs;
        let mut step = step[..m].to_vec();
        if let Some((lo, hi)) = &self.p.bounds {
            // The bounded value at `x` moves by `step` but no further than the bounds.
            let mut y = [0.0; MAX_OUT];
            self.value(x, &mut y[..m]);
            for o in 0..m {
                step[o] = (y[o] + step[o]).clamp(lo[o], hi[o]) - y[o];
            }
        }
        let mut act = Vec::with_capacity(self.p.tilings);
        self.active(x, &mut act);
        for &i in &act {
            for (t, s) in self.theta[i * m..(i + 1) * m].iter_mut().zip(&step) {
                *t += s;
            }
        }
    }
    fn fit(&mut self, x: &[f64], target: &[f64], rate: f64) {
        let m = self.p.outputs;
        let mut y = [0.0; MAX_OUT];
        self.value(x, &mut y[..m]);
        let step: Vec<f64> = (0..m).map(|o| rate * (target[o] - y[o])).collect();
        self.shift(x, &step);
    }
}

impl Traced for Tiles {
    fn visit(&mut self, x: &[f64], decay: f64) {
        for z in &mut self.trace {
            *z *= decay;
        }
        let mut act = Vec::with_capacity(self.p.tilings);
        self.active(x, &mut act);
        for i in act {
            self.trace[i] += 1.0;
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

impl Persist for Tiles {
    fn save(&self, s: &mut Snapshot) {
        s.scope("tiles", |s| {
            s.f64s("theta", &self.theta);
            s.f64s("trace", &self.trace);
        });
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.scope("tiles", |r| {
            r.f64s_into("theta", &mut self.theta)?;
            r.f64s_into("trace", &mut self.trace)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn tiles() -> Tiles {
        Tiles::new(&TilesParams {
            tilings: 16,
            tiles: vec![7, 7],
            range: vec![(-PI, PI), (-8.0 * PI, 8.0 * PI)],
            periodic: vec![true, false],
            outputs: 1,
            bounds: None,
        })
    }

    #[test]
    fn one_tile_per_tiling() {
        let t = tiles();
        let mut act = Vec::new();
        t.active(&[0.1, 3.0], &mut act);
        assert_eq!(act.len(), 16);
        for (k, &i) in act.iter().enumerate() {
            assert_eq!(i / t.per_tiling, k);
        }
    }

    #[test]
    fn shift_moves_the_prediction_by_the_step() {
        let mut t = tiles();
        t.shift(&[0.1, 3.0], &[0.7]);
        assert!((super::super::scalar(&t, &[0.1, 3.0]) - 0.7).abs() < 1e-12);
        // Generalises partially to a point a fraction of a tile away...
        let near = super::super::scalar(&t, &[0.2, 3.0]);
        assert!(near > 0.0 && near < 0.7);
        // ...and not at all far away.
        assert_eq!(super::super::scalar(&t, &[-2.0, -20.0]), 0.0);
    }

    #[test]
    fn shift_stops_at_the_output_bounds() {
        let mut t = Tiles::new(&TilesParams {
            bounds: Some((vec![-3.0], vec![3.0])),
            ..tiles().p
        });
        let x = [0.1, 3.0];
        for _ in 0..10 {
            t.shift(&x, &[2.0]);
        }
        assert!((super::super::scalar(&t, &x) - 3.0).abs() < 1e-12);
        t.shift(&x, &[-1.0]);
        assert!((super::super::scalar(&t, &x) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn angle_axis_wraps() {
        let mut t = tiles();
        t.shift(&[PI - 0.01, 0.0], &[1.0]);
        assert!(super::super::scalar(&t, &[-PI + 0.01, 0.0]) > 0.5);
    }
}
