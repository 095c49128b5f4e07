//! Checkpoints of an LLR memory.

use super::{Llr, Search};

/// The stored samples (scaled inputs, outputs, sequence numbers, traces) and the next
/// sequence number. The insertion order follows from the sequence numbers; the k-d tree
/// is rebuilt and the remembered searches and fits start empty — neighbour sets are
/// ordered totally (distance, then newer first), so searches give the same neighbours in
/// the same order whatever the tree's shape.
impl crate::checkpoint::Persist for Llr {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        s.scope("llr", |s| {
            s.f64s("inputs", &self.inputs);
            s.f64s("outputs", &self.outputs);
            s.u64s("seq", &self.seq);
            s.f64s("trace", &self.trace);
            s.u64s("next_seq", &[self.next_seq]);
        });
    }

    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        use crate::checkpoint::CheckpointError;
        r.scope("llr", |r| {
            let inputs = r.f64s("inputs")?;
            let outputs = r.f64s("outputs")?;
            let seq = r.u64s("seq")?;
            let trace = r.f64s("trace")?;
            let next_seq = r.u64s("next_seq")?.first().copied().unwrap_or(0);
            let len = seq.len();
            if len > self.cap
                || inputs.len() != len * self.n
                || outputs.len() != len * self.m
                || trace.len() != len
                || seq.iter().any(|&q| q >= next_seq)
            {
                return Err(CheckpointError::Unfit {
                    section: "llr",
                    why: format!(
                        "holds {len} samples of {} inputs and {} outputs, which does not fit a memory of {} samples of {} inputs and {} outputs: it was written by a differently configured agent",
                        inputs.len().checked_div(len).unwrap_or(0),
                        outputs.len().checked_div(len).unwrap_or(0),
                        self.cap,
                        self.n,
                        self.m
                    ),
                });
            }
            self.inputs.clear();
            self.inputs.extend_from_slice(inputs);
            self.outputs.clear();
            self.outputs.extend_from_slice(outputs);
            self.seq.clear();
            self.seq.extend_from_slice(seq);
            self.trace.clear();
            self.trace.extend_from_slice(trace);
            self.len = len;
            self.next_seq = next_seq;
            let mut order: Vec<(u32, u64)> = (0..len as u32).map(|i| (i, seq[i as usize])).collect();
            order.sort_by_key(|&(_, q)| q);
            self.fifo = order.into_iter().collect();
            self.traced = (0..len as u32)
                .filter(|&i| self.trace[i as usize] != 0.0)
                .map(|i| (i, self.seq[i as usize]))
                .collect();
            if self.search == Search::KdTree {
                self.tree.rebuild(&self.inputs, &self.seq);
            }
            *self.cache.borrow_mut() = [None, None];
            *self.near.get_mut() = None;
            self.version += 1;
            self.last_fit.borrow_mut().version = u64::MAX;
            Ok(())
        })
    }
}
