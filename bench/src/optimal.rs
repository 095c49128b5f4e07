//! The optimal-control reference for the pendulum swing-up: the best return any policy
//! can earn in one trial, computed by dynamic programming, to judge the learners against.
//!
//! The task is the thesis's §3.6 swing-up ([`plant::Task::pendulum`]): `Ts = 0.03 s`,
//! `u ∈ [−3, 3]`, one trial of 3 s = `N = 100` samples from `x_0 = [π, 0]`, reward
//! Eq. 3.16, `ρ(x_k, u_k) = −x_kᵀ Q x_k − P u_k²` with `Q = diag(5, 0.1)`, `P = 1` and the
//! angle wrapped to [-π, π). The number compared is exactly what a learner's greedy
//! return sums ([`runtime::experiment::Experiment::greedy_return_from`], infinite horizon):
//! the undiscounted `Σ_{k=0}^{N−1} ρ(x_k, u_k)` of the state *before* each transition and
//! the action applied, with no terminal reward.
//!
//! Method: finite-horizon value iteration (backward induction) on a grid,
//! `V_N = 0`, `V_k(x) = max_u [ρ(x, u) + V_{k+1}(f(x, u))]` for `k = N−1, …, 0`, with
//!
//! * a `grid × grid` state grid: the angle periodic, `grid` nodes on [-π, π) (the start
//!   state's wrapped angle −π is a node); the velocity `grid` nodes on
//!   `[−W, W]`, `W = 8π rad/s` — the bound the thesis assumes in §3.6.1 (and the task's
//!   approximator range, [`plant::Task::state_range`]). The plant does not clip the
//!   velocity; a successor beyond `±W` is evaluated at the edge, which is harmless as
//!   long as the optimal trajectory stays well inside (reported: [`Optimum::max_speed`]);
//! * `actions` levels evenly spaced on the action bounds (both bounds included);
//! * the successor `f(x, u)` from the plant itself ([`plant::Plant::step`]: saturation,
//!   20 RK4 sub-steps with the action held, angle wrapping) and the reward it returns;
//! * `V_{k+1}(f(x, u))` interpolated bilinearly between the four surrounding nodes. The
//!   dynamics are time-invariant, so each `(node, action)`'s successor cell and weights
//!   are computed once and every backup reuses them (in parallel, rayon).
//!
//! The grid value `V_0(x_0)` is an approximation of the true optimum `J*`, of either sign
//! of error. The independent check is a real return: the DP's greedy policy (one-step
//! lookahead on the interpolated `V_{k+1}` over the same action levels) run on the true
//! plant from `x_0` ([`Optimum::simulated_return`], [`Optimum::trajectory`]). Being the
//! return of an actual policy, it is a lower bound: `J* ≥ simulated_return`. The two agree
//! to a fraction of a percent on fine grids (`docs/results/optimal.md`).

use std::sync::Arc;
use std::time::{Duration, Instant};

use plant::{Plant, Task};
use rayon::prelude::*;

use runtime::response::ResponseSample;

/// Allowed state-grid sizes (nodes per dimension).
pub const GRID_RANGE: std::ops::RangeInclusive<usize> = 21..=4001;
/// Allowed numbers of action levels.
pub const ACTIONS_RANGE: std::ops::RangeInclusive<usize> = 2..=1001;
/// Largest `grid² × actions`: the transition table takes 12 bytes per
/// entry (2.4 GB here).
pub const MAX_TRANSITIONS: usize = 200_000_000;

/// How fine the dynamic programme is.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimumOptions {
    /// Nodes per state dimension (angle and velocity).
    pub grid: usize,
    /// Action levels, evenly spaced on `[−3, 3]`, both bounds included (61: steps of 0.1).
    pub actions: usize,
}

impl Default for OptimumOptions {
    fn default() -> Self {
        Self {
            grid: 401,
            actions: 61,
        }
    }
}

