//! A static k-d tree over the LLR memory, for the K-nearest-neighbour search of §3.5.2
//! ("one can reduce the computational burden by using, for instance, k-d trees").
//!
//! The tree is rebuilt from scratch by [`super::llr::Llr`] every few dozen insertions;
//! samples inserted since the last rebuild are scanned linearly, and samples overwritten
//! since then are recognised by their sequence number and skipped. Splits are on index
//! (median by `select_nth_unstable`), so any number of identical samples — every trial
//! starts at `[π, 0]`, saturated actions repeat — only makes leaves share coordinates,
//! never breaks the tree.
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
const LEAF_SIZE: usize = 8;
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
/// memory slot.
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
    #[inline]
    fn before(&self, other: &Candidate) -> bool {
        self.d2 < other.d2 || (self.d2 == other.d2 && self.seq > other.seq)
    }
}

/// The K best candidates so far, nearest first, newer first among equals.
pub struct Best {
    items: [Candidate; MAX_K],
    len: usize,
    k: usize,
}

impl Best {
    /// An empty set that keeps at most `k ≤ MAX_K` candidates.
    pub fn new(k: usize) -> Self {
        debug_assert!(k >= 1 && k <= MAX_K);
        Self { items: [Candidate { d2: 0.0, seq: 0, slot: 0 }; MAX_K], len: 0, k }
    }

    /// Offers a candidate.
    #[inline]
    pub fn offer(&mut self, c: Candidate) {
        if self.len == self.k {
            if !c.before(&self.items[self.len - 1]) {
                return;
            }
            self.len -= 1;
        }
        let mut i = self.len;
        while i > 0 && c.before(&self.items[i - 1]) {
            self.items[i] = self.items[i - 1];
            i -= 1;
        }
        self.items[i] = c;
        self.len += 1;
    }

    /// Whether `lower_bound` cannot beat the current worst candidate.
    #[inline]
    fn prunes(&self, lower_bound: f64) -> bool {
        self.len == self.k && lower_bound > self.items[self.len - 1].d2
    }

    /// The candidates, nearest first.
    pub fn as_slice(&self) -> &[Candidate] {
        &self.items[..self.len]
    }
}

#[derive(Clone, Copy)]
struct Node {
    start: u32,
    end: u32,
    left: u32,
    right: u32,
}

/// A static k-d tree over a snapshot of scaled points.
#[derive(Default)]
pub struct KdTree {
    dim: usize,
    points: Vec<f64>,
    slots: Vec<u32>,
    seqs: Vec<u64>,
    nodes: Vec<Node>,
    bbox: Vec<f64>,
}

impl KdTree {
    /// Builds a tree over `items` = (slot, seq), whose scaled coordinates are
    /// `coords(slot)`.
    pub fn build<'a>(dim: usize, mut items: Vec<(u32, u64)>, coords: impl Fn(u32) -> &'a [f64]) -> Self {
        let mut tree = KdTree { dim, ..Default::default() };
        if items.is_empty() {
            return tree;
        }
        tree.nodes.reserve(2 * items.len() / LEAF_SIZE + 1);
        tree.split(&mut items, 0, &coords);
        tree.points.reserve(items.len() * dim);
        for &(slot, seq) in &items {
            tree.points.extend_from_slice(coords(slot));
            tree.slots.push(slot);
            tree.seqs.push(seq);
        }
        tree
    }

    fn split<'a>(&mut self, items: &mut [(u32, u64)], offset: usize, coords: &impl Fn(u32) -> &'a [f64]) -> u32 {
        let id = self.nodes.len() as u32;
        let (mut lo, mut hi) = ([f64::INFINITY; MAX_DIM], [f64::NEG_INFINITY; MAX_DIM]);
        for &(slot, _) in items.iter() {
            let p = coords(slot);
            for j in 0..self.dim {
                lo[j] = lo[j].min(p[j]);
                hi[j] = hi[j].max(p[j]);
            }
        }
        self.bbox.extend_from_slice(&lo[..self.dim]);
        self.bbox.extend_from_slice(&hi[..self.dim]);
        let (start, end) = (offset as u32, (offset + items.len()) as u32);
        self.nodes.push(Node { start, end, left: NO_CHILD, right: NO_CHILD });
        if items.len() <= LEAF_SIZE {
            return id;
        }
        let axis = (0..self.dim)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        if hi[axis] <= lo[axis] {
            return id; // all points identical: one (large) leaf
        }
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |a, b| {
            coords(a.0)[axis].total_cmp(&coords(b.0)[axis]).then(a.1.cmp(&b.1))
        });
        let (left_items, right_items) = items.split_at_mut(mid);
        let left = self.split(left_items, offset, coords);
        let right = self.split(right_items, offset + mid, coords);
        self.nodes[id as usize].left = left;
        self.nodes[id as usize].right = right;
        id
    }

    /// Lower bound of the squared distance from `q` to node `id`'s bounding box.
    #[inline]
    fn box_dist2(&self, id: usize, q: &[f64], period: &[f64]) -> f64 {
        let d = self.dim;
        let lo = &self.bbox[2 * d * id..2 * d * id + d];
        let hi = &self.bbox[2 * d * id + d..2 * d * (id + 1)];
        let mut s = 0.0;
        for j in 0..d {
            let x = q[j];
            if x >= lo[j] && x <= hi[j] {
                continue;
            }
            let (mut a, mut b) = ((x - lo[j]).abs(), (x - hi[j]).abs());
            if period[j] > 0.0 {
                a = a.min(period[j] - a);
                b = b.min(period[j] - b);
            }
            let m = a.min(b);
            s += m * m;
        }
        s
    }

    /// Offers every live point of the tree that can still improve `best`;
    /// `live(slot, seq)` says whether the snapshot entry is still in the memory.
    pub fn search(&self, q: &[f64], period: &[f64], best: &mut Best, live: impl Fn(u32, u64) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: [(u32, f64); 64] = [(0, 0.0); 64];
        let mut top = 1;
        stack[0] = (0, 0.0);
        while top > 0 {
            top -= 1;
            let (id, lb) = stack[top];
            if best.prunes(lb) {
                continue;
            }
            let node = self.nodes[id as usize];
            if node.left == NO_CHILD {
                for i in node.start as usize..node.end as usize {
                    let p = &self.points[i * self.dim..(i + 1) * self.dim];
                    let d2 = dist2(p, q, period);
                    let (slot, seq) = (self.slots[i], self.seqs[i]);
                    if live(slot, seq) {
                        best.offer(Candidate { d2, seq, slot });
                    }
                }
                continue;
            }
            let dl = self.box_dist2(node.left as usize, q, period);
            let dr = self.box_dist2(node.right as usize, q, period);
            // Push the farther child first so the nearer one is searched first.
            let (near, far) = if dl <= dr { ((node.left, dl), (node.right, dr)) } else { ((node.right, dr), (node.left, dl)) };
            stack[top] = far;
            stack[top + 1] = near;
            top += 2;
        }
    }

    /// Number of points in the snapshot.
    pub fn len(&self) -> usize {
        self.slots.len()
    }
}
