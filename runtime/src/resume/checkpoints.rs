//! The checkpoints of a run: where they are, which there are, and the agent's writer
//! that keeps the loop from waiting for the disk.

use super::error::WriteError;
use crate::error::AtFile;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;

use agent::checkpoint::Checkpoint;

use crate::lock::FolderLock;
use crate::process::{CpuLayout, Part};

/// The checkpoint directory of run directory `out`.
pub fn checkpoint_dir(out: &Path) -> PathBuf {
    out.join("checkpoints")
}

/// The checkpoint file of `trial` in checkpoint directory `dir`.
pub fn checkpoint_path(dir: &Path, trial: u32) -> PathBuf {
    dir.join(format!("trial-{trial:06}.ckpt"))
}

/// The trials of the checkpoint files in `dir`, ascending.
pub fn checkpoints(dir: &Path) -> Vec<u32> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut trials: Vec<u32> = entries
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_prefix("trial-")?
                .strip_suffix(".ckpt")?
                .parse()
                .ok()
        })
        .collect();
    trials.sort_unstable();
    trials
}

/// Removes the checkpoints of trials before `trial`.
pub fn prune(dir: &Path, trial: u32) {
    remove(dir, |t| t < trial);
}

/// Keeps the newest checkpoint of a trial up to `trial`, the one before it (to fall back
/// on should the newest be corrupt after a power failure: they are not synced) and those
/// after `trial`: removes the older ones.
pub fn keep_from_newest(dir: &Path, trial: u32) {
    let oldest_kept = checkpoints(dir)
        .into_iter()
        .rev()
        .filter(|&t| t <= trial)
        .take(2)
        .last();
    if let Some(t) = oldest_kept {
        prune(dir, t);
    }
}

/// Removes the checkpoints of trials after `trial`.
pub fn discard_after(dir: &Path, trial: u32) {
    remove(dir, |t| t > trial);
}

fn remove(dir: &Path, which: impl Fn(u32) -> bool) {
    for t in checkpoints(dir) {
        if which(t) {
            let _ = std::fs::remove_file(checkpoint_path(dir, t));
        }
    }
}

/// Writes checkpoints on a background thread (atomically: [`Checkpoint::write`]) and keeps
/// the `keep` newest (0: all; `rig run` prunes them itself, keeping what a resume needs).
/// When the disk is slower than the trials, checkpoints queued behind the one being
/// written are skipped, except the newest: the loop never waits, and a resume redoes the
/// few trials after the newest checkpoint written. Dropped, it writes what is queued.
pub struct CheckpointWriter {
    tx: Option<mpsc::Sender<Checkpoint>>,
    thread: Option<JoinHandle<Result<(), WriteError>>>,
    /// The folder is this writer's while it lasts.
    _folder: FolderLock,
}

impl CheckpointWriter {
    /// A writer into `dir` (created if missing, and held: [`FolderLock`]), its thread
    /// placed as `layout` places the checkpoint writer, keeping the `keep` newest (0: all).
    pub fn new(dir: &Path, layout: Option<CpuLayout>, keep: usize) -> Result<Self, WriteError> {
        std::fs::create_dir_all(dir).at("cannot create", dir)?;
        let folder = FolderLock::acquire(dir)?;
        let (tx, rx) = mpsc::channel::<Checkpoint>();
        let dir = dir.to_owned();
        let thread = std::thread::spawn(move || -> Result<(), WriteError> {
            // Beside the loop: never preempting it (and never real-time).
            crate::process::batch_thread();
            // Where it cannot be pinned it runs on the agent's CPUs: no reason to stop.
            if let Some(l) = layout {
                let _ = l.place(Part::CheckpointWriter);
            }
            let mut written = std::collections::VecDeque::new();
            while let Ok(mut c) = rx.recv() {
                // Only the newest of those waiting.
                if let Some(newer) = rx.try_iter().last() {
                    c = newer;
                }
                let path = checkpoint_path(&dir, c.trial);
                c.write(&path).at("cannot write checkpoint", &path)?;
                written.push_back(c.trial);
                if keep > 0 && written.len() > keep {
                    written.pop_front();
                    prune(&dir, written[0]);
                }
            }
            Ok(())
        });
        Ok(Self {
            tx: Some(tx),
            thread: Some(thread),
            _folder: folder,
        })
    }

    /// Queues checkpoint `c` (of trial `c.trial`); fails if an earlier write failed.
    pub fn save(&mut self, c: Checkpoint) -> Result<(), WriteError> {
        let sent = self.tx.as_ref().is_some_and(|tx| tx.send(c).is_ok());
        if !sent {
            return self.finish();
        }
        Ok(())
    }

    /// Waits until every queued checkpoint is written.
    pub fn finish(&mut self) -> Result<(), WriteError> {
        drop(self.tx.take());
        match self.thread.take() {
            Some(t) => t.join().map_err(|_| WriteError::Panicked)?,
            None => Ok(()),
        }
    }
}

impl Drop for CheckpointWriter {
    /// Writes what is queued (a run stopped by an error or Ctrl-C keeps its newest
    /// checkpoint).
    fn drop(&mut self) {
        let _ = self.finish();
    }
}
