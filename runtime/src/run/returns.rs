//! `returns.csv` of a run, streamed from the plant's measurements (or the observer's
//! estimates, when the driver measures positions only): one row per trial, the format
//! of `rig learn`'s `runs.csv`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::error::{Result, RunError};
use crate::error::AtFile;
use ::agent::horizon::Horizon;
use wire::flags;

use crate::config::ExperimentConfig;
use crate::experiment::TrialRecord;
use crate::output::runs::{RUNS_HEADER, write_row};
use crate::resume::ResumePoint;

/// Builds `returns.csv` rows from the plant's measurements.
pub(super) struct Returns {
    pub(super) out: BufWriter<File>,
    /// Where `out` writes.
    path: PathBuf,
    pub(super) task: Arc<plant::Task>,
    pub(super) steps_per_trial: u64,
    /// Samples not run because trials ended early (left the operating range).
    pub(super) skipped_samples: u64,
    /// Adds `τ_N(x_N)` of a finite horizon's last measurement to the return (Eq. 4.1).
    pub(super) horizon: Horizon,
    pub(super) reward: plant::Reward,
    pub(super) pending: Option<TrialRecord>,
    /// Whether the pending learning trial has ended.
    pub(super) pending_ended: bool,
    /// Greedy evaluation trials after a learning trial, when due (one per start state).
    pub(super) eval_starts: u32,
    /// A greedy evaluation after every this-many trials (0: none).
    pub(super) eval_every: u32,
    /// The running greedy trial's reward sum.
    pub(super) greedy_trial: f64,
    /// Sum of the returns of the greedy trials after the pending trial, and their count.
    pub(super) greedy: (f64, u32),
    pub(super) records: Vec<TrialRecord>,
    /// Per row written by this run: its trial and the sequence number of the first sample
    /// after it and its greedy evaluations.
    pub(super) ends: Vec<(u32, u64)>,
    /// Per row written by this run, its log time in the recording: that of the last end
    /// of its trial or of its evaluations.
    pub(super) log_times: Vec<u64>,
    /// The log time of the last end of the pending trial or of its evaluations.
    end_log_time: u64,
    /// The sequence number of the sample being accounted for.
    seq: u64,
}

impl Returns {
    /// Creates `path` with the header and the trials a resumed run keeps (`point`).
    pub(super) fn create(
        path: &Path,
        cfg: &ExperimentConfig,
        task: Arc<plant::Task>,
        point: Option<&ResumePoint>,
    ) -> Result<Self> {
        let mut out = BufWriter::new(File::create(path).at("cannot create", path)?);
        let kept = point.map_or(&[][..], |p| &p.records[..]);
        writeln!(out, "{RUNS_HEADER}")
            .and_then(|()| kept.iter().try_for_each(|r| write_row(&mut out, r)))
            .and_then(|()| out.flush())
            .at("cannot write", path)?;
        let (after, sim_time) = point.map_or((0, 0.0), |p| (p.trial, p.sim_time_s));
        Ok(Self {
            out,
            path: path.to_owned(),
            steps_per_trial: task.steps_per_trial() as u64,
            skipped_samples: task.skipped_samples(after.into(), sim_time),
            horizon: cfg.agent().horizon.of(&task),
            reward: task.reward.clone(),
            pending: None,
            pending_ended: false,
            eval_starts: task.initial_states.len() as u32,
            eval_every: cfg.run().eval_every,
            greedy_trial: 0.0,
            greedy: (0.0, 0),
            records: kept.to_vec(),
            ends: Vec::new(),
            log_times: Vec::new(),
            end_log_time: 0,
            seq: 0,
            task,
        })
    }

    /// Accounts for the sample with header `h` and reward `reward`; `x` is its state for
    /// a finite horizon's terminal reward. From the plant's measurements: the true state
    /// (the measurement's `y` with full-state sensing); with [`flags::ESTIMATED_REWARD`]
    /// from the observer's estimates instead: their rewards and `x̂`. `log_time` is its
    /// log time in the recording.
    pub(super) fn sample(
        &mut self,
        h: &wire::Header,
        reward: f64,
        x: &[f64],
        log_time: u64,
    ) -> Result<()> {
        let f = h.flags;
        self.seq = h.seq;
        let greedy = f & flags::GREEDY != 0;
        if f & flags::SHUTDOWN != 0 || (f & flags::START != 0 && !greedy) {
            self.flush()?;
        }
        if f & flags::SHUTDOWN != 0 {
            return Ok(());
        }
        if f & flags::START != 0 {
            if greedy {
                self.greedy_trial = 0.0;
            } else {
                self.greedy = (0.0, 0);
                self.pending_ended = false;
                self.pending = Some(TrialRecord {
                    run: 0,
                    trial: h.trial as u32,
                    sim_time_s: 0.0,
                    ret: 0.0,
                    greedy: None,
                });
            }
            return Ok(());
        }
        if f & flags::GAP != 0 {
            // An attempt cut short by a gap: it is run again, and only that run counts.
            if !greedy {
                self.pending = None;
            }
            return Ok(());
        }
        let pending = self.pending.as_mut().ok_or(RunError::OutsideTrial)?;
        let end = f & flags::END != 0;
        if end {
            self.end_log_time = log_time;
        }
        let final_reward = if end {
            self.horizon.final_reward(&self.reward, x)
        } else {
            0.0
        };
        if greedy {
            // One greedy trial per start state: the greedy return is their mean.
            self.greedy_trial += reward;
            if end {
                self.greedy_trial += final_reward;
                self.greedy.0 += self.greedy_trial;
                self.greedy.1 += 1;
                pending.greedy = Some(self.greedy.0 / f64::from(self.greedy.1));
            }
        } else {
            pending.ret += reward;
            if end {
                self.pending_ended = true;
                pending.ret += final_reward;
                self.skipped_samples += self.steps_per_trial.saturating_sub(h.step);
                pending.sim_time_s = self
                    .task
                    .sim_time(pending.trial.into(), self.skipped_samples);
            }
        }
        Ok(())
    }

    pub(super) fn flush(&mut self) -> Result<()> {
        if let Some(r) = self.pending.take() {
            write_row(&mut self.out, &r)
                .and_then(|()| self.out.flush())
                .at("cannot write", &self.path)?;
            self.ends.push((r.trial, self.seq));
            self.log_times.push(self.end_log_time);
            self.records.push(r);
        }
        Ok(())
    }

    /// After a failure: writes the pending trial only if it is complete — the learning
    /// trial and its greedy evaluations (a resumed run redoes an incomplete one).
    pub(super) fn flush_complete(&mut self) -> Result<()> {
        let complete = self.pending.as_ref().is_some_and(|p| {
            let due = self.eval_every > 0 && p.trial.is_multiple_of(self.eval_every);
            self.pending_ended && self.greedy.1 == if due { self.eval_starts } else { 0 }
        });
        if complete {
            self.flush()?;
        }
        Ok(())
    }
}
