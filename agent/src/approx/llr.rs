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
//!   stores `[x | target]`; a critic's [`Traced::visit`] stores `[x | V(x)]` and gives it
//!   and its neighbours eligibility 1, decaying all others. Outputs can be bounded (the
//!   actor's memory is saturated to the input bounds, so it never proposes an action
//!   beyond them).
//!
//! # Speed
//!
//! The fit is monomorphised per input dimension like the search, and the last fit is
//! remembered with the memory's version (bumped by every change of a stored input or
//! output): MLAC asks for `π(x_k)` and then shifts the actor at `x_k`, which fits at the
//! same point on the same memory again. A query allocates nothing: the neighbours go into
//! a kept buffer, and the neighbourhood after an insertion is the new sample followed by
//! the earlier list. Measurements: `docs/results/llr-search.md`.

use std::cell::{Cell, Ref, RefCell};
use std::collections::VecDeque;

use super::kdtree::{Best, Candidate, KdTree, LEAF_SIZE, MAX_DIM, MAX_K, dist2};
use super::solve::cholesky_solve;
use super::{Approximator, Differentiable, MAX_OUT, Traced};

/// Traces below this are dropped (with λγ = 0.63 that is after 30 steps).
const TRACE_CUTOFF: f64 = 1e-6;
/// Ridge added to the scaled-input covariance of a fit, per neighbour.
const RIDGE: f64 = 1e-9;

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

/// The local affine model at a query.
#[derive(Clone, Copy)]
struct Fit {
    /// Prediction at the query.
    y: [f64; MAX_OUT],
    /// Slope `∂y/∂x` in unscaled input units, row-major `m × n`.
    jac: [f64; MAX_OUT * MAX_DIM],
}

/// A remembered neighbour search: the query (bit-exact), its scaled coordinates, and the
/// true nearest samples of the memory as it is now — insertions keep the list exact
/// (see `Llr::update_cache`), possibly shorter.
struct Cached {
    key: [u64; MAX_DIM],
    q: [f64; MAX_DIM],
    found: Vec<Candidate>,
}

/// The k-d tree is rebuilt, balanced, after this many times as many insertions as the
/// memory holds samples. Insertions only ever widen bounding boxes (removals leave them
/// as they are), and wide boxes prune worse; but a rebuild costs as much as tens of
/// searches. Measured (best 1000-step chunk of an MLAC/LLR replay on full memories,
/// rebuild after `x · N` insertions): x = ¼ 6.9–7.0 µs, ½ 6.6–6.7, 1 6.55–6.7,
/// 4 6.5–6.6, never 6.9.
const REBUILD_AFTER: usize = 4;

/// How many neighbours beyond K + 1 a search keeps, so that a remembered search survives
/// this many insertions (each can remove one of its samples).
const CACHE_SLACK: usize = 1;

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
    /// The last fit (see [`Llr::fitted`]). MLAC asks for `π(x_k)` and then shifts the
    /// actor at `x_k`, which fits there again.
    last_fit: RefCell<LastFit>,
    /// A buffer for the neighbours of a query, kept to avoid an allocation per query
    /// (taken while in use).
    neighbours: Cell<Vec<Candidate>>,
}

/// The last local model fitted: at which scaled query (bits) and memory version.
struct LastFit {
    key: [u64; MAX_DIM],
    version: u64,
    fit: Fit,
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