/// Sizes of the dynamic programme out of range ([`OptimumOptions::validate`]); each names
/// the `rig optimal` flag and the allowed range.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OptimumError {
    /// A grid outside [`GRID_RANGE`].
    #[error(
        "`--grid` {0} is out of range: must be an integer in [{lo}, {hi}]",
        lo = GRID_RANGE.start(), hi = GRID_RANGE.end()
    )]
    Grid(usize),
    /// Action levels outside [`ACTIONS_RANGE`].
    #[error(
        "`--actions` {0} is out of range: must be an integer in [{lo}, {hi}]",
        lo = ACTIONS_RANGE.start(), hi = ACTIONS_RANGE.end()
    )]
    Actions(usize),
    /// More than [`MAX_TRANSITIONS`] transitions.
    #[error(
        "`--grid` {grid} with `--actions` {actions} needs {} transitions ({:.1} GB): grid² × actions must be at most {MAX_TRANSITIONS}",
        .grid * .grid * .actions, (.grid * .grid * .actions) as f64 * 12e-9
    )]
    Transitions {
        /// Grid points per dimension.
        grid: usize,
        /// Action levels.
        actions: usize,
    },
}

impl OptimumOptions {
    /// Checks the sizes against [`GRID_RANGE`], [`ACTIONS_RANGE`] and [`MAX_TRANSITIONS`];
    /// the error names the `rig optimal` flag and the allowed range.
    pub fn validate(&self) -> Result<(), OptimumError> {
        if !GRID_RANGE.contains(&self.grid) {
            return Err(OptimumError::Grid(self.grid));
        }
        if !ACTIONS_RANGE.contains(&self.actions) {
            return Err(OptimumError::Actions(self.actions));
        }
        if self.grid * self.grid * self.actions > MAX_TRANSITIONS {
            return Err(OptimumError::Transitions {
                grid: self.grid,
                actions: self.actions,
            });
        }
        Ok(())
    }
}

/// The optimal-control reference for one grid.
#[derive(Clone, Debug)]
pub struct Optimum {
    /// The options it was computed with.
    pub options: OptimumOptions,
    /// The velocity bound `W` of the grid \[rad/s\].
    pub velocity_limit: f64,
    /// The grid value `V_0(x_0)`: the DP's estimate of the optimal return.
    pub value_grid: f64,
    /// The return of the DP's greedy policy on the true plant from `x_0` (a lower bound
    /// of the optimal return).
    pub simulated_return: f64,
    /// That trial, sample by sample (`t`, the state before the step, applied action, reward).
    pub trajectory: Vec<ResponseSample>,
    /// The largest `|φ̇|` along the trajectory (including its final state) \[rad/s\].
    pub max_speed: f64,
    /// Time to compute the transition table.
    pub transitions_time: Duration,
    /// Time of the `N` backups.
    pub backups_time: Duration,
    /// Time of the whole computation (table, backups, simulation).
    pub wall: Duration,
}

impl Optimum {
    /// `|value_grid − simulated_return| / |simulated_return|`.
    pub fn relative_gap(&self) -> f64 {
        (self.value_grid - self.simulated_return).abs() / self.simulated_return.abs()
    }
}

/// One `(node, action)` successor: the lower-left node of its cell and the bilinear
/// fractions along angle and velocity.
#[derive(Clone, Copy, Debug)]
struct Successor {
    i: u16,
    j: u16,
    fa: f32,
    fw: f32,
}

/// The state grid: node `(i, j)` is angle `−π + i·2π/n`, velocity `−W + j·2W/(n−1)`,
/// stored at `j·n + i`.
struct Grid {
    n: usize,
    w: f64,
}

