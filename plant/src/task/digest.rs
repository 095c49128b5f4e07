//! A task's content hash: what a driver advertises (`DriverInfo::task_hash`) so that the
//! rig can tell whether the driver serves the task it learns.
//!
//! The hash is the first 8 bytes (little-endian `u64`) of the SHA-256 of the task's
//! canonical bytes, which any language can write (`docs/tasks.md`, "The task's hash";
//! `rigkit.task`, `python/rigkit/task.py`, does): integers as `u64` and numbers as `f64`
//! little-endian, flags as one byte, in this order —
//!
//! 1. the text `rig.task.v1` and a NUL byte; the name's bytes and a NUL byte;
//! 2. `n`, `m`; the sampling time; the trial's length;
//! 3. per state: angle flag, range low, range high; per action: low, high;
//! 4. the reward: `Q` (n), `P` (m), the reference (n), `Q_N` (n);
//! 5. the number of start states, then each (n);
//! 6. the operating range flag, and if set: per state low, high; then the penalty;
//! 7. only what the task has of these, each as a tag byte and its values: 1 the cosine
//!    weights (n); 2 the absolute action weights (m); 3 the reward's goal: its region
//!    ([`crate::region::Region::digest`]) and bonus; 4 the terminal goal: its region and
//!    reward; 5 the start distribution ([`crate::start::StartDistribution::digest`]).
//!
//! A task without the keys of item 7 hashes as before they existed. Names of components,
//! units, the description and the simulation are not part of it.

use sha2::{Digest, Sha256};

use super::Task;

/// The canonical bytes of `task` (see the module documentation).
pub fn canonical_bytes(task: &Task) -> Vec<u8> {
    let mut b = Vec::new();
    let int = |b: &mut Vec<u8>, v: usize| b.extend_from_slice(&(v as u64).to_le_bytes());
    let num = |b: &mut Vec<u8>, v: f64| b.extend_from_slice(&v.to_le_bytes());
    let nums = |b: &mut Vec<u8>, v: &[f64]| v.iter().for_each(|&x| num(b, x));
    b.extend_from_slice(b"rig.task.v1\0");
    b.extend_from_slice(task.name.as_bytes());
    b.push(0);
    int(&mut b, task.state_dim());
    int(&mut b, task.action_dim());
    num(&mut b, task.ts);
    num(&mut b, task.trial_seconds);
    for (&angle, &(lo, hi)) in task.angle_mask.iter().zip(&task.state_range) {
        b.push(u8::from(angle));
        nums(&mut b, &[lo, hi]);
    }
    for (&lo, &hi) in task.action_low.iter().zip(&task.action_high) {
        nums(&mut b, &[lo, hi]);
    }
    let r = &task.reward;
    for v in [&r.q, &r.p, &r.reference, &r.terminal] {
        nums(&mut b, v);
    }
    int(&mut b, task.initial_states.len());
    for x0 in &task.initial_states {
        nums(&mut b, x0);
    }
    match &task.operating_range {
        None => b.push(0),
        Some(range) => {
            b.push(1);
            for &(lo, hi) in &range.limits {
                nums(&mut b, &[lo, hi]);
            }
            num(&mut b, range.penalty);
        }
    }
    for term in &r.terms {
        term.digest(&mut b);
    }
    if let Some(goal) = &task.goal {
        b.push(4);
        goal.region.digest(&mut b);
        num(&mut b, goal.reward);
    }
    if let Some(d) = &task.start_distribution {
        b.push(5);
        d.digest(&mut b);
    }
    b
}

/// The task's hash: the first 8 bytes of the SHA-256 of its canonical bytes, as a
/// little-endian `u64`.
pub fn hash(task: &Task) -> u64 {
    let d = Sha256::digest(canonical_bytes(task));
    u64::from_le_bytes(d[..8].try_into().expect("SHA-256 has 32 bytes"))
}

/// Appends `kind` and then `(first_i, second_i)` per component as little-endian `f64` to
/// `b`: the canonical bytes of a region or a start distribution.
pub(crate) fn kind_and_pairs(b: &mut Vec<u8>, kind: u8, first: &[f64], second: &[f64]) {
    b.push(kind);
    for (a, c) in first.iter().zip(second) {
        b.extend_from_slice(&a.to_le_bytes());
        b.extend_from_slice(&c.to_le_bytes());
    }
}