    /// The `count ≤ K + 1` nearest stored samples to the scaled query `q`, into `out`. A
    /// search keeps K + 2 and is remembered, so a value query and a later insertion at
    /// the same point share one search, even with one insertion elsewhere in between.
    fn nearest(&self, q: &[f64; MAX_DIM], count: usize, out: &mut Vec<Candidate>) {
        out.clear();
        let key = q.map(f64::to_bits);
        let mut cache = self.cache.borrow_mut();
        if let Some(hit) = cache
            .iter()
            .flatten()
            .find(|c| same_bits(&c.key, &key) && c.found.len() >= count.min(self.len))
        {
            out.extend_from_slice(&hit.found[..count.min(hit.found.len())]);
            return;
        }
        // The older remembered search is replaced; its list's allocation is reused.
        let reused = cache[1].take().map(|c| c.found).unwrap_or_default();
        let mut wide = Best::reusing(self.k + 1 + CACHE_SLACK, reused);
        // Warm start: the remembered neighbours of the nearest remembered query are as
        // many live samples as the search keeps, so the farthest of them from `q` bounds
        // the search from its first node (a ceiling: every sample within it is offered).
        let seed = cache.iter().flatten().min_by(|a, b| {
            dist2(&a.q[..self.n], &q[..self.n], &self.period).total_cmp(&dist2(
                &b.q[..self.n],
                &q[..self.n],
                &self.period,
            ))
        });
        if let Some(seed) = seed.filter(|s| s.found.len() >= wide.capacity()) {
            let ceiling = seed
                .found
                .iter()
                .map(|c| dist2(self.coords(c.slot), &q[..self.n], &self.period))
                // A NaN (a corrupt query or sample) leaves the search unbounded.
                .fold(0.0, |a: f64, d| if d > a || d.is_nan() { d } else { a });
            let ceiling = if ceiling.is_nan() {
                f64::INFINITY
            } else {
                ceiling
            };
            wide.set_ceiling(ceiling);
        }
        self.search_into(&q[..self.n], &mut wide);
        let found = wide.into_sorted();
        out.extend_from_slice(&found[..count.min(found.len())]);
        cache.swap(0, 1);
        cache[0] = Some(Cached { key, q: *q, found });
    }

    /// Keeps the remembered searches exact across the insertion of `new`, which removed
    /// the previous sample of slot `removed`, if any.
    ///
    /// A remembered list holds the true nearest samples of the memory. Removing one of
    /// them shortens it by one; the new sample joins it where it ranks if that is before
    /// the list's end (or right at the end when the memory holds nothing beyond the list).
    fn update_cache(&mut self, new: Candidate, removed: Option<u32>) {
        let (n, len, period) = (self.n, self.len, &self.period);
        let p = &self.inputs[new.slot as usize * n..(new.slot as usize + 1) * n];
        for c in self.cache.get_mut().iter_mut().flatten() {
            if let Some(pos) = removed.and_then(|r| c.found.iter().position(|f| f.slot == r)) {
                c.found.remove(pos);
            }
            let cand = Candidate {
                d2: dist2(p, &c.q[..n], period),
                ..new
            };
            let pos = c.found.partition_point(|f| f.before(&cand));
            // `len - 1` samples besides the new one; all of them remembered?
            if pos < c.found.len() || len - 1 <= c.found.len() {
                c.found.insert(pos, cand);
            }
        }
    }

