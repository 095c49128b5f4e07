//! Sample-to-actuation delays and when an action takes effect.
//!
//! * [`Delays`] — the delay of each sample: fixed (`run.delay_ms`) or drawn from a
//!   recorded distribution (`run.delay_from`, e.g. `rig latency`'s `latency.csv` or a
//!   real driver's recording), from the run seed's own stream [`STREAM`] so delay studies
//!   are reproducible and a run's exploration and sensor noise do not change with them.
//! * [`read_csv`] — the recorded distribution: one delay per row in a named column.
//! * [`Actuator`] — applies the agent's answer to a sample to the plant: *direct* timing
//!   applies it within the interval after the sample's delay ([`crate::Plant::step_delayed`]);
//!   *predictive* timing (thesis §6.4.1; docs/latency.md)
//!   holds it and applies it at the next sample instant for the whole interval — a
//!   one-sample action pipeline, on which a delay below `Ts` has no effect.
//!
//! Both drivers (`rig learn` in process, the plant process of `rig run`) run one
//! [`Actuator`] per run and call it once per simulated interval, learning and greedy
//! trials alike, so they draw the same delays in the same order.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::Plant;

/// Stream id of the delay stream derived from a run seed (the list of all:
/// `agent::explore::stream`).
pub const STREAM: u64 = 3;

/// The sample-to-actuation delay of each sample \[s\].
#[derive(Clone, Debug)]
pub enum Delays {
    /// The same delay every sample.
    Fixed(f64),
    /// Drawn uniformly from recorded delays, one draw per sample.
    Recorded {
        /// The recorded delays \[s\], each in `[0, Ts)`.
        values: Arc<Vec<f64>>,
        /// The run's delay stream.
        rng: Box<ChaCha8Rng>,
    },
}

impl Delays {
    /// A fixed delay of `delay` seconds.
    pub fn fixed(delay: f64) -> Self {
        Delays::Fixed(delay)
    }

    /// Delays drawn from `values` (non-empty) with stream [`STREAM`] of `run_seed`.
    pub fn recorded(values: Arc<Vec<f64>>, run_seed: u64) -> Self {
        assert!(!values.is_empty());
        let mut rng = ChaCha8Rng::seed_from_u64(run_seed);
        rng.set_stream(STREAM);
        Delays::Recorded {
            values,
            rng: Box::new(rng),
        }
    }

    /// The next sample's delay \[s\].
    pub fn draw(&mut self) -> f64 {
        match self {
            Delays::Fixed(d) => *d,
            Delays::Recorded { values, rng } => values[rng.random_range(0..values.len())],
        }
    }

    /// Whether every delay is zero (the thesis's simulations).
    pub fn is_zero(&self) -> bool {
        matches!(self, Delays::Fixed(d) if *d == 0.0)
    }
}

/// The unit of a delay column, in seconds, from its name's suffix; `None` if the name
/// does not tell.
fn unit_of(column: &str) -> Option<f64> {
    if column == "sample_to_actuation" {
        // `rig latency`'s latency.csv: stages in ns.
        return Some(1e-9);
    }
    [("_ns", 1e-9), ("_us", 1e-6), ("_ms", 1e-3), ("_s", 1.0)]
        .iter()
        .find(|(suffix, _)| column.ends_with(suffix))
        .map(|&(_, unit)| unit)
}