impl Grid {
    fn d_angle(&self) -> f64 {
        std::f64::consts::TAU / self.n as f64
    }
    fn d_speed(&self) -> f64 {
        2.0 * self.w / (self.n - 1) as f64
    }
    fn node(&self, index: usize) -> [f64; 2] {
        let (i, j) = (index % self.n, index / self.n);
        [
            -std::f64::consts::PI + i as f64 * self.d_angle(),
            -self.w + j as f64 * self.d_speed(),
        ]
    }
    /// The cell holding `x` (angle wrapped to [-π, π), velocity clamped to `[−W, W]`)
    /// and the fractions within it.
    fn locate(&self, x: &[f64]) -> (usize, usize, f64, f64) {
        let n = self.n;
        let a = (plant::angle::wrap(x[0]) + std::f64::consts::PI) / self.d_angle();
        let i = (a.floor() as usize).min(n - 1);
        let b = (x[1].clamp(-self.w, self.w) + self.w) / self.d_speed();
        let j = (b.floor() as usize).min(n - 2);
        (
            i,
            j,
            (a - i as f64).clamp(0.0, 1.0),
            (b - j as f64).clamp(0.0, 1.0),
        )
    }
    /// Bilinear interpolation of `v` in the cell `(i, j)` at fractions `(fa, fw)`.
    #[inline]
    fn interpolate(&self, v: &[f64], i: usize, j: usize, fa: f64, fw: f64) -> f64 {
        let n = self.n;
        let i1 = if i + 1 == n { 0 } else { i + 1 };
        let (lo, hi) = (j * n, (j + 1) * n);
        let bottom = v[lo + i] + fa * (v[lo + i1] - v[lo + i]);
        let top = v[hi + i] + fa * (v[hi + i1] - v[hi + i]);
        bottom + fw * (top - bottom)
    }
    fn value_at(&self, v: &[f64], x: &[f64]) -> f64 {
        let (i, j, fa, fw) = self.locate(x);
        self.interpolate(v, i, j, fa, fw)
    }
}

/// The optimal return of the pendulum swing-up from `[π, 0]` over one trial
/// ([`Task::pendulum`]), by finite-horizon dynamic programming on a grid, and the return
/// of the DP's greedy policy on the true plant (see the module documentation).
pub fn pendulum_optimum(options: &OptimumOptions) -> Result<Optimum, OptimumError> {
    options.validate()?;
    let start = Instant::now();
    let task = Arc::new(Task::pendulum());
    let steps = task.steps_per_trial();
    let grid = Grid {
        n: options.grid,
        w: task.state_range[1].1,
    };
    let (lo, hi) = (task.action_low[0], task.action_high[0]);
    let m = options.actions;
    let levels: Vec<f64> = (0..m)
        .map(|a| lo + (hi - lo) * a as f64 / (m - 1) as f64)
        .collect();
    let nodes = grid.n * grid.n;

    // Transition table and rewards, once: the dynamics and the reward are time-invariant.
    let empty = Successor {
        i: 0,
        j: 0,
        fa: 0.0,
        fw: 0.0,
    };
    let mut table = vec![empty; nodes * m];
    // ρ(x, u) = −xᵀQx − P u² as the state part of each node plus the cost of each level
    // (what `Reward::reward` computes, in the same order: checked below).
    let node_reward: Vec<f64> = (0..nodes)
        .map(|s| task.reward.state_reward(&grid.node(s)))
        .collect();
    let level_cost: Vec<f64> = levels.iter().map(|u| task.reward.p[0] * u * u).collect();
    table.par_chunks_mut(m).enumerate().for_each_init(
        || Plant::new(task.clone()),
        |plant, (s, succ)| {
            let x = grid.node(s);
            for a in 0..m {
                plant.reset(&x);
                let r = plant.step(&[levels[a]]);
                debug_assert_eq!(r, node_reward[s] - level_cost[a]);
                let (i, j, fa, fw) = grid.locate(plant.state());
                succ[a] = Successor {
                    i: i as u16,
                    j: j as u16,
                    fa: fa as f32,
                    fw: fw as f32,
                };
            }
        },
    );
    let transitions_time = start.elapsed();

    // Backward induction: values[k] = V_k, values[N] = 0 (no terminal reward).
    let backups = Instant::now();
    let mut values = vec![vec![0.0; nodes]; steps + 1];
    for k in (0..steps).rev() {
        let (now, later) = values.split_at_mut(k + 1);
        let next = &later[0];
        now[k].par_iter_mut().enumerate().for_each(|(s, v)| {
            let row = s * m;
            let mut best = f64::NEG_INFINITY;
            for a in 0..m {
                let t = table[row + a];
                let q = node_reward[s] - level_cost[a]
                    + grid.interpolate(
                        next,
                        t.i as usize,
                        t.j as usize,
                        f64::from(t.fa),
                        f64::from(t.fw),
                    );
                if q > best {
                    best = q;
                }
            }
            *v = best;
        });
    }
    let backups_time = backups.elapsed();
    drop(table);

    // The DP's greedy policy on the true plant.
    let mut plant = Plant::new(task.clone());
    let mut look = Plant::new(task.clone());
    plant.reset(&task.initial_states[0]);
    let value_grid = grid.value_at(&values[0], plant.state());
    let mut trajectory = Vec::with_capacity(steps);
    let mut max_speed = plant.state()[1].abs();
    for k in 0..steps {
        let x = plant.state().to_vec();
        let mut best = (f64::NEG_INFINITY, 0.0);
        for &u in &levels {
            look.reset(&x);
            let q = look.step(&[u]) + grid.value_at(&values[k + 1], look.state());
            if q > best.0 {
                best = (q, u);
            }
        }
        let reward = plant.step(&[best.1]);
        max_speed = max_speed.max(plant.state()[1].abs());
        trajectory.push(ResponseSample {
            t: k as f64 * task.ts,
            x,
            u: plant.applied_action().to_vec(),
            reward,
        });
    }
    let simulated_return = trajectory.iter().map(|s| s.reward).sum();
    Ok(Optimum {
        options: options.clone(),
        velocity_limit: grid.w,
        value_grid,
        simulated_return,
        trajectory,
        max_speed,
        transitions_time,
        backups_time,
        wall: start.elapsed(),
    })
}

