//! The K samples nearest in the leading inputs only — a process model's neighbours by the
//! state, whatever the action ([`crate::approx::Differentiable::value_and_jacobian_near`]).
//!
//! Two ways to the same neighbours:
//!
//! * **by a scan** of the whole memory, a partial selection of the K nearest, fitted in
//!   the order the selection leaves them — VGBP's, whose recorded results hold those
//!   bits;
//! * **through an index** ([`NearIndex`]): a second [`KdTree`] over the leading inputs,
//!   built on the first such query and kept exact across insertions and evictions from
//!   then on (the main tree's rules: entries removed as their slots are overwritten, a
//!   balanced rebuild after [`REBUILD_AFTER`] times as many insertions as samples); the
//!   neighbours come ranked, nearest first and newer first among equals, and are fitted in
//!   that order — the planners' ([`crate::lqr`], [`crate::ilqr`]).
//!
//! A plan asks for neighbours along its rollout, then again along the next rollout a little
//! displaced, all on one memory. The latest searches through the index are remembered
//! until the stored inputs change, each with its K + 1 nearest: a query `δ` from a
//! remembered one whose K-th and (K+1)-th nearest are `r_K` and `r_{K+1}` away has the same
//! K nearest if `r_K + δ < r_{K+1} − δ` (the triangle inequality; the wrapped distance is
//! a metric), ranked anew at the query without a search; otherwise the nearest remembered
//! search's K + 1 samples bound the new search from its first node. Neither changes which
//! neighbours are found or their order (the tests compare them with a sort of the whole
//! memory).
//!
//! The set is the same either way, distances and ties being ranked by one total order; the
//! fits' sums run in another order, so the two fits agree to rounding, not bit for bit.
//! [`Search::Scan`] ranks by a scan and a sort of the K, for the tests.

use super::super::kdtree::{Best, Candidate, KdTree, LEAF_SIZE, MAX_DIM, dist2};
use super::fit::Fit;
use super::neighbours::REBUILD_AFTER;
use super::{Llr, Search};

/// How many of the latest searches through the index are remembered: a plan's queries, one
/// per planned sample (20 in the acrobot's), come again, displaced, in its next rollout.
const REMEMBERED: usize = 32;

/// Relative margin on distances compared across two queries, far above their rounding.
const MARGIN: f64 = 1e-9;

/// A k-d tree over the first `lead` scaled inputs of every stored sample, and the latest
/// searches through it while the stored inputs stay as they are.
pub(super) struct NearIndex {
    lead: usize,
    tree: KdTree,
    /// A ring of the latest searches; emptied by every insertion.
    recent: Vec<Remembered>,
    /// Where in `recent` the next search is remembered.
    next: usize,
    /// Queries answered from a remembered search.
    #[cfg(test)]
    recalled: usize,
}

/// A search through the index: its query and its K + 1 nearest samples, ranked, at their
/// squared distances to it.
struct Remembered {
    q: [f64; MAX_DIM],
    found: Vec<Candidate>,
}

impl Remembered {
    /// Whether the K nearest to a query `δ` away from this one are this search's K
    /// nearest: each of them is within `r_K + δ` of it, every other sample beyond
    /// `r_{K+1} − δ` (the triangle inequality), so they are if `r_K + δ < r_{K+1} − δ`.
    fn holds_within(&self, delta: f64, k: usize) -> bool {
        if self.found.len() != k + 1 {
            return false;
        }
        let (r_k, r_next) = (self.found[k - 1].d2.sqrt(), self.found[k].d2.sqrt());
        (r_k + delta) * (1.0 + MARGIN) < (r_next - delta) * (1.0 - MARGIN)
    }
}

impl NearIndex {
    fn new(lead: usize, tree: KdTree) -> Self {
        Self {
            lead,
            tree,
            recent: Vec::with_capacity(REMEMBERED),
            next: 0,
            #[cfg(test)]
            recalled: 0,
        }
    }

