//! A static k-d tree over the LLR memory, for the K-nearest-neighbour search of §3.5.2
//! ("one can reduce the computational burden by using, for instance, k-d trees").
//!
//! The tree is dynamic: a new sample descends to a leaf, widening the bounding boxes on
//! its way, and a leaf that grows past [`LEAF_SIZE`] splits at its median along its
//! widest axis. A sample that the memory overwrites stays in the tree as a stale entry,
//! recognised by its sequence number and skipped; when stale entries reach a quarter of
//! the live ones the memory rebuilds the tree, balanced, from scratch — amortised
//! O(log N) per insertion. A search can be warm-started by offering candidates to
//! [`Best`] first (`Llr` offers the remembered neighbours of a nearby query): the bound is
//! then tight from the first node. Pruning uses the bounding boxes only, so correctness
//! never depends on the split values, and any number of identical samples (every trial starts at `[π, 0]`,
//! saturated actions repeat) only makes a leaf larger, never breaks the tree.
//!
//! Distances are squared Euclidean on pre-scaled coordinates, with periodic components
//! (angles) compared by their wrapped difference. Ties are broken in favour of the newer
//! sample (higher insertion sequence number: fresher information), so the neighbour set
//! is a pure function of the memory contents — the tree and a brute-force scan return
//! exactly the same neighbours.

/// Maximum number of neighbours a query may ask for.
pub const MAX_K: usize = 128;
/// Maximum input dimension of an LLR memory.
pub const MAX_DIM: usize = 8;
/// Entries per leaf before it splits.
pub const LEAF_SIZE: usize = 12;
const NO_CHILD: u32 = u32::MAX;

/// Squared distance between two scaled points; `period[j] > 0` marks a periodic axis.
#[inline]
pub fn dist2(a: &[f64], b: &[f64], period: &[f64]) -> f64 {
    let mut s = 0.0;
    for j in 0..a.len() {
        let mut d = (a[j] - b[j]).abs();
        if period[j] > 0.0 && d > 0.5 * period[j] {
            d = period[j] - d;
        }
        s += d * d;
    }
    s
}

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

/// The K best candidates so far: a bounded max-heap (worst candidate on top), sorted
/// nearest-first once by [`Best::sorted`]. The order is total — distance, then newer
/// first — so the result does not depend on the order candidates were offered in.
pub struct Best {
    items: Vec<Candidate>,
    len: usize,
    k: usize,
    sorted: bool,
}

impl Best {
    /// An empty set that keeps at most `k ≤ MAX_K + 2` candidates.
    pub fn new(k: usize) -> Self {
        debug_assert!((1..=MAX_K + 2).contains(&k));
        Self {
            items: vec![
                Candidate {
                    d2: 0.0,
                    seq: 0,
                    slot: 0
                };
                k
            ],
            len: 0,
            k,
            sorted: true,
        }
    }

    /// Offers a candidate.
    #[inline(always)]
    pub fn offer(&mut self, c: Candidate) {
        if self.sorted {
            // Nearest-first order reversed is worst-first: a valid max-heap again.
            self.items[..self.len].reverse();
        }
        let h = &mut self.items;
        if self.len < self.k {
            // Push and sift up.
            let mut i = self.len;
            self.len += 1;
            while i > 0 {
                let parent = (i - 1) / 2;
                if !h[parent].before(&c) {
                    break;
                }
                h[i] = h[parent];
                i = parent;
            }
            h[i] = c;
        } else if c.before(&h[0]) {
            // Replace the worst and sift down.
            let mut i = 0;
            loop {
                let (l, r) = (2 * i + 1, 2 * i + 2);
                let mut worst = i;
                let mut w = c;
                if l < self.len && w.before(&h[l]) {
                    worst = l;
                    w = h[l];
                }
                if r < self.len && w.before(&h[r]) {
                    worst = r;
                }
                if worst == i {
                    break;
                }
                h[i] = h[worst];
                i = worst;
            }
            h[i] = c;
        } else {
            self.sorted = false;
            return;
        }
        self.sorted = false;
    }

    /// Whether a candidate at squared distance `d2` could enter the set.
    #[inline(always)]
    fn admits(&self, d2: f64) -> bool {
        self.len < self.k || d2 <= self.items[0].d2
    }

    /// Whether `lower_bound` cannot beat the current worst candidate.
    #[inline]
    fn prunes(&self, lower_bound: f64) -> bool {
        self.len == self.k && lower_bound > self.items[0].d2
    }

    /// How many candidates this set keeps.
    pub fn capacity(&self) -> usize {
        self.k
    }

