//! Another observer over a recording's measurements (`rig replay --observer KIND`): its
//! errors per state against the recorded estimates and against the true state — the
//! thesis's observer comparison (§6.4.1), on recorded data.
//!
//! Two quantities, each like for like:
//!
//! - *against the recorded estimates*: what the agent acts on — `x̂_k` in direct timing,
//!   `x̂_{k+1|k}` in predictive timing — from the new observer with the run's timing, and
//!   from the recorded one;
//! - *against the truth*: the new observer's `x̂_k` and the true `x_k` — `/plant/truth`
//!   with a sensor that does not measure the full state, the measurement itself with one
//!   that does — beside the recorded observer's own `x̂_k` against the same truth (run
//!   again over the same measurements: replay reproduces it bit for bit).
//!
//! Trial starts (the state is known there) and the run's end are left out; angle errors
//! are wrapped to [−π, π).

use std::path::Path;

use ::observer::config::ObserverKind;
use ::observer::timing::Front;
use observer::config::SensorKind;
use plant::angle::wrap;
use wire::{Measurement, flags};

use super::{Recording, ReplayError};
use crate::process::observer::estimate;

/// Squared and largest errors of one quantity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Errors {
    /// Σ e².
    sum_sq: f64,
    /// max |e|.
    pub max: f64,
    /// Samples counted.
    pub samples: usize,
}

impl Errors {
    fn add(&mut self, e: f64) {
        self.sum_sq += e * e;
        self.max = self.max.max(e.abs());
        self.samples += 1;
    }

    /// The root mean square error (NaN without samples).
    pub fn rms(&self) -> f64 {
        (self.sum_sq / self.samples as f64).sqrt()
    }
}

/// One state's errors.
#[derive(Clone, Debug, PartialEq)]
pub struct StateErrors {
    /// The state's name (the task's).
    pub state: String,
    /// Against the recorded estimates.
    pub vs_recorded: Errors,
    /// Against the true state.
    pub vs_truth: Errors,
    /// The recorded observer's `x̂_k` against the true state: the baseline.
    pub recorded_vs_truth: Errors,
}

/// The errors per state of observer `kind` over `rec`'s measurements, with the run's
/// sensor, timing and observer settings otherwise.
pub fn compare(rec: &Recording, kind: ObserverKind) -> Result<Vec<StateErrors>, ReplayError> {
    let mut cfg = rec.cfg.clone();
    cfg.change_observer(|o| o.observer = kind)
        .map_err(|e| ReplayError::Config(format!("--observer {kind}: {e}")))?;
    let task = cfg.task();
    let n = task.state_dim();
    let mut front: Front = crate::build::front(&task, &cfg);
    let mut bare = ::observer::build(task.clone(), cfg.observer(), cfg.agent().model.as_ref());
    let recorded = rec.cfg.observer();
    let mut baseline = ::observer::build(task.clone(), recorded, cfg.agent().model.as_ref());
    let mut rows: Vec<StateErrors> = task
        .state_names
        .iter()
        .map(|name| StateErrors {
            state: name.clone(),
            vs_recorded: Errors::default(),
            vs_truth: Errors::default(),
            recorded_vs_truth: Errors::default(),
        })
        .collect();
    let error = |i: usize, a: f64, b: f64| {
        if task.angle_mask[i] {
            wrap(a - b)
        } else {
            a - b
        }
    };
    let full = cfg.observer().sensor == SensorKind::Full;
    for x in &rec.measurements {
        let f = x.header.flags;
        let acted = estimate(&mut front, x);
        if f & (flags::SHUTDOWN | flags::START) != 0 {
            if f & flags::START != 0 {
                bare.reset(&x.y[..n]);
                baseline.reset(&x.y[..n]);
            }
            continue;
        }
        if let Some(recorded) = rec.estimates.get(&x.header.seq) {
            for (i, row) in rows.iter_mut().enumerate() {
                row.vs_recorded.add(error(i, acted.x[i], recorded.x[i]));
            }
        }
        if f & flags::PRIMED != 0 {
            continue;
        }
        let u = &x.u_applied[..task.action_dim()];
        let x_hat = bare.update(&x.y[..n], u);
        let x_rec = baseline.update(&x.y[..n], u);
        let Some(truth) = true_state(rec, x, full) else {
            continue;
        };
        for (i, row) in rows.iter_mut().enumerate() {
            row.vs_truth.add(error(i, x_hat[i], truth[i]));
            row.recorded_vs_truth.add(error(i, x_rec[i], truth[i]));
        }
    }
    Ok(rows)
}

/// The true state of sample `x`: its measurement with full-state sensing, else the
/// recorded truth.
fn true_state<'a>(rec: &'a Recording, x: &'a Measurement, full: bool) -> Option<&'a [f64]> {
    if full {
        Some(&x.y)
    } else {
        rec.truth.get(&x.header.seq).map(|t| &t.x[..])
    }
}

/// The CSV header of [`write_csv`].
pub const CSV_HEADER: [&str; 8] = [
    "state",
    "rms_vs_recorded",
    "max_vs_recorded",
    "rms_vs_truth",
    "max_vs_truth",
    "rms_recorded_vs_truth",
    "max_recorded_vs_truth",
    "samples",
];

/// Writes `rows` to `path` as CSV ([`CSV_HEADER`]), numbers in shortest round-trip form.
pub fn write_csv(path: &Path, rows: &[StateErrors]) -> Result<(), ReplayError> {
    let io = |e: csv::Error| ReplayError::Io {
        path: path.into(),
        cause: e.to_string(),
    };
    let mut w = csv::Writer::from_path(path).map_err(io)?;
    w.write_record(CSV_HEADER).map_err(io)?;
    for r in rows {
        w.write_record([
            r.state.clone(),
            r.vs_recorded.rms().to_string(),
            r.vs_recorded.max.to_string(),
            r.vs_truth.rms().to_string(),
            r.vs_truth.max.to_string(),
            r.recorded_vs_truth.rms().to_string(),
            r.recorded_vs_truth.max.to_string(),
            r.vs_truth.samples.to_string(),
        ])
        .map_err(io)?;
    }
    w.flush().map_err(|e| ReplayError::Io {
        path: path.into(),
        cause: e.to_string(),
    })
}
