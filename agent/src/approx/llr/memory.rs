//! Memory management (§3.5.2): storing a sample, evicting the oldest or a redundant one,
//! and the neighbourhood of a new sample.

use super::super::MAX_OUT;
use super::super::kdtree::{Candidate, MAX_DIM};
use super::{Eviction, Llr};

impl Llr {
    /// Stores `[x | y]` (`q` = scaled `x`, `nearest` = the nearest stored sample, if
    /// known), evicting per the memory-management rule. Returns the new sample as a
    /// candidate at distance 0 and the slot whose previous sample was removed, if any.
    pub(super) fn insert(
        &mut self,
        q: &[f64; MAX_DIM],
        y: &[f64],
        nearest: Option<Candidate>,
    ) -> (Candidate, Option<u32>) {
        let seq = self.next_seq;
        self.next_seq += 1;
        self.version += 1;
        let replace = match self.eviction {
            Eviction::Redundant(radius) if self.len > 0 => {
                let nearest = nearest.or_else(|| {
                    let mut found = self.neighbours.take();
                    self.nearest(q, 1, &mut found);
                    let first = found.first().copied();
                    self.neighbours.set(found);
                    first
                });
                nearest.filter(|c| c.d2 < radius * radius).map(|c| c.slot)
            }
            _ => None,
        };
        let (slot, removed) = match replace {
            Some(slot) => (slot, Some(slot)),
            None if self.len < self.cap => {
                self.inputs.extend_from_slice(&q[..self.n]);
                self.outputs.extend_from_slice(y);
                self.seq.push(seq);
                self.trace.push(0.0);
                self.len += 1;
                ((self.len - 1) as u32, None)
            }
            None => {
                let slot = self.oldest_slot();
                (slot, Some(slot))
            }
        };
        let s = slot as usize;
        if removed.is_some() {
            self.inputs[s * self.n..(s + 1) * self.n].copy_from_slice(&q[..self.n]);
            self.outputs[s * self.m..(s + 1) * self.m].copy_from_slice(y);
            self.seq[s] = seq;
            self.trace[s] = 0.0;
        }
        for o in 0..self.m {
            self.outputs[s * self.m + o] = self.clamp(o, self.outputs[s * self.m + o]);
        }
        self.fifo.push_back((slot, seq));
        self.index(slot, seq, removed.is_some());
        let new = Candidate { d2: 0.0, seq, slot };
        self.update_cache(new, removed);
        (new, removed)
    }

    fn oldest_slot(&mut self) -> u32 {
        while let Some((slot, seq)) = self.fifo.pop_front() {
            if self.seq[slot as usize] == seq {
                return slot;
            }
        }
        unreachable!("a full memory always has a live oldest sample")
    }

    /// Stores `[x | f(x)]`; returns `f(x)` (before the insertion) and the neighbourhood of
    /// `x` after it, nearest first, in the [`Llr::neighbours`] buffer (to be given back).
    /// One search serves both: the K + 1 nearest before the insertion contain the K − 1
    /// that join the new sample, whatever the insertion removed.
    pub(super) fn insert_here(&mut self, x: &[f64]) -> ([f64; MAX_OUT], Vec<Candidate>) {
        let q = self.scale(x);
        let mut near = self.neighbours.take();
        self.nearest(&q, self.k + 1, &mut near);
        let y = self.fitted(&q, Some(&near[..near.len().min(self.k)])).y;
        let (new, removed) = self.insert(&q, &y[..self.m], near.first().copied());
        // The new sample (distance 0, newest) ranks first; the others keep their order.
        near.retain(|c| Some(c.slot) != removed);
        near.insert(0, new);
        near.truncate(self.k);
        (y, near)
    }
}