    /// The remembered search whose query is nearest to `q` (over the leading inputs,
    /// of periods `period`), and the squared distance between the two queries.
    fn nearest(&self, q: &[f64; MAX_DIM], period: &[f64]) -> Option<(&Remembered, f64)> {
        let lead = self.lead;
        self.recent
            .iter()
            .map(|r| (r, dist2(&r.q[..lead], &q[..lead], period)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// A buffer for the next search's list: the allocation of the search it will replace.
    fn buffer(&mut self) -> Vec<Candidate> {
        if self.recent.len() == REMEMBERED {
            std::mem::take(&mut self.recent[self.next].found)
        } else {
            Vec::new()
        }
    }

    /// Remembers a search, in place of the oldest once the ring is full.
    fn remember(&mut self, r: Remembered) {
        if self.recent.len() < REMEMBERED {
            self.recent.push(r);
        } else {
            self.recent[self.next] = r;
        }
        self.next = (self.next + 1) % REMEMBERED;
    }

    /// Forgets every search: the stored inputs are changing.
    fn forget(&mut self) {
        self.recent.clear();
        self.next = 0;
    }
}

/// The ranking of candidates: nearer first, newer first among equals.
fn rank(a: &Candidate, b: &Candidate) -> std::cmp::Ordering {
    a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq))
}

impl Llr {
    /// Every stored sample as a candidate at its distance from `q[..lead]`, the K nearest
    /// first in the order a partial selection leaves them; and K (or fewer, if the memory
    /// holds fewer).
    fn near_by_scan(&self, q: &[f64; MAX_DIM], lead: usize) -> (Vec<Candidate>, usize) {
        let mut all: Vec<Candidate> = (0..self.len as u32)
            .map(|slot| Candidate {
                d2: dist2(&self.coords(slot)[..lead], &q[..lead], &self.period[..lead]),
                seq: self.seq[slot as usize],
                slot,
            })
            .collect();
        let k = self.k.min(all.len());
        if k > 0 && k < all.len() {
            all.select_nth_unstable_by(k - 1, rank);
        }
        (all, k)
    }

    /// The fit to the K samples nearest to `q[..lead]`, found by a scan and fitted in the
    /// order a partial selection leaves them.
    pub(super) fn fit_near_by_scan(&self, q: &[f64; MAX_DIM], lead: usize, fit: &mut Fit) {
        let (all, k) = self.near_by_scan(q, lead);
        self.fit_local(q, &all[..k], fit);
    }

    /// The K samples nearest to `q[..lead]`, ranked, into `out`: through the
    /// [`NearIndex`] (built now if there is none over `lead` inputs), or with
    /// [`Search::Scan`] by a scan.
    pub(super) fn near_ranked(&self, q: &[f64; MAX_DIM], lead: usize, out: &mut Vec<Candidate>) {
        out.clear();
        if self.search == Search::Scan {
            let (mut all, k) = self.near_by_scan(q, lead);
            all.truncate(k);
            all.sort_unstable_by(rank);
            out.extend_from_slice(&all);
            return;
        }
        let mut near = self.near.borrow_mut();
        if near.as_ref().is_none_or(|i| i.lead != lead) {
            let mut tree = KdTree::new(lead);
            tree.rebuild(&self.leading(lead), &self.seq[..self.len]);
            *near = Some(NearIndex::new(lead, tree));
        }
        let index = near.as_mut().expect("built above");
        let period = &self.period[..lead];
        let nearest = index.nearest(q, period);
        if let Some((r, _)) = nearest.filter(|(r, d2)| r.holds_within(d2.sqrt(), self.k)) {
            // The same K samples, ranked at `q`.
            out.extend(r.found[..self.k].iter().map(|c| Candidate {
                d2: dist2(&self.coords(c.slot)[..lead], &q[..lead], period),
                ..*c
            }));
            out.sort_unstable_by(rank);
            #[cfg(test)]
            {
                index.recalled += 1;
            }
            return;
        }
        let ceiling = nearest.and_then(|(r, _)| self.ceiling(r, q, lead));
        let mut best = Best::reusing(self.k + 1, index.buffer());
        if let Some(ceiling) = ceiling {
            best.set_ceiling(ceiling);
        }
        index.tree.search(&q[..lead], period, &mut best);
        let found = best.into_sorted();
        out.extend_from_slice(&found[..found.len().min(self.k)]);
        index.remember(Remembered { q: *q, found });
    }