/// Writes the trajectory as CSV: `t,angle,velocity,u,reward`.
pub fn write_trajectory(
    path: &std::path::Path,
    trajectory: &[ResponseSample],
) -> Result<(), runtime::error::FileError> {
    use std::fmt::Write;
    let mut text = String::from("t,angle,velocity,u,reward\n");
    for s in trajectory {
        // A String takes any text.
        let _ = writeln!(
            text,
            "{},{},{},{},{}",
            s.t, s.x[0], s.x[1], s.u[0], s.reward
        );
    }
    runtime::output::write_atomic(path, &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_interpolation_is_exact_on_affine_functions_and_wraps_the_angle() {
        let g = Grid { n: 21, w: 10.0 };
        let v: Vec<f64> = (0..g.n * g.n)
            .map(|s| {
                let x = g.node(s);
                2.0 * x[0] - 0.5 * x[1] + 1.0
            })
            .collect();
        for x in [[0.3, 1.7], [-3.0, -9.99], [1.0, 10.0], [-1.234, 0.0]] {
            let f = 2.0 * x[0] - 0.5 * x[1] + 1.0;
            assert!((g.value_at(&v, &x) - f).abs() < 1e-9, "{x:?}");
        }
        // Nodes are exact, and an angle beyond the last node interpolates towards −π.
        assert_eq!(g.value_at(&v, &[-std::f64::consts::PI, 0.0]), v[10 * 21]);
        let last = -std::f64::consts::PI + 20.0 * g.d_angle();
        let mid = 0.5 * (last + std::f64::consts::PI);
        let expect = 0.5 * (v[10 * 21 + 20] + v[10 * 21]);
        assert!((g.value_at(&v, &[mid, 0.0]) - expect).abs() < 1e-12);
        // Velocities beyond the bound are clamped to it.
        assert_eq!(g.value_at(&v, &[0.0, 50.0]), g.value_at(&v, &[0.0, 10.0]));
    }

    #[test]
    fn bad_sizes_name_the_flag_and_the_range() {
        let e = OptimumOptions {
            grid: 5,
            actions: 61,
        }
        .validate()
        .unwrap_err();
        assert_eq!(e, OptimumError::Grid(5));
        let e = e.to_string();
        assert!(e.contains("`--grid` 5") && e.contains("[21, 4001]"), "{e}");
        let e = OptimumOptions {
            grid: 101,
            actions: 1,
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`--actions` 1") && e.contains("[2, 1001]"),
            "{e}"
        );
        let e = OptimumOptions {
            grid: 4001,
            actions: 1001,
        }
        .validate()
        .unwrap_err();
        assert!(matches!(e, OptimumError::Transitions { .. }), "{e:?}");
        let e = e.to_string();
        assert!(e.contains("grid² × actions"), "{e}");
        assert!(
            e.contains("needs 16024009001 transitions (192.3 GB)"),
            "{e}"
        );
    }
}
