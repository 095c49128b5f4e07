//! `[run]`: how many experiments, of how many trials, from which seed, with which
//! sample-to-actuation delays.

use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{ConfigError, check_float, check_int};
use crate::Task;
use crate::delay::{self, DelayFileError, Delays};

/// How many experiments, of how many trials, from which seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// Trials per run.
    pub trials: u32,
    /// Independent runs (learning experiments).
    pub runs: u32,
    /// Seed from which every random stream of every run is derived.
    pub seed: u64,
    /// A greedy evaluation trial after every this many trials (0, or more than `trials`:
    /// none).
    pub eval_every: u32,
    /// Sample-to-actuation delay \[ms\], applied deterministically in lockstep: over each
    /// sample period the previous action stays in effect for this long, then the new one
    /// (0: the thesis's simulations, the action applies at the sample instant).
    #[serde(default)]
    pub delay_ms: f64,
    /// A recorded distribution of sample-to-actuation delays: a CSV file, one delay per
    /// row in column `delay_column`; each sample's delay is drawn from it (uniformly, from
    /// the run seed's stream [`delay::STREAM`]) and applied as `delay_ms` is.
    /// Empty: none. Exclusive with `delay_ms`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub delay_from: String,
    /// The column of `delay_from` holding the delays; its unit is its name's suffix
    /// (`_s`, `_ms`, `_us`, `_ns`; `sample_to_actuation` of `rig latency`'s latency.csv is
    /// ns). Empty: `delay_ms`, else `sample_to_actuation`, whichever the file has.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub delay_column: String,
}

impl RunConfig {
    /// The sample-to-actuation delays of a run with seed `run_seed` on `task`:
    /// `delay_from`'s recorded distribution, else the fixed `delay_ms` ([`Delays`]). The
    /// error names the file, column, row and allowed range.
    pub fn delays_for_run(&self, task: &Task, run_seed: u64) -> Result<Delays, DelayFileError> {
        if self.delay_from.is_empty() {
            return Ok(Delays::fixed(self.delay_ms * 1e-3));
        }
        Ok(Delays::recorded(self.delays(task)?, run_seed))
    }

    /// `delay_from`'s delays \[s\].
    fn delays(&self, task: &Task) -> Result<Arc<Vec<f64>>, DelayFileError> {
        let column = (!self.delay_column.is_empty()).then_some(self.delay_column.as_str());
        delay::read_csv(Path::new(&self.delay_from), column, task.ts).map(Arc::new)
    }

    /// Checks every value against its allowed range; a delay must be shorter than
    /// `task`'s sample period, and a delay file must be readable.
    pub fn validate(&self, task: &Task) -> Result<(), ConfigError> {
        check_int("run.trials", self.trials.into(), 1, 10_000_000)?;
        check_int("run.runs", self.runs.into(), 1, 100_000)?;
        check_int("run.eval_every", self.eval_every.into(), 0, 10_000_000)?;
        if self.delay_ms != 0.0 {
            // Less than one sample period.
            check_float("run.delay_ms", self.delay_ms, 0.0, task.ts * 1e3, true)?;
        }
        if !self.delay_from.is_empty() {
            if self.delay_ms != 0.0 {
                return Err(ConfigError::new(
                    "run.delay_from",
                    "is exclusive with run.delay_ms (--delay-from, --delay-ms): give one of them",
                ));
            }
            self.delays(task)
                .map_err(|e| ConfigError::new("run.delay_from", e.to_string()))?;
        } else if !self.delay_column.is_empty() {
            return Err(ConfigError::new(
                "run.delay_column",
                "needs run.delay_from (--delay-from), the file it is a column of",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SystemName;

    fn run() -> RunConfig {
        RunConfig {
            trials: 400,
            runs: 30,
            seed: 1,
            eval_every: 10,
            delay_ms: 0.0,
            delay_from: String::new(),
            delay_column: String::new(),
        }
    }

    #[test]
    fn ranges_and_delays_are_checked() {
        let task = Task::new(SystemName::Pendulum);
        run().validate(&task).unwrap();
        let key = |r: RunConfig| r.validate(&task).unwrap_err().key;
        assert_eq!(key(RunConfig { trials: 0, ..run() }), "run.trials");
        assert_eq!(key(RunConfig { runs: 0, ..run() }), "run.runs");
        let e = RunConfig {
            delay_ms: 30.0,
            ..run()
        }
        .validate(&task)
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "`run.delay_ms`: 30 is out of range: must be a finite number in (0, 30)"
        );
        let column = RunConfig {
            delay_column: "x_ms".into(),
            ..run()
        };
        assert_eq!(key(column), "run.delay_column");
        let d = RunConfig {
            delay_ms: 5.0,
            ..run()
        }
        .delays_for_run(&task, 1)
        .unwrap();
        assert_eq!(format!("{d:?}"), format!("{:?}", Delays::fixed(5e-3)));
    }
}