/// Reads recorded delays \[s\] from the CSV file `path` (a header row, then one row per
/// sample): column `column`, or if `None` the first of `delay_ms`, `sample_to_actuation`
/// the file has. The unit is the column name's suffix (`_s`, `_ms`, `_us`, `_ns`;
/// `sample_to_actuation` is `rig latency`'s ns). Empty cells (cycles without a value, such
/// as `latency.csv`'s deadline misses) are skipped. Every value must be finite and in
/// `[0, ts)`; the error names the file, column, row (1-based, the header is row 1) and
/// the allowed range.
pub fn read_csv(path: &Path, column: Option<&str>, ts: f64) -> Result<Vec<f64>, DelayFileError> {
    let file = || path.to_path_buf();
    let text = std::fs::read_to_string(path).map_err(|error| DelayFileError::Read {
        file: file(),
        error,
    })?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| DelayFileError::Empty(file()))?
        .split(',')
        .map(str::trim)
        .collect();
    let want: Vec<&str> = match column {
        Some(c) => vec![c],
        None => vec!["delay_ms", "sample_to_actuation"],
    };
    let (index, name) = want
        .iter()
        .find_map(|w| header.iter().position(|h| h == w).map(|i| (i, *w)))
        .ok_or_else(|| DelayFileError::NoColumn {
            file: file(),
            want: want.join(" or "),
            columns: header.join(", "),
        })?;
    let unit = unit_of(name).ok_or_else(|| DelayFileError::NoUnit {
        file: file(),
        column: name.to_string(),
    })?;
    let at = |row: usize, cell: &str| Cell {
        file: file(),
        column: name.to_string(),
        row,
        cell: cell.to_string(),
        ts_ms: ts * 1e3,
    };
    let mut out = Vec::new();
    for (i, line) in lines.enumerate() {
        let row = i + 2;
        let cell = line.split(',').nth(index).map(str::trim).unwrap_or("");
        if cell.is_empty() {
            continue;
        }
        let v: f64 = cell
            .parse()
            .map_err(|_| DelayFileError::NotANumber(at(row, cell)))?;
        let d = v * unit;
        if !(d.is_finite() && d >= 0.0 && d < ts) {
            return Err(DelayFileError::OutOfRange(at(row, cell)));
        }
        out.push(d);
    }
    if out.is_empty() {
        return Err(DelayFileError::NoDelays {
            file: file(),
            column: name.to_string(),
        });
    }
    Ok(out)
}

/// What is wrong with a delay file ([`read_csv`]); each names the file.
#[derive(Debug, thiserror::Error)]
pub enum DelayFileError {
    /// The file cannot be read.
    #[error("{}: cannot read: {error}", .file.display())]
    Read {
        /// The file.
        file: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The file has no header row.
    #[error("{}: is empty; wants a header row and one delay per row", .0.display())]
    Empty(PathBuf),
    /// The file has none of the columns wanted.
    #[error("{}: has no column {want} (its columns: {columns})", .file.display())]
    NoColumn {
        /// The file.
        file: PathBuf,
        /// The columns wanted, "a or b".
        want: String,
        /// The file's columns, comma-separated.
        columns: String,
    },
    /// A column whose name has no unit suffix.
    #[error(
        "{}: cannot tell the unit of column {column}: name it with a suffix _s, _ms, _us or _ns",
        .file.display()
    )]
    NoUnit {
        /// The file.
        file: PathBuf,
        /// The column.
        column: String,
    },
    /// A cell that is not a number.
    #[error(
        "{}: column {}, row {}: {:?} is not a number; must be in [0, {}) ms (less than one sample period Ts)",
        .0.file.display(), .0.column, .0.row, .0.cell, .0.ts_ms
    )]
    NotANumber(Cell),
    /// A delay outside `[0, Ts)`.
    #[error(
        "{}: column {}, row {}: {} is out of range: must be in [0, {}) ms (less than one sample period Ts)",
        .0.file.display(), .0.column, .0.row, .0.cell, .0.ts_ms
    )]
    OutOfRange(Cell),
    /// A column without a single delay.
    #[error("{}: column {column} holds no delays", .file.display())]
    NoDelays {
        /// The file.
        file: PathBuf,
        /// The column.
        column: String,
    },
}

/// Where a bad cell of a delay file is ([`DelayFileError`]).
#[derive(Debug)]
pub struct Cell {
    /// The file.
    pub file: PathBuf,
    /// The column.
    pub column: String,
    /// The row, 1-based (the header is row 1).
    pub row: usize,
    /// The cell's text.
    pub cell: String,
    /// The sample period Ts \[ms\], which a delay must be less than.
    pub ts_ms: f64,
}

/// When the agent's answer to a sample takes effect ([module documentation](self)).
pub struct Actuator {
    delays: Delays,
    /// Predictive timing: the action held for the next sample instant.
    pipelined: Option<Vec<f64>>,
    /// The last interval's delay \[s\].
    last_delay: f64,
}

impl Actuator {
    /// For actions of dimension `m`: direct timing (`pipelined = false`) or the one-sample
    /// pipeline of predictive timing, with sample-to-actuation delays `delays`.
    pub fn new(m: usize, pipelined: bool, delays: Delays) -> Self {
        Self {
            delays,
            pipelined: pipelined.then(|| vec![0.0; m]),
            last_delay: 0.0,
        }
    }

