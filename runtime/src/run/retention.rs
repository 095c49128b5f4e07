//! Which checkpoints a resume may still need.
//!
//! The agent checkpoints every learning trial as it ends, and may run ahead of what the
//! supervisor has recorded (by up to a whole buffer of samples). A resume continues from
//! the last trial complete everywhere: in `returns.csv`, in the recording that survives
//! a crash (the chunks written out) and in the checkpoints. So the supervisor removes a
//! checkpoint only when two newer ones are of trials complete everywhere (the newest,
//! and one to fall back on should it be corrupt), and keeps every checkpoint from
//! those on.

use std::path::PathBuf;

use crate::resume;

/// The supervisor's side of the checkpoints: removes those no resume can need.
pub(super) struct Retention {
    /// The run's checkpoint folder.
    dir: PathBuf,
    /// The recorder's flushes seen so far.
    flushes: u64,
}

/// What was recorded before a drain: every sample before `recorded` on all three topics,
/// and the first `rows` rows of this run's `returns.csv`.
#[derive(Clone, Copy)]
pub(super) struct DrainMark {
    pub(super) recorded: u64,
    pub(super) rows: usize,
}

impl Retention {
    pub(super) fn new(dir: PathBuf) -> Self {
        Self { dir, flushes: 0 }
    }

    /// After a drain that began at `before`, when the recorder has written everything out
    /// since (`flushes` grew): the trials complete in both `ends` (the rows' trials and
    /// the first sample after each) and the written-out recording are safe, and the
    /// checkpoints before the two newest of them are removed
    /// ([`resume::keep_from_newest`]).
    pub(super) fn after_drain(&mut self, before: DrainMark, flushes: u64, ends: &[(u32, u64)]) {
        if flushes == self.flushes {
            return;
        }
        self.flushes = flushes;
        let safe = ends[..before.rows]
            .iter()
            .rev()
            .find(|&&(_, end)| end <= before.recorded)
            .map(|&(trial, _)| trial);
        if let Some(safe) = safe {
            resume::keep_from_newest(&self.dir, safe);
        }
    }
}
