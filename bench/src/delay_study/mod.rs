//! `rig delay-study`: how a sample-to-actuation delay hurts learning, and how much
//! predictive timing recovers (thesis §6.4.1; docs/latency.md).
//!
//! Every cell is one `rig learn` experiment ([`runtime::learn::learn`], runs in parallel) on
//! the pendulum with angle-only sensing and the predictive (model-based) estimator:
//! learner × timing × injected delay, the learners VGBP-LSTD and MLAC/LLR with their
//! presets, the timings direct (`x̂_k`, action applied `D` after the sample) and
//! predictive (`x̂_{k+1|k}`, action applied at the next sample instant), the delays
//! `D` = 0, 5, 10, 20 ms by default. A cell's score per run is its *final greedy return*:
//! the mean of the run's last [`LAST_EVALUATIONS`](runtime::output::runs::LAST_EVALUATIONS) greedy evaluations (as `rig learn`
//! summarises); across runs its mean, sample standard deviation and 95 % confidence
//! interval of the mean (Student's t).
//!
//! Outputs in `DIR`:
//! * `cells.csv` — `algo,approx,mode,delay_ms,runs,mean,sd,ci_low,ci_high,velocity_error`
//!   (the last: how far the velocity the agent acted on was from the truth, [`StudyCell`]);
//! * `final_return.png` / `.svg` — final greedy return against the delay, direct and
//!   predictive per learner, with 95 % CIs;
//! * `curves-ALGO-APPROX.png` / `.svg` — the greedy learning curves (means) of every cell
//!   of a learner;
//! * `summary.txt` — the table and the acceptance checks: at 10 ms, is predictive timing
//!   better than direct (one-sided Welch t-test, p < 0.05; whether the CIs overlap is
//!   reported too), and does each learner learn the swing-up in predictive timing (mean
//!   final greedy return ≥ [`SWING_UP`])?
//! * `ALGO-APPROX/direct-Dms/`, `ALGO-APPROX/predictive/` — each cell's `rig learn`
//!   output. Predictive timing applies an action at the next sample instant, so a delay
//!   below `Ts` never reaches the plant: its cell is run once (no delay) and stands for
//!   every delay.
//!
//! `--observer-model known` runs the same study with the plant's own dynamics as the
//! estimator's model: the reference for what a perfect one-step prediction recovers.
//!
//! `study` learns the cells; `report` writes what they came to.

mod report;
mod study;

pub use report::summary;
pub use study::{
    COMPARED_AT_MS, DELAYS_MS, DelayStudyError, DelayStudyOptions, LEARNERS, ReturnStats, SWING_UP,
    StudyCell, welch,
};

/// Runs the study and writes its report; see the module documentation.
pub fn delay_study(opts: &DelayStudyOptions) -> Result<Vec<StudyCell>, DelayStudyError> {
    let cells = study::run(opts)?;
    report::write(opts, &cells)?;
    Ok(cells)
}
