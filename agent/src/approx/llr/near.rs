//! The K samples nearest in the leading inputs only — a process model's neighbours by the
//! state, whatever the action ([`Differentiable::value_and_jacobian_near`]).
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
//! The set is the same either way, distances and ties being ranked by one total order; the
//! fits' sums run in another order, so the two fits agree to rounding, not bit for bit.
//! [`Search::Scan`] ranks by a scan and a sort of the K, for the tests.

use super::super::kdtree::{Best, Candidate, KdTree, LEAF_SIZE, MAX_DIM, dist2};
use super::fit::Fit;
use super::neighbours::REBUILD_AFTER;
use super::{Llr, Search};

/// A k-d tree over the first `lead` scaled inputs of every stored sample.
pub(super) struct NearIndex {
    lead: usize,
    tree: KdTree,
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
            *near = Some(NearIndex { lead, tree });
        }
        let index = near.as_ref().expect("built above");
        let mut best = Best::reusing(self.k, std::mem::take(out));
        index
            .tree
            .search(&q[..lead], &self.period[..lead], &mut best);
        *out = best.into_sorted();
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
