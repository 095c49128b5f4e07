//! The bounded list of the K best candidate neighbours a search collects.

use super::MAX_K;

/// A candidate neighbour: squared distance, sequence number (tie-break: newer first),
/// memory slot. Distinct samples have distinct sequence numbers, so the order is total.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// Squared scaled distance to the query.
    pub d2: f64,
    /// Insertion sequence number of the sample (unique).
    pub seq: u64,
    /// Memory slot holding the sample.
    pub slot: u32,
}

impl Candidate {
    /// Whether `self` ranks before `other`: nearer, or as near and newer.
    #[inline]
    pub fn before(&self, other: &Candidate) -> bool {
        self.d2 < other.d2 || (self.d2 == other.d2 && self.seq > other.seq)
    }
}

/// The K best candidates so far, kept sorted nearest-first (newer first among equals):
/// an offer is inserted at its rank, so reading the set needs no sort. The order is
/// total — distance, then newer first — so the result does not depend on the order
/// candidates were offered in.
pub struct Best {
    items: Vec<Candidate>,
    k: usize,
    /// Candidates farther than this are not wanted (see [`Best::set_ceiling`]).
    ceiling: f64,
}

impl Best {
    /// An empty set that keeps at most `k ≤ MAX_K + 2` candidates.
    pub fn new(k: usize) -> Self {
        Self::reusing(k, Vec::new())
    }

    /// [`Best::new`], keeping the candidates in `buffer` (cleared), so that its
    /// allocation serves again.
    pub fn reusing(k: usize, mut buffer: Vec<Candidate>) -> Self {
        debug_assert!((1..=MAX_K + 2).contains(&k));
        buffer.clear();
        buffer.reserve(k);
        Self {
            items: buffer,
            k,
            ceiling: f64::INFINITY,
        }
    }

    /// Declares that at least `k` candidates lie within squared distance `d2`, so that
    /// no farther one can enter the set: the search prunes with this bound until the set
    /// is full (a warm start). Candidates at exactly `d2` are still admitted.
    pub fn set_ceiling(&mut self, d2: f64) {
        self.ceiling = d2;
    }

    /// The squared distance a candidate must not exceed to enter the set.
    #[inline(always)]
    pub(super) fn bound(&self) -> f64 {
        if self.items.len() == self.k {
            self.items[self.k - 1].d2
        } else {
            self.ceiling
        }
    }

    /// Offers a candidate.
    #[inline(always)]
    pub fn offer(&mut self, c: Candidate) {
        let len = self.items.len();
        if len == self.k {
            if !c.before(&self.items[len - 1]) {
                return;
            }
            self.items.pop();
        }
        // Insertion from the end (measured: about 6 items move per offer).
        self.items.push(c);
        let h = &mut self.items[..];
        let mut i = h.len() - 1;
        while i > 0 && c.before(&h[i - 1]) {
            h[i] = h[i - 1];
            i -= 1;
        }
        h[i] = c;
    }

    /// Whether a candidate at squared distance `d2` could enter the set.
    #[inline(always)]
    pub(super) fn admits(&self, d2: f64) -> bool {
        d2 <= self.bound()
    }

    /// Whether `lower_bound` cannot beat the current worst candidate.
    #[inline(always)]
    pub(super) fn prunes(&self, lower_bound: f64) -> bool {
        lower_bound > self.bound()
    }

    /// How many candidates this set keeps.
    pub fn capacity(&self) -> usize {
        self.k
    }

    /// The candidates, nearest first (newer first among equals).
    pub fn sorted(&self) -> &[Candidate] {
        &self.items
    }

    /// The candidates, nearest first (newer first among equals), as a vector.
    pub fn into_sorted(self) -> Vec<Candidate> {
        self.items
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn best_keeps_the_k_nearest_in_order_whatever_the_offer_order() {
        let cands: Vec<Candidate> = (0..50u64)
            .map(|i| Candidate {
                d2: ((i * 37) % 11) as f64,
                seq: i,
                slot: i as u32,
            })
            .collect();
        let mut want = cands.clone();
        want.sort_by(|a, b| a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq)));
        for rot in [0, 7, 23] {
            let mut best = Best::new(12);
            for i in 0..cands.len() {
                best.offer(cands[(i + rot) % cands.len()]);
                if i == 20 {
                    // Looking at the set midway must not disturb it.
                    let _ = best.sorted();
                }
            }
            assert_eq!(best.sorted(), &want[..12]);
        }
    }
}
