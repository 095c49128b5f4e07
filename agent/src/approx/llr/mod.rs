//! Local linear regression (§3.5.2): a memory of samples `[x | y]`; a query fits an
//! affine model to the K nearest samples and evaluates it.
//!
//! * **Distance**: weighted Euclidean, the input scaling `diag(W)` of Table 6.2
//!   (coordinates are stored pre-multiplied by `W`); angle inputs are compared by their
//!   wrapped difference, so `φ = −π + ε` and `φ = π − ε` are neighbours.
//! * **Neighbour search**: a dynamic [`KdTree`] over the memory (or, with
//!   [`Search::Scan`], a partial selection over it) — never a sort of the whole memory.
//!   The two most recent searches are remembered and kept exact across insertions, and a
//!   new search is warm-started from the nearest remembered one: the farthest of its
//!   remembered neighbours from the new query bounds the new search from the start.
//!   The neighbours nearest in the leading inputs only (a process model's, by the state:
//!   [`Differentiable::value_and_jacobian_near`]) are found by a scan — VGBP's — or, for
//!   the planners, through a second tree over those inputs, kept from its first query on
//!   (`near.rs`).
//! * **Fit**: `β = Y Xᵀ (X Xᵀ)⁻¹` solved as a centred ridge regression in coordinates
//!   relative to the query: with `dᵢ = W (xᵢ − x_q)` (angles wrapped), the slope is
//!   `B = (Σ d̃ d̃ᵀ + εI)⁻¹ Σ d̃ ỹᵀ` (tilde: minus the mean) and the prediction
//!   `ŷ_q = ȳ − Bᵀ d̄`. The tiny ridge `ε` keeps the solve well-conditioned when the
//!   neighbours are fewer than `n + 1` or coincide (repeated samples): the slope then
//!   shrinks to zero and the prediction to the neighbours' mean — the "smallest-norm
//!   solution" the thesis prescribes for an under-determined set.
//! * **Clipping** ([`LlrParams::clip_to_neighbours`]): a prediction can be limited to the
//!   range of the neighbours' outputs. Far from its samples an affine fit extrapolates;
//!   for a critic that means values better than any observed nearby, which a model-based
//!   actor then climbs towards (see [`crate::preset`]).
//! * **Memory management** ([`Eviction`]): when full, purge the oldest sample; or, with
//!   [`Eviction::Redundant`], first let a new sample replace a stored one closer than a
//!   given (scaled) distance — a repeated sample then refreshes its twin instead of
//!   pushing an old, distinct sample out.
//! * **Updates** (§3.5.2, "Application to SAC/MLAC/RMAC"): [`Approximator::shift`]
//!   stores `[x | f(x)]` and adds the step to the output of it and its K−1 nearest
//!   neighbours; [`Approximator::fit`] moves the neighbours' outputs towards the target and
//!   stores `[x | target]`; a critic's [`Traced::visit`](super::Traced::visit) stores
//!   `[x | V(x)]` and gives it and its neighbours eligibility 1, decaying all others.
//!   Outputs can be bounded (the actor's memory is saturated to the input bounds, so it
//!   never proposes an action beyond them).
//!
//! # Speed
//!
//! The fit is monomorphised per input dimension like the search, and the last fit is
//! remembered with the memory's version (bumped by every change of a stored input or
//! output): MLAC asks for `π(x_k)` and then shifts the actor at `x_k`, which fits at the
//! same point on the same memory again. A query allocates nothing: the neighbours go into
//! a kept buffer, and the neighbourhood after an insertion is the new sample followed by
//! the earlier list. Measurements: `docs/results/llr-search.md`.

mod fit;
mod memory;
mod near;
mod neighbours;
mod persist;
#[cfg(test)]
mod tests;
mod traces;

use std::cell::{Cell, RefCell};
use std::collections::VecDeque;

use super::kdtree::{Candidate, KdTree, MAX_DIM, MAX_K};
use super::{Approximator, Differentiable, MAX_OUT};
use fit::{Fit, LastFit};
use neighbours::{CACHE_SLACK, Cached};

/// How the K nearest neighbours are found. Both give exactly the same neighbours (ties
/// broken by insertion order); they differ only in speed — see `agent/benches`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Search {
    /// A dynamic [`KdTree`].
    KdTree,
    /// A scan of the whole memory with partial selection (`select_nth_unstable`) of the
    /// K nearest — never a full sort.
    Scan,
}

/// What to remove when a sample arrives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Eviction {
    /// When full, purge the oldest sample.
    Oldest,
    /// Replace a stored sample whose scaled distance to the new one is below the given
    /// radius; otherwise, when full, purge the oldest.
    Redundant(f64),
}