    /// The candidates, nearest first (newer first among equals).
    pub fn sorted(&mut self) -> &[Candidate] {
        if !self.sorted {
            self.items[..self.len]
                .sort_unstable_by(|a, b| a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq)));
            self.sorted = true;
        }
        &self.items[..self.len]
    }
}

/// A stored point: scaled coordinates, memory slot, sequence number.
#[derive(Clone, Copy)]
struct Entry {
    p: [f64; MAX_DIM],
    slot: u32,
    seq: u64,
}

#[derive(Clone)]
struct Node {
    lo: [f64; MAX_DIM],
    hi: [f64; MAX_DIM],
    axis: usize,
    split: f64,
    left: u32,
    right: u32,
    /// Entries of a leaf (empty for an inner node): coordinates packed `dim` per entry,
    /// then slots and sequence numbers.
    coords: Vec<f64>,
    slots: Vec<u32>,
    seqs: Vec<u64>,
}

impl Node {
    fn leaf(entries: Vec<Entry>, dim: usize) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; MAX_DIM], [f64::NEG_INFINITY; MAX_DIM]);
        for e in &entries {
            for j in 0..dim {
                lo[j] = lo[j].min(e.p[j]);
                hi[j] = hi[j].max(e.p[j]);
            }
        }
        let mut node = Node {
            lo,
            hi,
            axis: 0,
            split: 0.0,
            left: NO_CHILD,
            right: NO_CHILD,
            coords: Vec::with_capacity(entries.len() * dim),
            slots: Vec::with_capacity(entries.len()),
            seqs: Vec::with_capacity(entries.len()),
        };
        for e in &entries {
            node.push(e, dim);
        }
        node
    }

    fn push(&mut self, e: &Entry, dim: usize) {
        self.coords.extend_from_slice(&e.p[..dim]);
        self.slots.push(e.slot);
        self.seqs.push(e.seq);
    }

    fn len(&self) -> usize {
        self.slots.len()
    }

    /// The leaf's entries, unpacked (for splitting).
    fn take_entries(&mut self, dim: usize) -> Vec<Entry> {
        let out = (0..self.len())
            .map(|i| {
                let mut p = [0.0; MAX_DIM];
                p[..dim].copy_from_slice(&self.coords[i * dim..(i + 1) * dim]);
                Entry {
                    p,
                    slot: self.slots[i],
                    seq: self.seqs[i],
                }
            })
            .collect();
        self.coords = Vec::new();
        self.slots = Vec::new();
        self.seqs = Vec::new();
        out
    }

    fn is_leaf(&self) -> bool {
        self.left == NO_CHILD
    }

    /// Widest axis of the bounding box, if it has any extent.
    fn widest(&self, dim: usize) -> Option<usize> {
        let axis = (0..dim)
            .max_by(|&a, &b| (self.hi[a] - self.lo[a]).total_cmp(&(self.hi[b] - self.lo[b])))?;
        (self.hi[axis] > self.lo[axis]).then_some(axis)
    }
}

/// A dynamic k-d tree over scaled points.
pub struct KdTree {
    dim: usize,
    nodes: Vec<Node>,
    entries: usize,
}

impl KdTree {
    /// An empty tree for `dim`-dimensional points.
    pub fn new(dim: usize) -> Self {
        Self {
            dim,
            nodes: vec![Node::leaf(Vec::new(), dim)],
            entries: 0,
        }
    }

