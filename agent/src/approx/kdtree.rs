//! A k-d tree over the LLR memory, for the K-nearest-neighbour search of §3.5.2
//! ("one can reduce the computational burden by using, for instance, k-d trees").
//!
//! The tree is dynamic: a new sample descends to a leaf, widening the bounding boxes on
//! its way, and a leaf that grows past [`LEAF_SIZE`] splits at its median along its
//! widest axis. A sample that the memory overwrites is removed from its leaf (the tree
//! knows each slot's leaf), leaving the boxes as they are; now and then the memory
//! rebuilds the tree, balanced, from scratch, to tighten them again — amortised
//! O(log N) per insertion. A search can be warm-started with a ceiling on [`Best`] (`Llr`
//! takes the farthest of the remembered neighbours of a nearby query): the bound is then
//! tight from the first node. Pruning uses the bounding boxes only, so correctness
//! never depends on the split values, and any number of identical samples (every trial starts at `[π, 0]`,
//! saturated actions repeat) only makes a leaf larger, never breaks the tree.
//!
//! Distances are squared Euclidean on pre-scaled coordinates, with periodic components
//! (angles) compared by their wrapped difference. Ties are broken in favour of the newer
//! sample (higher insertion sequence number: fresher information), so the neighbour set
//! is a pure function of the memory contents — the tree and a brute-force scan return
//! exactly the same neighbours.
//!
//! # Speed
//!
//! The search's layout (separate link, box and entry vectors; branch-free box and leaf
//! distances; a sorted [`Best`]; [`LEAF_SIZE`] 32; removal of overwritten samples) was
//! chosen by measurement: `docs/results/llr-search.md` lists each change, its effect and
//! what was tried and dropped. None of it changes which neighbours are found or in which
//! order.

/// Maximum number of neighbours a query may ask for.
pub const MAX_K: usize = 128;
/// Maximum input dimension of an LLR memory.
pub const MAX_DIM: usize = 8;
/// Entries per leaf of a balanced build; an insertion splits a leaf that grows past
/// twice this many (see the module notes on speed for the choice).
pub const LEAF_SIZE: usize = 32;
const NO_CHILD: u32 = u32::MAX;
/// Leaf entries whose distances a search computes in one pass.
const SCAN_BLOCK: usize = 2 * LEAF_SIZE;
// Positions within a block are stored as `u8`.
const _: () = assert!(SCAN_BLOCK <= 256);

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
    fn bound(&self) -> f64 {
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
    fn admits(&self, d2: f64) -> bool {
        d2 <= self.bound()
    }

    /// Whether `lower_bound` cannot beat the current worst candidate.
    #[inline(always)]
    fn prunes(&self, lower_bound: f64) -> bool {
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

/// The points a subtree is grown from: point `i` has the scaled coordinates
/// `coords[i·dim..(i + 1)·dim]`, the sequence number `seqs[i]` and the memory slot
/// `slots[i]` (or `i` itself without `slots`: a whole memory).
struct Points<'a> {
    dim: usize,
    coords: &'a [f64],
    slots: Option<&'a [u32]>,
    seqs: &'a [u64],
}

impl Points<'_> {
    fn coords(&self, i: u32) -> &[f64] {
        &self.coords[i as usize * self.dim..(i as usize + 1) * self.dim]
    }

    fn slot(&self, i: u32) -> u32 {
        self.slots.map_or(i, |slots| slots[i as usize])
    }
}

/// A node's links; its bounding box lives in [`KdTree::boxes`].
#[derive(Clone, Copy)]
struct Node {
    /// Split value along `axis` (inner nodes; insertion goes left below it).
    split: f64,
    axis: u32,
    /// Left child, or [`NO_CHILD`] for a leaf.
    left: u32,
    /// Right child, or, for a leaf, its index in [`KdTree::leaves`].
    right: u32,
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.left == NO_CHILD
    }
}

