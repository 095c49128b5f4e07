//! The K-nearest-neighbour search: a descent that offers the entries of every leaf
//! whose bounding box can still hold a better candidate.

use super::{Best, Candidate, KdTree, LEAF_SIZE, MAX_DIM, dist2};

/// Leaf entries whose distances a search computes in one pass.
const SCAN_BLOCK: usize = 2 * LEAF_SIZE;
// Positions within a block are stored as `u8`.
const _: () = assert!(SCAN_BLOCK <= 256);

impl KdTree {
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
}
