//! Whether a run can continue from a checkpoint: a checkpoint holds the agent's state
//! only, so what else a run carries from trial to trial must be the default.

use agent::checkpoint::CheckpointError;

use crate::config::ExperimentConfig;

/// A run with delays drawn from `run.delay_from` cannot be resumed: a checkpoint does not
/// hold where the delay stream stands.
pub fn resumable_delays(cfg: &ExperimentConfig) -> Result<(), ResumeError> {
    if cfg.run().delay_from.is_empty() {
        Ok(())
    } else {
        Err(ResumeError::DelayStream(cfg.run().delay_from.clone()))
    }
}

/// Why a run cannot continue from a checkpoint ([`crate::experiment::Experiment::resume`]).
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    /// A run with a sensor or observer other than the default, whose state a checkpoint
    /// does not hold.
    #[error(
        "a checkpoint holds the agent's state only; resuming needs the default sensor and observer"
    )]
    Observer,
    /// A run with delays drawn from the file `run.delay_from` names.
    #[error(
        "cannot resume a run with run.delay_from = {0:?}: checkpoints do not hold where its delay stream stands; start a new run"
    )]
    DelayStream(String),
    /// A checkpoint that cannot be read or does not fit the run.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
}