    /// Offers the nearest stored samples to `best`.
    fn search_into(&self, q: &[f64], best: &mut Best) {
        match self.search {
            Search::KdTree => self.tree.search(q, &self.period, best),
            Search::Scan => {
                let mut all: Vec<Candidate> = (0..self.len as u32)
                    .map(|slot| Candidate {
                        d2: dist2(self.coords(slot), q, &self.period),
                        seq: self.seq[slot as usize],
                        slot,
                    })
                    .collect();
                let k = best.capacity().min(all.len());
                if k > 0 && k < all.len() {
                    all.select_nth_unstable_by(k - 1, |a, b| {
                        a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq))
                    });
                }
                for c in &all[..k] {
                    best.offer(*c);
                }
            }
        }
    }

    /// The affine model fitted to the neighbours `nb` of the scaled query `q`, into
    /// `out` (its first `m` outputs and `m × n` slopes).
    fn fit_local(&self, q: &[f64; MAX_DIM], nb: &[Candidate], out: &mut Fit) {
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
    fn fitted(&self, q: &[f64; MAX_DIM], nb: Option<&[Candidate]>) -> Ref<'_, Fit> {
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
    fn clamp(&self, o: usize, v: f64) -> f64 {
        match &self.bounds {
            Some((lo, hi)) => v.clamp(lo[o], hi[o]),
            None => v,
        }
    }

    /// Stores `[x | y]` (`q` = scaled `x`, `nearest` = the nearest stored sample, if
    /// known), evicting per the memory-management rule. Returns the new sample as a
    /// candidate at distance 0 and the slot whose previous sample was removed, if any.
    fn insert(
        &mut self,
        q: &[f64; MAX_DIM],
        y: &[f64],
        nearest: Option<Candidate>,
    ) -> (Candidate, Option<u32>) {
        let seq = self.next_seq;
        self.next_seq += 1;
        self.version += 1;
        let replace = match self.eviction {
            Eviction::Redundant(radius) if self.len > 0 => {
                let nearest = nearest.or_else(|| {
                    let mut found = self.neighbours.take();
                    self.nearest(q, 1, &mut found);
                    let first = found.first().copied();
                    self.neighbours.set(found);
                    first
                });
                nearest.filter(|c| c.d2 < radius * radius).map(|c| c.slot)
            }
            _ => None,
        };
        let (slot, removed) = match replace {
            Some(slot) => (slot, Some(slot)),
            None if self.len < self.cap => {
                self.inputs.extend_from_slice(&q[..self.n]);
                self.outputs.extend_from_slice(y);
                self.seq.push(seq);
                self.trace.push(0.0);
                self.len += 1;
                ((self.len - 1) as u32, None)
            }
            None => {
                let slot = self.oldest_slot();
                (slot, Some(slot))
            }
        };
        let s = slot as usize;
        if removed.is_some() {
            self.inputs[s * self.n..(s + 1) * self.n].copy_from_slice(&q[..self.n]);
            self.outputs[s * self.m..(s + 1) * self.m].copy_from_slice(y);
            self.seq[s] = seq;
            self.trace[s] = 0.0;
        }
        for o in 0..self.m {
            self.outputs[s * self.m + o] = self.clamp(o, self.outputs[s * self.m + o]);
        }
        self.fifo.push_back((slot, seq));
        self.index(slot, seq, removed.is_some());
        let new = Candidate { d2: 0.0, seq, slot };
        self.update_cache(new, removed);
        (new, removed)
    }

    fn oldest_slot(&mut self) -> u32 {
        while let Some((slot, seq)) = self.fifo.pop_front() {
            if self.seq[slot as usize] == seq {
                return slot;
            }
        }
        unreachable!("a full memory always has a live oldest sample")
    }

    /// Adds a new sample to the search index, removing the entry of the sample it
    /// `replaced` in `slot`; rebuilds the tree, balanced, after [`REBUILD_AFTER`] times
    /// as many insertions as samples.
    fn index(&mut self, slot: u32, seq: u64, replaced: bool) {
        if self.search == Search::Scan {
            return;
        }
        if replaced {
            self.tree.remove(slot);
        }
        if self.tree.insertions() >= REBUILD_AFTER * self.len + 8 * LEAF_SIZE {
            self.tree.rebuild(&self.inputs, &self.seq);
        } else {
            self.tree.insert(
                &self.inputs[slot as usize * self.n..(slot as usize + 1) * self.n],
                slot,
                seq,
            );
        }
    }

    /// Stores `[x | f(x)]`; returns `f(x)` (before the insertion) and the neighbourhood of
    /// `x` after it, nearest first, in the [`Llr::neighbours`] buffer (to be given back).
    /// One search serves both: the K + 1 nearest before the insertion contain the K − 1
    /// that join the new sample, whatever the insertion removed.
    fn insert_here(&mut self, x: &[f64]) -> ([f64; MAX_OUT], Vec<Candidate>) {
        let q = self.scale(x);
        let mut near = self.neighbours.take();
        self.nearest(&q, self.k + 1, &mut near);
        let y = self.fitted(&q, Some(&near[..near.len().min(self.k)])).y;
        let (new, removed) = self.insert(&q, &y[..self.m], near.first().copied());
        // The new sample (distance 0, newest) ranks first; the others keep their order.
        near.retain(|c| Some(c.slot) != removed);
        near.insert(0, new);
        near.truncate(self.k);
        (y, near)
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
        let mut all: Vec<Candidate> = (0..self.len as u32)
            .map(|slot| Candidate {
                d2: dist2(&self.coords(slot)[..lead], &q[..lead], &self.period[..lead]),
                seq: self.seq[slot as usize],
                slot,
            })
            .collect();
        let k = self.k.min(all.len());
        if k > 0 && k < all.len() {
            all.select_nth_unstable_by(k - 1, |a, b| a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq)));
        }
        let mut fit = Fit {
            y: [0.0; MAX_OUT],
            jac: [0.0; MAX_OUT * MAX_DIM],
        };
        self.fit_local(&q, &all[..k], &mut fit);
        y.copy_from_slice(&fit.y[..self.m]);
        jac.copy_from_slice(&fit.jac[..self.m * self.n]);
    }
}