/// The entries of a leaf: coordinates packed `dim` per entry, then slots and sequence
/// numbers.
#[derive(Clone, Default)]
struct Leaf {
    coords: Vec<f64>,
    slots: Vec<u32>,
    seqs: Vec<u64>,
}

impl Leaf {
    fn push(&mut self, p: &[f64], slot: u32, seq: u64) {
        self.coords.extend_from_slice(p);
        self.slots.push(slot);
        self.seqs.push(seq);
    }

    fn clear(&mut self) {
        self.coords.clear();
        self.slots.clear();
        self.seqs.clear();
    }

    fn len(&self) -> usize {
        self.slots.len()
    }
}

/// A dynamic k-d tree over scaled points.
///
/// Layout (for the search's memory traffic): node links, bounding boxes (`2·dim` floats
/// per node, lower corner then upper) and leaf entries live in separate vectors, so a
/// search touches 16 bytes of links and `16·dim` bytes of box per node.
pub struct KdTree {
    dim: usize,
    nodes: Vec<Node>,
    /// Bounding boxes, `2 * dim` per node: `lo[..dim]`, then `hi[..dim]`.
    boxes: Vec<f64>,
    leaves: Vec<Leaf>,
    /// Leaves emptied by a split or a rebuild, for reuse.
    free_leaves: Vec<u32>,
    /// The leaf (index in `leaves`) holding each memory slot's entry, by slot.
    leaf_of: Vec<u32>,
    entries: usize,
    /// Insertions since the last balanced build.
    insertions: usize,
    /// The search's stack, kept between searches to avoid an allocation per search.
    stack: std::cell::RefCell<Vec<(u32, f64)>>,
}

impl KdTree {
    /// An empty tree for `dim`-dimensional points.
    pub fn new(dim: usize) -> Self {
        let mut tree = Self {
            dim,
            nodes: Vec::new(),
            boxes: Vec::new(),
            leaves: Vec::new(),
            free_leaves: Vec::new(),
            leaf_of: Vec::new(),
            entries: 0,
            insertions: 0,
            stack: std::cell::RefCell::new(Vec::with_capacity(64)),
        };
        tree.rebuild(&[], &[]);
        tree
    }

    /// Replaces the contents by a balanced tree over a whole memory: sample `i` (in
    /// slot `i`) has the scaled coordinates `coords[i·dim..(i + 1)·dim]` and the
    /// sequence number `seqs[i]`. The storage of the old tree is reused.
    pub fn rebuild(&mut self, coords: &[f64], seqs: &[u64]) {
        self.nodes.clear();
        self.boxes.clear();
        self.free_leaves.clear();
        for (l, leaf) in self.leaves.iter_mut().enumerate().rev() {
            leaf.clear();
            self.free_leaves.push(l as u32);
        }
        self.entries = seqs.len();
        self.insertions = 0;
        self.leaf_of.resize(seqs.len(), u32::MAX);
        let points = Points {
            dim: self.dim,
            coords,
            slots: None,
            seqs,
        };
        let mut order: Vec<u32> = (0..seqs.len() as u32).collect();
        self.grow(&points, &mut order);
    }

    /// Bounding box of the points `order` (empty: `+∞` below `−∞`).
    fn bbox(&self, points: &Points, order: &[u32]) -> ([f64; MAX_DIM], [f64; MAX_DIM]) {
        let (mut lo, mut hi) = ([f64::INFINITY; MAX_DIM], [f64::NEG_INFINITY; MAX_DIM]);
        for &i in order {
            for (j, &v) in points.coords(i).iter().enumerate() {
                lo[j] = lo[j].min(v);
                hi[j] = hi[j].max(v);
            }
        }
        (lo, hi)
    }

