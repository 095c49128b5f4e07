//! `runs.csv`: `run,trial,sim_time_s,return,greedy_return`, one row per learning trial
//! in (run, trial) order (`greedy_return` blank except every `eval_every` trials), and
//! what is computed from its rows: the learning curves and each run's final greedy return.

use std::collections::BTreeMap;
use std::io::Write;

use crate::experiment::TrialRecord;
use crate::report::{self, CurveError, CurvePoint};

/// The header of `runs.csv`.
pub const RUNS_HEADER: &str = "run,trial,sim_time_s,return,greedy_return";

/// One `runs.csv` row (numbers in Rust's shortest round-trip form).
pub fn write_row(out: &mut impl Write, r: &TrialRecord) -> std::io::Result<()> {
    match r.greedy {
        Some(g) => writeln!(
            out,
            "{},{},{},{},{}",
            r.run, r.trial, r.sim_time_s, r.ret, g
        ),
        None => writeln!(out, "{},{},{},{},", r.run, r.trial, r.sim_time_s, r.ret),
    }
}

/// Writes `runs.csv` in run order, each row as soon as it can be: the rows of the first
/// unfinished run as its trials end (a study can follow a run trial by trial), those of
/// later runs once every run before them has finished.
pub(crate) struct OrderedWriter<W: Write> {
    /// The run whose rows are written as they come.
    next: u32,
    /// Rows of later runs, and whether each has finished.
    pending: BTreeMap<u32, (Vec<TrialRecord>, bool)>,
    out: W,
}

impl<W: Write> OrderedWriter<W> {
    /// A writer whose first run is run 0.
    pub(crate) fn new(out: W) -> Self {
        Self {
            next: 0,
            pending: BTreeMap::new(),
            out,
        }
    }

    /// One trial of `run` has ended.
    pub(crate) fn trial(&mut self, run: u32, r: &TrialRecord) -> std::io::Result<()> {
        if run == self.next {
            write_row(&mut self.out, r)?;
            self.out.flush()?;
        } else {
            self.pending.entry(run).or_default().0.push(r.clone());
        }
        Ok(())
    }

    /// Every trial of `run` has ended.
    pub(crate) fn finished(&mut self, run: u32) -> std::io::Result<()> {
        self.pending.entry(run).or_default().1 = true;
        while self.pending.get(&self.next).is_some_and(|(_, done)| *done) {
            self.pending.remove(&self.next);
            self.next += 1;
            if let Some((rows, _)) = self.pending.get_mut(&self.next) {
                for r in rows.drain(..) {
                    write_row(&mut self.out, &r)?;
                }
            }
        }
        self.out.flush()?;
        Ok(())
    }
}

/// The greedy evaluations a run's final policy is judged by (the thesis's figures end on
/// them): the mean of the last this many.
pub const LAST_EVALUATIONS: usize = 3;

/// Per run, the mean of its last [`LAST_EVALUATIONS`] greedy evaluations.
pub fn final_greedy(records: &[TrialRecord], runs: u32) -> Result<Vec<f64>, CurveError> {
    (0..runs)
        .map(|run| {
            let g: Vec<f64> = records
                .iter()
                .filter(|r| r.run == run)
                .filter_map(|r| r.greedy)
                .collect();
            let last = &g[g.len().saturating_sub(LAST_EVALUATIONS)..];
            if last.is_empty() {
                return Err(CurveError::NoEvaluation { run });
            }
            Ok(last.iter().sum::<f64>() / last.len() as f64)
        })
        .collect()
}

/// Learning and greedy curves from the records of `runs` runs of `trials` trials.
pub fn curves(
    records: &[TrialRecord],
    runs: usize,
    trials: usize,
) -> Result<(Vec<CurvePoint>, Vec<CurvePoint>), CurveError> {
    let mut ret = vec![Vec::with_capacity(runs); trials];
    let mut time = vec![0.0; trials];
    let mut greedy: BTreeMap<u32, (f64, Vec<f64>)> = BTreeMap::new();
    for r in records {
        let i = r.trial as usize - 1;
        ret[i].push(r.ret);
        time[i] = r.sim_time_s;
        if let Some(g) = r.greedy {
            greedy
                .entry(r.trial)
                .or_insert_with(|| (r.sim_time_s, Vec::new()))
                .1
                .push(g);
        }
    }
    let trial_numbers: Vec<u32> = (1..=trials as u32).collect();
    let curve = report::curve(&trial_numbers, &time, &ret)?;
    let greedy_curve = if greedy.is_empty() {
        Vec::new()
    } else {
        let t: Vec<u32> = greedy.keys().copied().collect();
        let s: Vec<f64> = greedy.values().map(|v| v.0).collect();
        let v: Vec<Vec<f64>> = greedy.into_values().map(|v| v.1).collect();
        report::curve(&t, &s, &v)?
    };
    Ok((curve, greedy_curve))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(run: u32, trial: u32) -> TrialRecord {
        TrialRecord {
            run,
            trial,
            sim_time_s: f64::from(trial),
            ret: -1.0,
            greedy: None,
        }
    }

    fn rows(w: &OrderedWriter<Vec<u8>>) -> Vec<String> {
        String::from_utf8(w.out.clone())
            .unwrap()
            .lines()
            .map(|l| l[..3].to_string())
            .collect()
    }

    #[test]
    fn the_first_unfinished_run_is_written_as_its_trials_end_and_later_runs_wait() {
        let mut w = OrderedWriter::new(Vec::new());
        w.trial(1, &record(1, 1)).unwrap();
        w.trial(0, &record(0, 1)).unwrap();
        assert_eq!(rows(&w), ["0,1"], "run 0's row at once, run 1's held back");
        w.trial(2, &record(2, 1)).unwrap();
        w.trial(2, &record(2, 2)).unwrap();
        w.finished(2).unwrap();
        w.trial(0, &record(0, 2)).unwrap();
        assert_eq!(rows(&w), ["0,1", "0,2"]);
        w.finished(0).unwrap();
        assert_eq!(
            rows(&w),
            ["0,1", "0,2", "1,1"],
            "run 1 is now written as it goes"
        );
        w.trial(1, &record(1, 2)).unwrap();
        assert_eq!(rows(&w), ["0,1", "0,2", "1,1", "1,2"]);
        w.finished(1).unwrap();
        assert_eq!(
            rows(&w),
            ["0,1", "0,2", "1,1", "1,2", "2,1", "2,2"],
            "the finished run 2 follows at once, in run order"
        );
        assert!(w.pending.is_empty());
    }
}