impl Traced for Llr {
    fn visit(&mut self, x: &[f64], decay: f64) {
        self.visit_value(x, decay);
    }
    fn visit_value(&mut self, x: &[f64], decay: f64) -> f64 {
        let mut kept = 0;
        for i in 0..self.traced.len() {
            let (slot, seq) = self.traced[i];
            let s = slot as usize;
            if self.seq[s] != seq {
                continue;
            }
            self.trace[s] *= decay;
            if self.trace[s] < TRACE_CUTOFF {
                self.trace[s] = 0.0;
                continue;
            }
            self.traced[kept] = (slot, seq);
            kept += 1;
        }
        self.traced.truncate(kept);
        let (y, after) = self.insert_here(x);
        for c in &after {
            if self.trace[c.slot as usize] == 0.0 {
                self.traced.push((c.slot, c.seq));
            }
            self.trace[c.slot as usize] = 1.0;
        }
        self.neighbours.set(after);
        y[0]
    }
    fn apply_td(&mut self, step: f64) {
        self.version += 1;
        for &(slot, seq) in &self.traced {
            let s = slot as usize;
            if self.seq[s] == seq {
                self.outputs[s] += step * self.trace[s];
            }
        }
    }
    fn clear_traces(&mut self) {
        for &(slot, _) in &self.traced {
            self.trace[slot as usize] = 0.0;
        }
        self.traced.clear();
    }
}