/// Parameters of one LLR memory (Tables 3.2 and 6.2).
#[derive(Clone, Debug, PartialEq)]
pub struct LlrParams {
    /// Memory size `N`.
    pub memory: usize,
    /// Nearest neighbours `K`.
    pub neighbours: usize,
    /// Input scaling `diag(W)`.
    pub weights: Vec<f64>,
    /// Which inputs are angles (period 2π).
    pub periodic: Vec<bool>,
    /// Output dimension `m`.
    pub outputs: usize,
    /// Optional output bounds `(low, high)`; stored outputs are clamped to them.
    pub bounds: Option<(Vec<f64>, Vec<f64>)>,
    /// Memory management rule.
    pub eviction: Eviction,
    /// Neighbour search strategy.
    pub search: Search,
    /// Limit a prediction to the range of its neighbours' outputs (no extrapolation
    /// beyond the values observed nearby; the slope is unaffected).
    pub clip_to_neighbours: bool,
}

/// Whether two queries are the same bits: branch-free and inline (the array comparison
/// is a call to `memcmp`).
#[inline]
fn same_bits(a: &[u64; MAX_DIM], b: &[u64; MAX_DIM]) -> bool {
    a.iter().zip(b).fold(0, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// An LLR memory.
pub struct Llr {
    n: usize,
    m: usize,
    k: usize,
    cap: usize,
    weights: Vec<f64>,
    /// Period of each scaled input (2π·w for angles, 0 otherwise).
    period: Vec<f64>,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    eviction: Eviction,
    search: Search,
    clip_to_neighbours: bool,
    // Sample storage, by slot.
    inputs: Vec<f64>,
    outputs: Vec<f64>,
    seq: Vec<u64>,
    trace: Vec<f64>,
    len: usize,
    next_seq: u64,
    /// Slots in insertion order (lazily cleaned: an entry is stale when the slot's
    /// sequence number has changed).
    fifo: VecDeque<(u32, u64)>,
    // Index.
    tree: KdTree,
    /// The two most recent neighbour searches. The algorithms ask for the same point
    /// repeatedly (e.g. `π(x_{k+1})`, then, one sample later, the actor update at
    /// `x_{k+1}`). Neighbour sets depend on the stored inputs only, so output updates
    /// leave them valid, and insertions update them exactly.
    cache: RefCell<[Option<Cached>; 2]>,
    /// Slots with a non-zero trace.
    traced: Vec<(u32, u64)>,
    /// Changes to the stored inputs or outputs so far: a fit depends on nothing else.
    version: u64,
    /// The index of the neighbours nearest in the leading inputs, from the first query
    /// through it on ([`near`]).
    near: RefCell<Option<near::NearIndex>>,
    /// The last fit (see [`Llr::fitted`]). MLAC asks for `π(x_k)` and then shifts the
    /// actor at `x_k`, which fits there again.
    last_fit: RefCell<LastFit>,
    /// A buffer for the neighbours of a query, kept to avoid an allocation per query
    /// (taken while in use).
    neighbours: Cell<Vec<Candidate>>,
}

impl Llr {
    /// An empty memory.
    ///
    /// # Panics
    /// If the parameters are inconsistent (validated beforehand by the configuration).
    pub fn new(p: &LlrParams) -> Self {
        let n = p.weights.len();
        assert!(
            (1..=MAX_DIM).contains(&n),
            "LLR input dimension {n} not in 1..={MAX_DIM}"
        );
        assert!(p.outputs >= 1 && p.outputs <= MAX_OUT);
        assert!(p.neighbours >= 1 && p.neighbours <= MAX_K);
        assert!(p.memory >= 1 && p.periodic.len() == n);
        let period = p
            .weights
            .iter()
            .zip(&p.periodic)
            .map(|(w, &per)| {
                if per {
                    2.0 * std::f64::consts::PI * w
                } else {
                    0.0
                }
            })
            .collect();
        Self {
            n,
            m: p.outputs,
            k: p.neighbours,
            cap: p.memory,
            weights: p.weights.clone(),
            period,
            bounds: p.bounds.clone(),
            eviction: p.eviction,
            search: p.search,
            clip_to_neighbours: p.clip_to_neighbours,
            inputs: Vec::with_capacity(p.memory * n),
            outputs: Vec::with_capacity(p.memory * p.outputs),
            seq: Vec::with_capacity(p.memory),
            trace: Vec::with_capacity(p.memory),
            len: 0,
            next_seq: 0,
            fifo: VecDeque::with_capacity(p.memory + 1),
            tree: KdTree::new(n),
            cache: RefCell::new([None, None]),
            traced: Vec::new(),
            version: 0,
            near: RefCell::new(None),
            last_fit: RefCell::new(LastFit {
                key: [0; MAX_DIM],
                // No memory version reaches this: nothing is remembered yet.
                version: u64::MAX,
                fit: Fit {
                    y: [0.0; MAX_OUT],
                    jac: [0.0; MAX_OUT * MAX_DIM],
                },
            }),
            neighbours: Cell::new(Vec::with_capacity(p.neighbours + 1 + CACHE_SLACK)),
        }
    }

    /// Number of stored samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the memory is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// `(stored, capacity)`.
    pub fn fill(&self) -> (usize, usize) {
        (self.len, self.cap)
    }

    /// The stored samples as `(x, y)` pairs in slot order (for plots and checkpoints).
    pub fn samples(&self) -> impl Iterator<Item = (Vec<f64>, &[f64])> + '_ {
        (0..self.len).map(move |s| {
            let x = self.inputs[s * self.n..(s + 1) * self.n]
                .iter()
                .zip(&self.weights)
                .map(|(v, w)| v / w)
                .collect();
            (x, &self.outputs[s * self.m..(s + 1) * self.m])
        })
    }

    /// Scaled query coordinates (angles wrapped, then weighted).
    fn scale(&self, x: &[f64]) -> [f64; MAX_DIM] {
        let mut q = [0.0; MAX_DIM];
        for j in 0..self.n {
            let v = if self.period[j] > 0.0 {
                plant::angle::wrap(x[j])
            } else {
                x[j]
            };
            q[j] = v * self.weights[j];
        }
        q
    }

    fn coords(&self, slot: u32) -> &[f64] {
        &self.inputs[slot as usize * self.n..(slot as usize + 1) * self.n]
    }

    fn output(&self, slot: u32) -> &[f64] {
        &self.outputs[slot as usize * self.m..(slot as usize + 1) * self.m]
    }
}

impl Approximator for Llr {
    fn input_dim(&self) -> usize {
        self.n
    }
    fn output_dim(&self) -> usize {
        self.m
    }
    fn value(&self, x: &[f64], y: &mut [f64]) {
        y.copy_from_slice(&self.fitted(&self.scale(x), None).y[..self.m]);
    }
    fn shift(&mut self, x: &[f64], step: &[f64]) {
        let (_, after) = self.insert_here(x);
        self.version += 1;
        for c in &after {
            for o in 0..self.m {
                let i = c.slot as usize * self.m + o;
                self.outputs[i] = self.clamp(o, self.outputs[i] + step[o]);
            }
        }
        self.neighbours.set(after);
    }
    fn fit(&mut self, x: &[f64], target: &[f64], rate: f64) {
        let q = self.scale(x);
        let mut nearest = None;
        if rate > 0.0 && !self.is_empty() {
            let mut best = self.neighbours.take();
            self.nearest(&q, self.k, &mut best);
            nearest = best.first().copied();
            self.version += 1;
            for c in &best {
                for o in 0..self.m {
                    let i = c.slot as usize * self.m + o;
                    self.outputs[i] =
                        self.clamp(o, self.outputs[i] + rate * (target[o] - self.outputs[i]));
                }
            }
            self.neighbours.set(best);
        }
        self.insert(&q, target, nearest);
    }
    fn fill(&self) -> Option<(usize, usize)> {
        Some(Llr::fill(self))
    }
}

impl Differentiable for Llr {
    fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]) {
        let local = self.fitted(&self.scale(x), None);
        y.copy_from_slice(&local.y[..self.m]);
        jac.copy_from_slice(&local.jac[..self.m * self.n]);
    }

    /// The K samples nearest to `x[..lead]` (scaled distance over those inputs only,
    /// found by a scan of the memory), and the affine fit to them over all inputs.
    fn value_and_jacobian_near(&self, x: &[f64], lead: usize, y: &mut [f64], jac: &mut [f64]) {
        if lead >= self.n {
            return self.value_and_jacobian(x, y, jac);
        }
        let q = self.scale(x);
        let mut fit = Fit {
            y: [0.0; MAX_OUT],
            jac: [0.0; MAX_OUT * MAX_DIM],
        };
        self.fit_near_by_scan(&q, lead, &mut fit);
        y.copy_from_slice(&fit.y[..self.m]);
        jac.copy_from_slice(&fit.jac[..self.m * self.n]);
    }

    /// The same K samples, found through an index over `x[..lead]` (built at the first
    /// such query, kept from then on) and fitted nearest first ([`near`]).
    fn value_and_jacobian_near_indexed(
        &self,
        x: &[f64],
        lead: usize,
        y: &mut [f64],
        jac: &mut [f64],
    ) {
        if lead >= self.n {
            return self.value_and_jacobian(x, y, jac);
        }
        let q = self.scale(x);
        let mut nb = self.neighbours.take();
        self.near_ranked(&q, lead, &mut nb);
        let mut fit = Fit {
            y: [0.0; MAX_OUT],
            jac: [0.0; MAX_OUT * MAX_DIM],
        };
        self.fit_local(&q, &nb, &mut fit);
        self.neighbours.set(nb);
        y.copy_from_slice(&fit.y[..self.m]);
        jac.copy_from_slice(&fit.jac[..self.m * self.n]);
    }
}