    /// A warm start for the search at `q`: the K + 1 samples of the remembered search `r`
    /// lie within the farthest of them from `q` (none if a distance is NaN, of a corrupt
    /// query, or `r` holds fewer).
    fn ceiling(&self, r: &Remembered, q: &[f64; MAX_DIM], lead: usize) -> Option<f64> {
        if r.found.len() != self.k + 1 {
            return None;
        }
        let period = &self.period[..lead];
        let d = r
            .found
            .iter()
            .map(|c| dist2(&self.coords(c.slot)[..lead], &q[..lead], period));
        let farthest = d.fold(0.0, |a: f64, d| if d > a || d.is_nan() { d } else { a });
        (!farthest.is_nan()).then_some(farthest)
    }

    /// The first `lead` scaled inputs of every stored sample, packed.
    fn leading(&self, lead: usize) -> Vec<f64> {
        (0..self.len)
            .flat_map(|s| self.inputs[s * self.n..s * self.n + lead].iter().copied())
            .collect()
    }

    /// Keeps the [`NearIndex`], if there is one, exact across the insertion of `slot`'s
    /// new sample (`replaced`: the slot held one before).
    pub(super) fn index_near(&mut self, slot: u32, seq: u64, replaced: bool) {
        let Some(index) = self.near.get_mut().as_mut() else {
            return;
        };
        index.forget();
        if replaced {
            index.tree.remove(slot);
        }
        let lead = index.lead;
        if index.tree.insertions() < REBUILD_AFTER * self.len + 8 * LEAF_SIZE {
            let at = slot as usize * self.n;
            index.tree.insert(&self.inputs[at..at + lead], slot, seq);
            return;
        }
        let coords = self.leading(lead);
        if let Some(index) = self.near.get_mut().as_mut() {
            index.tree.rebuild(&coords, &self.seq[..self.len]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::params;
    use super::super::{Eviction, LlrParams};
    use super::*;
    use crate::approx::{Approximator, Differentiable};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The reference: every sample, fully sorted by (distance over the leading inputs,
    /// newer first).
    fn brute_force(llr: &Llr, x: &[f64], lead: usize) -> Vec<(u32, u64)> {
        let q = llr.scale(x);
        let mut all: Vec<Candidate> = (0..llr.len as u32)
            .map(|slot| Candidate {
                d2: dist2(&llr.coords(slot)[..lead], &q[..lead], &llr.period[..lead]),
                seq: llr.seq[slot as usize],
                slot,
            })
            .collect();
        all.sort_by(rank);
        all.iter().take(llr.k).map(|c| (c.slot, c.seq)).collect()
    }

    fn ranked(llr: &Llr, x: &[f64], lead: usize) -> Vec<(u32, u64)> {
        let mut out = Vec::new();
        llr.near_ranked(&llr.scale(x), lead, &mut out);
        out.iter().map(|c| (c.slot, c.seq)).collect()
    }

    /// A memory of `[x (4, two angles) | u]` (some on a coarse grid: ties and duplicates), full and
    /// overwritten; queries walk in small steps (as a plan's rollouts move), jump now and
    /// then, repeat, and alternate with insertions. The index's neighbours, recalled or
    /// searched, equal a sort of the whole memory's, in order; the scan finds the same set.
    #[test]
    fn the_index_finds_the_nearest_by_the_leading_inputs_in_order() {
        let lead = 4;
        for eviction in [Eviction::Oldest, Eviction::Redundant(0.3)] {
            let p = LlrParams {
                periodic: vec![true, true, false, false, false],
                weights: vec![1.0, 0.7, 0.3, 0.2, 0.05],
                eviction,
                ..params(5, 4, 600, 12)
            };
            let (mut llr, mut scan) = (
                Llr::new(&p),
                Llr::new(&LlrParams {
                    search: Search::Scan,
                    ..p
                }),
            );
            let mut rng = ChaCha8Rng::seed_from_u64(17);
            // Every third sample on a coarse grid (ties and duplicates), the others anywhere.
            let point = |rng: &mut ChaCha8Rng, i: usize| -> Vec<f64> {
                (0..5)
                    .map(|_| match i % 3 {
                        0 => (rng.random_range(-8..8) as f64) * 0.4,
                        _ => rng.random_range(-3.2..3.2),
                    })
                    .collect()
            };
            let mut walk = point(&mut rng, 1);
            for i in 0..3000 {
                let x = point(&mut rng, i);
                llr.fit(&x, &[i as f64, 0.0, 1.0, -1.0], 0.0);
                scan.fit(&x, &[i as f64, 0.0, 1.0, -1.0], 0.0);
                if i < 600 && i % 50 != 0 {
                    continue;
                }
                for j in 0..8 {
                    if j % 4 == 0 {
                        walk = point(&mut rng, j);
                    }
                    for w in walk.iter_mut() {
                        *w += rng.random_range(-1e-3..1e-3);
                    }
                    let want = brute_force(&llr, &walk, lead);
                    assert_eq!(ranked(&llr, &walk, lead), want, "insertion {i}, query {j}");
                    assert_eq!(ranked(&scan, &walk, lead), want, "insertion {i}, query {j}");
                    let (mut set, _) = llr.near_by_scan(&llr.scale(&walk), lead);
                    set.truncate(llr.k);
                    let mut set: Vec<(u32, u64)> = set.iter().map(|c| (c.slot, c.seq)).collect();
                    let mut sorted = want.clone();
                    set.sort();
                    sorted.sort();
                    assert_eq!(set, sorted, "the scan's set, insertion {i}");
                }
            }
            let recalled = llr.near.borrow().as_ref().map_or(0, |i| i.recalled);
            assert!(recalled > 1000, "{eviction:?}: {recalled} queries recalled");
        }
    }

    /// The fit to the neighbours found through the index agrees with the scan's fit (the
    /// same neighbours, summed in another order) to rounding.
    #[test]
    fn the_indexed_fit_is_the_scans_to_rounding() {
        let p = LlrParams {
            periodic: vec![true, false, false],
            ..params(3, 2, 800, 10)
        };
        let mut llr = Llr::new(&p);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let f = |x: &[f64]| [x[0].sin() + 0.5 * x[2], x[1] * x[1] - x[2]];
        for _ in 0..2000 {
            let x: Vec<f64> = (0..3).map(|_| rng.random_range(-3.0..3.0)).collect();
            llr.fit(&x, &f(&x), 0.0);
        }
        for _ in 0..300 {
            let x: Vec<f64> = (0..3).map(|_| rng.random_range(-3.0..3.0)).collect();
            let (mut y, mut jac, mut y2, mut jac2) = ([0.0; 2], [0.0; 6], [0.0; 2], [0.0; 6]);
            llr.value_and_jacobian_near(&x, 2, &mut y, &mut jac);
            llr.value_and_jacobian_near_indexed(&x, 2, &mut y2, &mut jac2);
            for (a, b) in y.iter().chain(&jac).zip(y2.iter().chain(&jac2)) {
                assert!(
                    (a - b).abs() <= 1e-9 * a.abs().max(1.0),
                    "{y:?} {jac:?} vs {y2:?} {jac2:?}"
                );
            }
        }
    }
}