/// The stored samples (scaled inputs, outputs, sequence numbers, traces) and the next
/// sequence number. The insertion order follows from the sequence numbers; the k-d tree
/// is rebuilt and the remembered searches and fits start empty — neighbour sets are
/// ordered totally (distance, then newer first), so searches give the same neighbours in
/// the same order whatever the tree's shape.
impl crate::checkpoint::Persist for Llr {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        s.scope("llr", |s| {
            s.f64s("inputs", &self.inputs);
            s.f64s("outputs", &self.outputs);
            s.u64s("seq", &self.seq);
            s.f64s("trace", &self.trace);
            s.u64s("next_seq", &[self.next_seq]);
        });
    }

    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        use crate::checkpoint::CheckpointError;
        r.scope("llr", |r| {
            let inputs = r.f64s("inputs")?;
            let outputs = r.f64s("outputs")?;
            let seq = r.u64s("seq")?;
            let trace = r.f64s("trace")?;
            let next_seq = r.u64s("next_seq")?.first().copied().unwrap_or(0);
            let len = seq.len();
            if len > self.cap
                || inputs.len() != len * self.n
                || outputs.len() != len * self.m
                || trace.len() != len
                || seq.iter().any(|&q| q >= next_seq)
            {
                return Err(CheckpointError(format!(
                    "checkpoint section `llr` holds {len} samples of {} inputs and {} outputs, which does not fit a memory of {} samples of {} inputs and {} outputs: it was written by a differently configured agent",
                    inputs.len().checked_div(len).unwrap_or(0),
                    outputs.len().checked_div(len).unwrap_or(0),
                    self.cap,
                    self.n,
                    self.m
                )));
            }
            self.inputs.clear();
            self.inputs.extend_from_slice(inputs);
            self.outputs.clear();
            self.outputs.extend_from_slice(outputs);
            self.seq.clear();
            self.seq.extend_from_slice(seq);
            self.trace.clear();
            self.trace.extend_from_slice(trace);
            self.len = len;
            self.next_seq = next_seq;
            let mut order: Vec<(u32, u64)> = (0..len as u32).map(|i| (i, seq[i as usize])).collect();
            order.sort_by_key(|&(_, q)| q);
            self.fifo = order.into_iter().collect();
            self.traced = (0..len as u32)
                .filter(|&i| self.trace[i as usize] != 0.0)
                .map(|i| (i, self.seq[i as usize]))
                .collect();
            if self.search == Search::KdTree {
                self.tree.rebuild(&self.inputs, &self.seq);
            }
            *self.cache.borrow_mut() = [None, None];
            self.version += 1;
            self.last_fit.borrow_mut().version = u64::MAX;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn params(n: usize, m: usize, memory: usize, k: usize) -> LlrParams {
        LlrParams {
            memory,
            neighbours: k,
            weights: vec![1.0; n],
            periodic: vec![false; n],
            outputs: m,
            bounds: None,
            eviction: Eviction::Oldest,
            search: Search::KdTree,
            clip_to_neighbours: false,
        }
    }

    fn neighbours(llr: &Llr, x: &[f64]) -> Vec<u32> {
        let mut found = Vec::new();
        llr.nearest(&llr.scale(x), llr.k, &mut found);
        found.iter().map(|c| c.slot).collect()
    }

    /// The reference: every sample, fully sorted by (distance, newer first).
    fn brute_force(llr: &Llr, x: &[f64]) -> Vec<u32> {
        let q = llr.scale(x);
        let mut all: Vec<Candidate> = (0..llr.len as u32)
            .map(|slot| Candidate {
                d2: dist2(llr.coords(slot), &q[..llr.n], &llr.period),
                seq: llr.seq[slot as usize],
                slot,
            })
            .collect();
        all.sort_by(|a, b| a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq)));
        all.iter().take(llr.k).map(|c| c.slot).collect()
    }

    /// `y = x + 2u`, stored as a process model stores (rate 0). Three samples at `u = 0` surround the query `(0.3, 0)`, one at
    /// `u = 2` shares its state. Nearest to `(0.3, 0)` in `(x, u)` are the three at
    /// `u = 0`: no slope along `u`. Nearest to `x = 0.3` alone (`lead = 1`) are the
    /// samples at `x = 0.3` (both), `0.31` and `0.29`: the exact `∂y/∂u = 2`, `∂y/∂x = 1`.
    #[test]
    fn near_chooses_the_neighbours_by_the_leading_inputs() {
        let mut llr = Llr::new(&params(2, 1, 10, 4));
        for xu in [
            [0.3, 0.0],
            [0.31, 0.0],
            [0.29, 0.0],
            [0.3, 2.0],
            [0.5, -2.0],
        ] {
            llr.fit(&xu, &[xu[0] + 2.0 * xu[1]], 0.0);
        }
        let mut llr3 = Llr::new(&params(2, 1, 10, 3));
        for xu in [[0.3, 0.0], [0.31, 0.0], [0.29, 0.0], [0.3, 2.0]] {
            llr3.fit(&xu, &[xu[0] + 2.0 * xu[1]], 0.0);
        }
        let (mut y, mut jac) = ([0.0], [0.0; 2]);
        llr3.value_and_jacobian(&[0.3, 0.0], &mut y, &mut jac);
        assert_eq!(jac[1], 0.0, "all three neighbours at u = 0");
        llr.value_and_jacobian_near(&[0.3, 0.0], 1, &mut y, &mut jac);
        // Exact up to the ridge (relative 2·10⁻⁵ on the small spread along x).
        assert!(
            (jac[0] - 1.0).abs() < 1e-4 && (jac[1] - 2.0).abs() < 1e-6,
            "{jac:?}"
        );
        assert!((y[0] - 0.3).abs() < 1e-6);
        // The action of the query moves the prediction along the fit, not the neighbours.
        llr.value_and_jacobian_near(&[0.3, 1.0], 1, &mut y, &mut jac);
        assert!((y[0] - 2.3).abs() < 1e-6 && (jac[1] - 2.0).abs() < 1e-6);
        // With all inputs leading it is the ordinary query.
        let (mut y2, mut jac2) = ([0.0], [0.0; 2]);
        llr.value_and_jacobian_near(&[0.3, 1.0], 2, &mut y, &mut jac);
        llr.value_and_jacobian(&[0.3, 1.0], &mut y2, &mut jac2);
        assert_eq!((y, jac), (y2, jac2));
    }

    #[test]
    fn reproduces_an_affine_function_exactly() {
        let mut llr = Llr::new(&LlrParams {
            weights: vec![1.0, 0.1, 2.0],
            ..params(3, 2, 500, 12)
        });
        let f = |x: &[f64]| {
            [
                1.5 - 2.0 * x[0] + 0.3 * x[1] + 4.0 * x[2],
                -0.5 + x[0] - x[2],
            ]
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..400 {
            let x = [
                rng.random_range(-3.0..3.0),
                rng.random_range(-20.0..20.0),
                rng.random_range(-1.0..1.0),
            ];
            llr.fit(&x, &f(&x), 0.0);
        }
        for _ in 0..50 {
            let x = [
                rng.random_range(-3.0..3.0),
                rng.random_range(-20.0..20.0),
                rng.random_range(-1.0..1.0),
            ];
            let (mut y, mut jac) = ([0.0; 2], [0.0; 6]);
            llr.value_and_jacobian(&x, &mut y, &mut jac);
            let want = f(&x);
            assert!(
                (y[0] - want[0]).abs() < 1e-6 && (y[1] - want[1]).abs() < 1e-6,
                "{y:?} vs {want:?}"
            );
            let want_jac = [-2.0, 0.3, 4.0, 1.0, 0.0, -1.0];
            for (a, b) in jac.iter().zip(&want_jac) {
                assert!((a - b).abs() < 1e-6, "{jac:?}");
            }
        }
    }

    #[test]
    fn kd_tree_and_scan_match_brute_force() {
        for (n, periodic) in [
            (2, vec![true, false]),
            (3, vec![true, false, false]),
            (6, vec![true, true, false, false, false, false]),
        ] {
            let mut p = params(n, 1, 700, 25);
            p.periodic = periodic;
            p.weights = (0..n).map(|j| 1.0 / (j + 1) as f64).collect();
            let mut tree = Llr::new(&p);
            let mut scan = Llr::new(&LlrParams {
                search: Search::Scan,
                ..p
            });
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            let pi = [std::f64::consts::PI; 8];
            for i in 0..1500 {
                let x: Vec<f64> = (0..n).map(|_| rng.random_range(-4.0..4.0)).collect();
                tree.fit(&x, &[i as f64], 0.0);
                scan.fit(&x, &[i as f64], 0.0);
                // Exact duplicates, as learning produces them.
                if i % 5 == 0 {
                    tree.fit(&pi[..n], &[0.0], 0.0);
                    scan.fit(&pi[..n], &[0.0], 0.0);
                }
            }
            let queries = (0..300).map(|_| {
                (0..n)
                    .map(|_| rng.random_range(-4.0..4.0))
                    .collect::<Vec<f64>>()
            });
            for x in queries.chain([pi[..n].to_vec()]) {
                let want = brute_force(&tree, &x);
                assert_eq!(neighbours(&tree, &x), want);
                assert_eq!(neighbours(&scan, &x), want);
            }
        }
    }

    #[test]
    fn neighbourhood_after_insertion_equals_a_fresh_search() {
        for eviction in [Eviction::Oldest, Eviction::Redundant(0.3)] {
            let mut p = params(2, 1, 300, 15);
            p.periodic = vec![true, false];
            p.eviction = eviction;
            let mut llr = Llr::new(&p);
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            for i in 0..2000 {
                // Coarse coordinates: many exact and near duplicates, full memory.
                let x = [
                    (rng.random_range(-6..6) as f64) * 0.5,
                    (rng.random_range(-20..20) as f64) * 0.5,
                ];
                let (_, after) = llr.insert_here(&x);
                let after: Vec<u32> = after.iter().map(|c| c.slot).collect();
                assert_eq!(after, brute_force(&llr, &x), "insertion {i}");
            }
        }
    }

    #[test]
    fn remembered_searches_stay_exact_across_insertions() {
        for eviction in [Eviction::Oldest, Eviction::Redundant(0.3)] {
            let mut p = params(2, 1, 200, 10);
            p.periodic = vec![true, false];
            p.eviction = eviction;
            let mut llr = Llr::new(&p);
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            let mut point = || {
                [
                    (rng.random_range(-6..6) as f64) * 0.5,
                    (rng.random_range(-20..20) as f64) * 0.5,
                ]
            };
            let queries: Vec<[f64; 2]> = (0..4).map(|_| point()).collect();
            for i in 0..1500 {
                let q = queries[i % 4];
                // Ask, insert elsewhere, ask again: the second answer comes from the cache.
                let _ = neighbours(&llr, &q);
                let x = point();
                llr.fit(&x, &[0.0], 0.0);
                assert_eq!(neighbours(&llr, &q), brute_force(&llr, &q), "step {i}");
                let (_, after) = llr.insert_here(&q);
                let after: Vec<u32> = after.iter().map(|c| c.slot).collect();
                assert_eq!(after, brute_force(&llr, &q), "step {i}");
            }
        }
    }

    #[test]
    fn clipping_stops_extrapolation_but_keeps_the_slope() {
        let mut p = params(1, 1, 10, 3);
        let mut plain = Llr::new(&p);
        p.clip_to_neighbours = true;
        let mut clipped = Llr::new(&p);
        for x in [0.0, 1.0, 2.0] {
            plain.fit(&[x], &[2.0 * x], 0.0);
            clipped.fit(&[x], &[2.0 * x], 0.0);
        }
        assert!((super::super::scalar(&plain, &[5.0]) - 10.0).abs() < 1e-6);
        assert!((super::super::scalar(&clipped, &[5.0]) - 4.0).abs() < 1e-12);
        assert!(
            (super::super::scalar(&clipped, &[1.5]) - 3.0).abs() < 1e-6,
            "interpolation unchanged"
        );
        let (mut y, mut jac) = ([0.0], [0.0]);
        clipped.value_and_jacobian(&[5.0], &mut y, &mut jac);
        assert!((jac[0] - 2.0).abs() < 1e-6);
    }

    #[test]
    fn angles_wrap_in_the_distance() {
        let mut p = params(1, 1, 10, 1);
        p.periodic = vec![true];
        let mut llr = Llr::new(&p);
        llr.fit(&[3.1], &[1.0], 0.0);
        llr.fit(&[0.0], &[2.0], 0.0);
        assert_eq!(super::super::scalar(&llr, &[-3.1]), 1.0);
    }

    #[test]
    fn repeated_samples_give_finite_predictions() {
        let mut llr = Llr::new(&params(3, 2, 200, 10));
        for i in 0..1000 {
            llr.fit(&[std::f64::consts::PI, 0.0, 3.0], &[i as f64, 1.0], 0.0);
        }
        let (mut y, mut jac) = ([0.0; 2], [0.0; 6]);
        llr.value_and_jacobian(&[std::f64::consts::PI, 0.0, 3.0], &mut y, &mut jac);
        assert!(y.iter().chain(&jac).all(|v| v.is_finite()));
        assert!(
            jac.iter().all(|v| *v == 0.0),
            "no slope from identical inputs"
        );
        // The mean of the 10 newest duplicates.
        assert!((y[0] - (990..1000).map(|i| i as f64).sum::<f64>() / 10.0).abs() < 1e-9);
        // Fewer samples than n + 1 (under-determined): finite, mean-like.
        let mut small = Llr::new(&params(3, 1, 200, 10));
        small.fit(&[0.0, 0.0, 0.0], &[1.0], 0.0);
        small.fit(&[1.0, 0.0, 0.0], &[3.0], 0.0);
        let v = super::super::scalar(&small, &[0.5, 0.0, 0.0]);
        assert!((v - 2.0).abs() < 1e-6, "{v}");
    }

    #[test]
    fn oldest_sample_is_purged() {
        let mut llr = Llr::new(&params(1, 1, 3, 1));
        for i in 0..5 {
            llr.fit(&[i as f64], &[i as f64], 0.0);
        }
        assert_eq!(llr.len(), 3);
        let mut xs: Vec<f64> = llr.samples().map(|(x, _)| x[0]).collect();
        xs.sort_by(f64::total_cmp);
        assert_eq!(xs, vec![2.0, 3.0, 4.0]);
    }

    #[test]
    fn redundant_sample_replaces_its_twin() {
        let mut p = params(1, 1, 3, 1);
        p.eviction = Eviction::Redundant(0.01);
        let mut llr = Llr::new(&p);
        llr.fit(&[0.0], &[0.0], 0.0);
        llr.fit(&[1.0], &[1.0], 0.0);
        llr.fit(&[2.0], &[2.0], 0.0);
        llr.fit(&[0.001], &[5.0], 0.0); // replaces the sample at 0, not the oldest
        let mut xs: Vec<(f64, f64)> = llr.samples().map(|(x, y)| (x[0], y[0])).collect();
        xs.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(xs, vec![(0.001, 5.0), (1.0, 1.0), (2.0, 2.0)]);
    }

    #[test]
    fn output_bounds_saturate_the_memory() {
        let mut p = params(1, 1, 10, 3);
        p.bounds = Some((vec![-3.0], vec![3.0]));
        let mut llr = Llr::new(&p);
        llr.fit(&[0.0], &[1.0], 0.0);
        for _ in 0..10 {
            llr.shift(&[0.0], &[2.0]);
        }
        assert!(llr.samples().all(|(_, y)| y[0] <= 3.0));
        assert_eq!(super::super::scalar(&llr, &[0.0]), 3.0);
    }

    #[test]
    fn traces_follow_replacing_eligibility() {
        let mut llr = Llr::new(&params(1, 1, 10, 1));
        llr.visit(&[0.0], 0.5); // sample A, trace 1
        llr.visit(&[10.0], 0.5); // A decays to 0.5, sample B trace 1
        llr.apply_td(2.0);
        let mut ys: Vec<(f64, f64)> = llr.samples().map(|(x, y)| (x[0], y[0])).collect();
        ys.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(ys, vec![(0.0, 1.0), (10.0, 2.0)]);
        llr.clear_traces();
        llr.apply_td(2.0);
        assert!(llr.samples().all(|(_, y)| y[0] <= 2.0));
    }
}