    /// A trial starts: predictive timing holds the safe action (zero) until
    /// [`Actuator::prime`] gives the first interval's.
    pub fn reset(&mut self) {
        if let Some(p) = &mut self.pipelined {
            p.fill(0.0);
        }
    }

    /// Predictive timing: `u_0`, the first interval's action — computed from the known
    /// start state before the trial's first interval — is applied over that interval.
    /// Nothing in direct timing.
    pub fn prime(&mut self, u0: &[f64]) {
        if let Some(p) = &mut self.pipelined {
            p.copy_from_slice(u0);
        }
    }

    /// Whether the timing is predictive: the answer to a sample is applied at the next
    /// sample instant.
    pub fn is_pipelined(&self) -> bool {
        self.pipelined.is_some()
    }

    /// The action the plant applies from the current sample instant on, as sent
    /// (predictive timing); `None` in direct timing, where it is not known at the instant.
    pub fn next_action(&self) -> Option<&[f64]> {
        self.pipelined.as_deref()
    }

    /// The delay drawn for the last interval \[s\] (in predictive timing the time after
    /// the sample at which the action arrived, held until the next instant).
    pub fn last_delay(&self) -> f64 {
        self.last_delay
    }

    /// The interval after a sample whose answer is `u`: direct timing applies `u` after
    /// the sample's delay; predictive timing applies the held action for the whole
    /// interval and holds `u` for the next. Returns the interval's reward
    /// ([`Plant::step`]). One delay is drawn per interval in both timings.
    pub fn interval(&mut self, plant: &mut Plant, u: &[f64]) -> f64 {
        self.last_delay = self.delays.draw();
        match &mut self.pipelined {
            None => plant.step_delayed(u, self.last_delay),
            Some(held) => {
                let r = plant.step(held);
                held.copy_from_slice(u);
                r
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let p = std::env::temp_dir().join(format!("plant-delay-{}-{name}", std::process::id()));
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn reads_ms_and_latency_ns_columns_and_names_bad_rows() {
        let p = write("a.csv", "seq,delay_ms\n0,5\n1,\n2,12.5\n");
        assert_eq!(read_csv(&p, None, 0.03).unwrap(), vec![0.005, 0.0125]);
        let p = write("b.csv", "seq,sample_to_actuation,slack\n0,1000000,0\n");
        assert_eq!(read_csv(&p, None, 0.03).unwrap(), vec![0.001]);
        let p = write("c.csv", "delay_ms\n5\n30\n");
        let e = read_csv(&p, None, 0.03).unwrap_err();
        assert!(
            matches!(&e, DelayFileError::OutOfRange(c) if c.row == 3 && c.column == "delay_ms"),
            "{e:?}"
        );
        let e = e.to_string();
        assert!(e.contains("row 3") && e.contains("[0, 30) ms"), "{e}");
        let e = read_csv(&p, Some("lag"), 0.03).unwrap_err().to_string();
        assert!(e.contains("no column lag") && e.contains("delay_ms"), "{e}");
        let p = write("d.csv", "delay_ms\n-1\n");
        assert!(
            read_csv(&p, None, 0.03)
                .unwrap_err()
                .to_string()
                .contains("row 2")
        );
        let p = write("n.csv", "delay_ms\nfive\n");
        let e = read_csv(&p, None, 0.03).unwrap_err();
        assert!(matches!(e, DelayFileError::NotANumber(_)), "{e:?}");
        assert!(e.to_string().ends_with(
            "row 2: \"five\" is not a number; must be in [0, 30) ms (less than one sample period Ts)"
        ));
        let p = write("e.csv", "delay_ms\nNaN\n");
        assert!(
            read_csv(&p, None, 0.03)
                .unwrap_err()
                .to_string()
                .contains("out of range")
        );
        let missing = std::env::temp_dir().join("plant-delay-missing.csv");
        assert!(
            read_csv(&missing, None, 0.03)
                .unwrap_err()
                .to_string()
                .contains("cannot read")
        );
    }

    #[test]
    fn recorded_delays_are_deterministic_per_run_seed() {
        let v = Arc::new(vec![0.0, 0.001, 0.002, 0.003]);
        let draw = |seed| {
            let mut d = Delays::recorded(v.clone(), seed);
            (0..20).map(|_| d.draw()).collect::<Vec<_>>()
        };
        assert_eq!(draw(1), draw(1));
        assert_ne!(draw(1), draw(2));
    }
}
