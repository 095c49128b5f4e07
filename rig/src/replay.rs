//! `rig replay RUN_DIR`: the observer and the agent of a recorded run run again over its
//! measurements; their estimates and actions are checked against the recording.

use crate::exit::{Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;
use observer::config::ObserverKind;
use runtime::replay::observers::{self, StateErrors};
use runtime::replay::{Recording, ReplayEnd, ReplayError, replay};

#[derive(Flags)]
pub struct Args {
    /// The folder of a finished `rig run` (its run.mcap: the configuration attached, the
    /// metadata, every message).
    #[arg(value_name = "RUN_DIR")]
    dir: PathBuf,
    /// Also run this observer over the recorded measurements (the run's sensor, timing
    /// and observer settings otherwise) and print, per state, its RMS and largest error
    /// against the recorded estimates and against the true state; written as CSV too.
    #[arg(long, value_name = "KIND", value_enum)]
    observer: Option<ObserverKind>,
    /// Where `--observer` writes its table [default: RUN_DIR/observer-KIND.csv].
    #[arg(long, value_name = "FILE", requires = "observer")]
    csv: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// Runs the command: exit 0 when every estimate and action replays as recorded, 1 at a
/// difference, 2 for a recording that cannot be replayed.
pub fn main(args: &Args) -> Outcome {
    Ok(match run(args).usage()? {
        true => ExitCode::SUCCESS,
        false => ExitCode::FAILURE,
    })
}

/// Whether the replay was identical.
fn run(args: &Args) -> Result<bool, ReplayError> {
    let rec = Recording::read(&args.dir)?;
    let about = |k: &str| rec.about.get(k).map_or("?", String::as_str);
    println!(
        "replaying {}: {} samples of task {}, {}/{}, seed {}, timing {}",
        rec.path.display(),
        rec.measurements.len(),
        about("task"),
        about("algo"),
        about("approx"),
        about("seed"),
        about("timing"),
    );
    let bar = runtime::replay::progress_bar(rec.measurements.len() as u64, !args.quiet);
    let outcome = replay(&rec, &bar);
    bar.finish_and_clear();
    let identical = match outcome? {
        ReplayEnd::Identical { counts } => {
            let total: usize = counts.iter().map(|c| c.1).sum();
            let each: Vec<String> = counts.iter().map(|(t, c)| format!("{t} {c}")).collect();
            println!(
                "{total} messages of {} topics replayed, identical ({})",
                counts.len(),
                each.join(", ")
            );
            true
        }
        ReplayEnd::Differs(d) => {
            println!("first difference: {d}");
            false
        }
    };
    if let Some(kind) = args.observer {
        let rows = observers::compare(&rec, kind)?;
        print_table(kind, &rows);
        let path = args
            .csv
            .clone()
            .unwrap_or_else(|| args.dir.join(format!("observer-{kind}.csv")));
        observers::write_csv(&path, &rows)?;
        println!("written to {}", path.display());
    }
    Ok(identical)
}

/// The `--observer` table, one row per state.
fn print_table(kind: ObserverKind, rows: &[StateErrors]) {
    println!("observer {kind} over the recorded measurements, error per state:");
    println!(
        "  {:<12} {:>14} {:>14} {:>14} {:>14} {:>14} {:>14} {:>8}",
        "state",
        "RMS vs rec.",
        "max vs rec.",
        "RMS vs truth",
        "max vs truth",
        "rec. RMS",
        "rec. max",
        "samples"
    );
    for r in rows {
        println!(
            "  {:<12} {:>14.6e} {:>14.6e} {:>14.6e} {:>14.6e} {:>14.6e} {:>14.6e} {:>8}",
            r.state,
            r.vs_recorded.rms(),
            r.vs_recorded.max,
            r.vs_truth.rms(),
            r.vs_truth.max,
            r.recorded_vs_truth.rms(),
            r.recorded_vs_truth.max,
            r.vs_truth.samples
        );
    }
    println!("  (rec. RMS, rec. max: the recorded observer's own estimate against the truth)");
}