    /// A balanced tree over `items` = (slot, seq), whose scaled coordinates are
    /// `coords(slot)`.
    pub fn build<'a>(dim: usize, items: &[(u32, u64)], coords: impl Fn(u32) -> &'a [f64]) -> Self {
        let entries: Vec<Entry> = items
            .iter()
            .map(|&(slot, seq)| {
                let mut p = [0.0; MAX_DIM];
                p[..dim].copy_from_slice(coords(slot));
                Entry { p, slot, seq }
            })
            .collect();
        let mut tree = Self {
            dim,
            nodes: Vec::with_capacity(2 * items.len() / LEAF_SIZE + 1),
            entries: entries.len(),
        };
        tree.grow(entries);
        tree
    }

    /// Adds node(s) holding `entries`, split recursively; returns the subtree's root.
    fn grow(&mut self, mut all: Vec<Entry>) -> u32 {
        let id = self.nodes.len() as u32;
        let leaf = Node::leaf(Vec::new(), self.dim);
        self.nodes.push(leaf);
        let probe = Node::leaf(all.clone(), self.dim);
        let axis = if all.len() > LEAF_SIZE {
            probe.widest(self.dim)
        } else {
            None
        };
        let Some(axis) = axis else {
            self.nodes[id as usize] = probe;
            return id;
        };
        let (lo, hi) = (probe.lo, probe.hi);
        let mid = all.len() / 2;
        all.select_nth_unstable_by(mid, |a, b| {
            a.p[axis].total_cmp(&b.p[axis]).then(a.seq.cmp(&b.seq))
        });
        let split = all[mid].p[axis];
        let right_entries = all.split_off(mid);
        let left = self.grow(all);
        let right = self.grow(right_entries);
        self.nodes[id as usize] = Node {
            lo,
            hi,
            axis,
            split,
            left,
            right,
            ..Node::leaf(Vec::new(), self.dim)
        };
        id
    }

    /// Inserts a point.
    pub fn insert(&mut self, p: &[f64], slot: u32, seq: u64) {
        let mut e = Entry {
            p: [0.0; MAX_DIM],
            slot,
            seq,
        };
        e.p[..self.dim].copy_from_slice(p);
        self.entries += 1;
        let mut id = 0usize;
        loop {
            let node = &mut self.nodes[id];
            for j in 0..self.dim {
                node.lo[j] = node.lo[j].min(p[j]);
                node.hi[j] = node.hi[j].max(p[j]);
            }
            if node.is_leaf() {
                node.push(&e, self.dim);
                if node.len() > 2 * LEAF_SIZE {
                    self.split_leaf(id);
                }
                return;
            }
            id = if p[node.axis] < node.split {
                node.left
            } else {
                node.right
            } as usize;
        }
    }

    /// Splits an overfull leaf in place (no-op if all its points coincide).
    fn split_leaf(&mut self, id: usize) {
        let Some(_) = self.nodes[id].widest(self.dim) else {
            return;
        };
        let entries = self.nodes[id].take_entries(self.dim);
        let sub = self.grow(entries);
        // The grown subtree's root replaces the leaf (its own slot is left unused).
        self.nodes.swap(id, sub as usize);
        self.nodes[sub as usize] = Node::leaf(Vec::new(), self.dim);
    }

    /// Offers every live point of the tree that can still improve `best`;
    /// `live(slot, seq)` says whether an entry is still in the memory.
    pub fn search(
        &self,
        q: &[f64],
        period: &[f64],
        best: &mut Best,
        live: impl Fn(u32, u64) -> bool,
    ) {
        // Monomorphised per dimension, so that the distance loops unroll.
        match self.dim {
            1 => self.search_in::<1>(q, period, best, live),
            2 => self.search_in::<2>(q, period, best, live),
            3 => self.search_in::<3>(q, period, best, live),
            4 => self.search_in::<4>(q, period, best, live),
            5 => self.search_in::<5>(q, period, best, live),
            6 => self.search_in::<6>(q, period, best, live),
            7 => self.search_in::<7>(q, period, best, live),
            _ => self.search_in::<MAX_DIM>(q, period, best, live),
        }
    }

    fn search_in<const D: usize>(
        &self,
        q: &[f64],
        period: &[f64],
        best: &mut Best,
        live: impl Fn(u32, u64) -> bool,
    ) {
        let q: &[f64; D] = q.try_into().expect("query of the tree's dimension");
        let period: &[f64; D] = period.try_into().expect("periods of the tree's dimension");
        let box_dist2 = |node: &Node| -> f64 {
            let mut s = 0.0;
            for j in 0..D {
                let x = q[j];
                if x >= node.lo[j] && x <= node.hi[j] {
                    continue;
                }
                let (mut a, mut b) = ((x - node.lo[j]).abs(), (x - node.hi[j]).abs());
                if period[j] > 0.0 {
                    a = a.min(period[j] - a);
                    b = b.min(period[j] - b);
                }
                let m = a.min(b);
                s += m * m;
            }
            s
        };
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        stack.push((0, box_dist2(&self.nodes[0])));
        while let Some((id, lb)) = stack.pop() {
            if best.prunes(lb) {
                continue;
            }
            let node = &self.nodes[id as usize];
            if node.is_leaf() {
                for ((p, &slot), &seq) in
                    node.coords.chunks_exact(D).zip(&node.slots).zip(&node.seqs)
                {
                    let p: &[f64; D] = p.try_into().expect("chunks of D");
                    let d2 = dist2(p, q, period);
                    if best.admits(d2) && live(slot, seq) {
                        best.offer(Candidate { d2, seq, slot });
                    }
                }
                continue;
            }
            let dl = box_dist2(&self.nodes[node.left as usize]);
            let dr = box_dist2(&self.nodes[node.right as usize]);
            // Push the farther child first so the nearer one is searched first.
            let (near, far) = if dl <= dr {
                ((node.left, dl), (node.right, dr))
            } else {
                ((node.right, dr), (node.left, dl))
            };
            stack.push(far);
            stack.push(near);
        }
    }

    /// Entries in the tree, stale ones included.
    pub fn entries(&self) -> usize {
        self.entries
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