    /// Widest axis of a bounding box, if it has any extent.
    fn widest(&self, lo: &[f64], hi: &[f64]) -> Option<usize> {
        let axis = (0..self.dim).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))?;
        (hi[axis] > lo[axis]).then_some(axis)
    }

    /// Appends a node with the given box; returns its id.
    fn add_node(&mut self, node: Node, lo: &[f64], hi: &[f64]) -> u32 {
        let id = self.nodes.len() as u32;
        self.nodes.push(node);
        self.boxes.extend_from_slice(&lo[..self.dim]);
        self.boxes.extend_from_slice(&hi[..self.dim]);
        id
    }

    /// Appends a leaf node holding the points `order`; returns its id.
    fn add_leaf(&mut self, points: &Points, order: &[u32]) -> u32 {
        let leaf = match self.free_leaves.pop() {
            Some(l) => l,
            None => {
                self.leaves.push(Leaf::default());
                (self.leaves.len() - 1) as u32
            }
        };
        let store = &mut self.leaves[leaf as usize];
        store.coords.reserve(order.len() * points.dim);
        store.slots.reserve(order.len());
        store.seqs.reserve(order.len());
        for &i in order {
            let slot = points.slot(i);
            store.push(points.coords(i), slot, points.seqs[i as usize]);
            self.leaf_of[slot as usize] = leaf;
        }
        let (lo, hi) = self.bbox(points, order);
        let node = Node {
            split: 0.0,
            axis: 0,
            left: NO_CHILD,
            right: leaf,
        };
        self.add_node(node, &lo, &hi)
    }

    /// Adds node(s) holding the points `order`, split recursively at the median of the
    /// widest axis; returns the subtree's root. `order` is permuted (indices are moved,
    /// not points).
    fn grow(&mut self, points: &Points, order: &mut [u32]) -> u32 {
        let (lo, hi) = self.bbox(points, order);
        let axis = if order.len() > LEAF_SIZE {
            self.widest(&lo, &hi)
        } else {
            None
        };
        let Some(axis) = axis else {
            return self.add_leaf(points, order);
        };
        let mid = order.len() / 2;
        let at = |i: u32| points.coords[i as usize * points.dim + axis];
        order.select_nth_unstable_by(mid, |&a, &b| {
            at(a)
                .total_cmp(&at(b))
                .then(points.seqs[a as usize].cmp(&points.seqs[b as usize]))
        });
        let split = at(order[mid]);
        let id = self.add_node(
            Node {
                split,
                axis: axis as u32,
                left: NO_CHILD,
                right: NO_CHILD,
            },
            &lo,
            &hi,
        );
        let (left, right) = order.split_at_mut(mid);
        let left = self.grow(points, left);
        let right = self.grow(points, right);
        self.nodes[id as usize].left = left;
        self.nodes[id as usize].right = right;
        id
    }

    /// Inserts a point.
    pub fn insert(&mut self, p: &[f64], slot: u32, seq: u64) {
        let dim = self.dim;
        self.entries += 1;
        self.insertions += 1;
        if slot as usize >= self.leaf_of.len() {
            self.leaf_of.resize(slot as usize + 1, u32::MAX);
        }
        let mut id = 0usize;
        loop {
            let b = &mut self.boxes[2 * dim * id..2 * dim * (id + 1)];
            for j in 0..dim {
                b[j] = b[j].min(p[j]);
                b[dim + j] = b[dim + j].max(p[j]);
            }
            let node = self.nodes[id];
            if node.is_leaf() {
                self.leaf_of[slot as usize] = node.right;
                let leaf = &mut self.leaves[node.right as usize];
                leaf.push(p, slot, seq);
                if leaf.len() > 2 * LEAF_SIZE {
                    self.split_leaf(id);
                }
                return;
            }
            id = if p[node.axis as usize] < node.split {
                node.left
            } else {
                node.right
            } as usize;
        }
    }

    /// Removes the entry of memory slot `slot`, which must be in the tree (its sample is
    /// being overwritten). Bounding boxes are not narrowed: they stay valid bounds.
    pub fn remove(&mut self, slot: u32) {
        let dim = self.dim;
        let leaf = &mut self.leaves[self.leaf_of[slot as usize] as usize];
        let at = leaf
            .slots
            .iter()
            .position(|&s| s == slot)
            .expect("the slot's entry is in its leaf");
        let last = leaf.len() - 1;
        leaf.slots.swap_remove(at);
        leaf.seqs.swap_remove(at);
        leaf.coords
            .copy_within(last * dim..(last + 1) * dim, at * dim);
        leaf.coords.truncate(last * dim);
        self.entries -= 1;
    }

    /// Splits an overfull leaf in place (no-op if all its points coincide).
    fn split_leaf(&mut self, id: usize) {
        let dim = self.dim;
        let b = &self.boxes[2 * dim * id..2 * dim * (id + 1)];
        if self.widest(&b[..dim], &b[dim..]).is_none() {
            return;
        }
        let leaf = self.nodes[id].right;
        let store = std::mem::take(&mut self.leaves[leaf as usize]);
        self.free_leaves.push(leaf);
        let points = Points {
            dim,
            coords: &store.coords,
            slots: Some(&store.slots),
            seqs: &store.seqs,
        };
        let mut order: Vec<u32> = (0..store.len() as u32).collect();
        let sub = self.grow(&points, &mut order) as usize;
        // The grown subtree's root replaces the leaf (its own node is left unused).
        self.nodes[id] = self.nodes[sub];
        self.boxes
            .copy_within(2 * dim * sub..2 * dim * (sub + 1), 2 * dim * id);
    }

    /// Offers every point of the tree that can still improve `best`.
    pub fn search(&self, q: &[f64], period: &[f64], best: &mut Best) {
        // Monomorphised per dimension, so that the distance loops unroll.
        match self.dim {
            1 => self.search_in::<1>(q, period, best),
            2 => self.search_in::<2>(q, period, best),
            3 => self.search_in::<3>(q, period, best),
            4 => self.search_in::<4>(q, period, best),
            5 => self.search_in::<5>(q, period, best),
            6 => self.search_in::<6>(q, period, best),
            7 => self.search_in::<7>(q, period, best),
            _ => self.search_in::<MAX_DIM>(q, period, best),
        }
    }

    fn search_in<const D: usize>(&self, q: &[f64], period: &[f64], best: &mut Best) {
        let q: &[f64; D] = q.try_into().expect("query of the tree's dimension");
        let period: &[f64; D] = period.try_into().expect("periods of the tree's dimension");
        let box_dist2 = |id: u32| -> f64 {
            let b = &self.boxes[2 * D * id as usize..2 * D * (id as usize + 1)];
            let (lo, hi): (&[f64; D], &[f64; D]) = (
                b[..D].try_into().expect("box of D"),
                b[D..].try_into().expect("box of D"),
            );
            // Branch-free: whether the query lies inside the box along an axis is
            // unpredictable.
            let mut s = 0.0;
            for j in 0..D {
                let x = q[j];
                let m = if period[j] > 0.0 {
                    let (mut a, mut b) = ((x - lo[j]).abs(), (x - hi[j]).abs());
                    a = a.min(period[j] - a);
                    b = b.min(period[j] - b);
                    let inside = x >= lo[j] && x <= hi[j];
                    if inside { 0.0 } else { a.min(b) }
                } else {
                    (lo[j] - x).max(x - hi[j]).max(0.0)
                };
                s += m * m;
            }
            s
        };
        let mut stack = self.stack.borrow_mut();
        stack.clear();
        // Per block of leaf entries: their distances, and the positions of those within
        // the bound (zeroed once per search, not per leaf).
        let mut d2s = [0.0; SCAN_BLOCK];
        let mut within = [0u8; SCAN_BLOCK];
        // The node to visit next: the nearer child is descended into directly, the
        // farther one pushed — each only if its box can still hold a better candidate.
        let mut next = Some((0u32, box_dist2(0)));
        loop {
            let (id, lb) = match next.take() {
                Some(n) => n,
                None => match stack.pop() {
                    Some(n) => n,
                    None => break,
                },
            };
            if best.prunes(lb) {
                continue;
            }
            let node = self.nodes[id as usize];
            if node.is_leaf() {
                // Three passes per block of entries: the distances, branch-free (the
                // compiler vectorises it); the positions of those within the bound,
                // also branch-free (whether an entry is within is unpredictable); then
                // the few that can enter `best`.
                let leaf = &self.leaves[node.right as usize];
                for (b, coords) in leaf.coords.chunks(SCAN_BLOCK * D).enumerate() {
                    let len = coords.len() / D;
                    for (d2, p) in d2s.iter_mut().zip(coords.chunks_exact(D)) {
                        let p: &[f64; D] = p.try_into().expect("chunks of D");
                        *d2 = dist2(p, q, period);
                    }
                    let bound = best.bound();
                    let mut count = 0;
                    for (i, &d2) in d2s[..len].iter().enumerate() {
                        within[count] = i as u8;
                        count += usize::from(d2 <= bound);
                    }
                    let at = b * SCAN_BLOCK;
                    let slots = &leaf.slots[at..at + len];
                    let seqs = &leaf.seqs[at..at + len];
                    for &i in &within[..count] {
                        let (i, d2) = (usize::from(i), d2s[usize::from(i)]);
                        if best.admits(d2) {
                            best.offer(Candidate {
                                d2,
                                seq: seqs[i],
                                slot: slots[i],
                            });
                        }
                    }
                }
                continue;
            }
            let dl = box_dist2(node.left);
            let dr = box_dist2(node.right);
            let (near, far) = if dl <= dr {
                ((node.left, dl), (node.right, dr))
            } else {
                ((node.right, dr), (node.left, dl))
            };
            if !best.prunes(far.1) {
                stack.push(far);
            }
            if !best.prunes(near.1) {
                next = Some(near);
            }
        }
    }

    /// Entries in the tree.
    pub fn entries(&self) -> usize {
        self.entries
    }

    /// Insertions since the last balanced build.
    pub fn insertions(&self) -> usize {
        self.insertions
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A ring memory of `cap` slots, overwritten in turn (remove, then insert) with
    /// coarse points (many duplicates), the tree rebuilt now and then: every search
    /// equals a brute-force selection over the live samples.
    #[test]
    fn removals_insertions_and_rebuilds_keep_searches_exact() {
        let (dim, cap, k) = (2, 150, 12);
        let period = [2.0 * std::f64::consts::PI, 0.0];
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (mut coords, mut seqs) = (Vec::new(), Vec::new());
        let mut tree = KdTree::new(dim);
        for seq in 0..3000u64 {
            let p = [
                (rng.random_range(-6..6) as f64) * 0.5,
                (rng.random_range(-8..8) as f64) * 0.25,
            ];
            let slot = (seq % cap as u64) as u32;
            if seqs.len() < cap {
                coords.extend_from_slice(&p);
                seqs.push(seq);
            } else {
                tree.remove(slot);
                coords[slot as usize * dim..(slot as usize + 1) * dim].copy_from_slice(&p);
                seqs[slot as usize] = seq;
            }
            if seq % 700 == 699 {
                tree.rebuild(&coords, &seqs);
            } else {
                tree.insert(&p, slot, seq);
            }
            assert_eq!(tree.entries(), seqs.len());
            let q = [rng.random_range(-3.5..3.5), rng.random_range(-2.5..2.5)];
            let mut best = Best::new(k);
            tree.search(&q, &period, &mut best);
            let mut want: Vec<Candidate> = (0..seqs.len())
                .map(|s| Candidate {
                    d2: dist2(&coords[s * dim..(s + 1) * dim], &q, &period),
                    seq: seqs[s],
                    slot: s as u32,
                })
                .collect();
            want.sort_by(|a, b| a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq)));
            want.truncate(k);
            assert_eq!(best.sorted(), &want[..], "after insertion {seq}");
        }
    }

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
