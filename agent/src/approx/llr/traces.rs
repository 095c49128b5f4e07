//! Eligibility traces of an LLR critic (§3.5.2, "Application to SAC"): a visit stores
//! the sample and gives it and its neighbours eligibility 1.

use super::super::Traced;
use super::Llr;

/// Traces below this are dropped (with λγ = 0.63 that is after 30 steps).
const TRACE_CUTOFF: f64 = 1e-6;

impl Traced for Llr {
    fn visit(&mut self, x: &[f64], decay: f64) {
        self.visit_value(x, decay);
    }
    fn visit_value(&mut self, x: &[f64], decay: f64) -> f64 {
        let mut kept = 0;
        for i in 0..self.traced.len() {
            let (slot, seq) = self.traced[i];
            let s = slot as usize;
            if self.seq[s] != seq {
                continue;
            }
            self.trace[s] *= decay;
            if self.trace[s] < TRACE_CUTOFF {
                self.trace[s] = 0.0;
                continue;
            }
            self.traced[kept] = (slot, seq);
            kept += 1;
        }
        self.traced.truncate(kept);
        let (y, after) = self.insert_here(x);
        for c in &after {
            if self.trace[c.slot as usize] == 0.0 {
                self.traced.push((c.slot, c.seq));
            }
            self.trace[c.slot as usize] = 1.0;
        }
        self.neighbours.set(after);
        y[0]
    }
    fn apply_td(&mut self, step: f64) {
        self.version += 1;
        for &(slot, seq) in &self.traced {
            let s = slot as usize;
            if self.seq[s] == seq {
                self.outputs[s] += step * self.trace[s];
            }
        }
    }
    fn clear_traces(&mut self) {
        for &(slot, _) in &self.traced {
            self.trace[slot as usize] = 0.0;
        }
        self.traced.clear();
    }
}
