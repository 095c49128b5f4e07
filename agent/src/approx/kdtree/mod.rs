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

mod best;
mod grow;
mod search;

pub use best::{Best, Candidate};

/// Maximum number of neighbours a query may ask for.
pub const MAX_K: usize = 128;
/// Maximum input dimension of an LLR memory.
pub const MAX_DIM: usize = 8;
/// Entries per leaf of a balanced build; an insertion splits a leaf that grows past
/// twice this many (see the module notes on speed for the choice).
pub const LEAF_SIZE: usize = 32;
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
}
