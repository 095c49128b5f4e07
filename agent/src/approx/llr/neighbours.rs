//! The K nearest neighbours of a query (§3.5.2): a search of the
//! [`KdTree`](super::super::kdtree::KdTree) (or a scan),
//! warm-started from the remembered searches, which insertions keep exact.

use super::super::kdtree::{Best, Candidate, LEAF_SIZE, MAX_DIM, dist2};
use super::{Llr, Search, same_bits};

/// A remembered neighbour search: the query (bit-exact), its scaled coordinates, and the
/// true nearest samples of the memory as it is now — insertions keep the list exact
/// (see `Llr::update_cache`), possibly shorter.
pub(super) struct Cached {
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
pub(super) const REBUILD_AFTER: usize = 4;

/// How many neighbours beyond K + 1 a search keeps, so that a remembered search survives
/// this many insertions (each can remove one of its samples).
pub(super) const CACHE_SLACK: usize = 1;

impl Llr {
    /// The `count ≤ K + 1` nearest stored samples to the scaled query `q`, into `out`. A
    /// search keeps K + 2 and is remembered, so a value query and a later insertion at
    /// the same point share one search, even with one insertion elsewhere in between.
    pub(super) fn nearest(&self, q: &[f64; MAX_DIM], count: usize, out: &mut Vec<Candidate>) {
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
    pub(super) fn update_cache(&mut self, new: Candidate, removed: Option<u32>) {
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

    /// Adds a new sample to the search index, removing the entry of the sample it
    /// `replaced` in `slot`; rebuilds the tree, balanced, after [`REBUILD_AFTER`] times
    /// as many insertions as samples.
    pub(super) fn index(&mut self, slot: u32, seq: u64, replaced: bool) {
        self.index_near(slot, seq, replaced);
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
}
