//! Growing the tree: a balanced build over a whole memory, and the split of an overfull
//! leaf.

use super::{KdTree, LEAF_SIZE, Leaf, MAX_DIM, NO_CHILD, Node};

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

impl KdTree {
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

    /// Splits an overfull leaf in place (no-op if all its points coincide).
    pub(super) fn split_leaf(&mut self, id: usize) {
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
}
