//! `rig delay-study`: how a sample-to-actuation delay hurts learning, and how much
//! predictive timing recovers.

use crate::exit::{Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;
use observer::config::ObserverModel;

#[derive(Flags)]
pub struct Args {
    /// Runs per cell.
    #[arg(long, default_value_t = 10)]
    runs: u32,
    /// Trials per run [default: the presets'; VGBP-LSTD 200, MLAC/LLR 400].
    #[arg(long)]
    trials: Option<u32>,
    /// Injected delays [ms], each in [0, Ts = 30) (comma-separated).
    #[arg(long, value_name = "MS", value_delimiter = ',', default_values_t = bench::delay_study::DELAYS_MS)]
    delays: Vec<f64>,
    /// The predictive estimator's process model: learned (LLR, online) or known (the
    /// plant's dynamics — the reference for a perfect prediction) (`observer.model`).
    #[arg(long, default_value = "learned", value_enum)]
    observer_model: ObserverModel,
    /// Worker threads [default: one per core].
    #[arg(long)]
    threads: Option<usize>,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/delay-study")]
    out: PathBuf,
    /// No per-cell lines and no summary.
    #[arg(long)]
    quiet: bool,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    let opts = bench::delay_study::DelayStudyOptions {
        runs: args.runs,
        trials: args.trials,
        delays_ms: args.delays.clone(),
        model: args.observer_model,
        out: args.out.clone(),
        threads: args.threads,
        verbose: !args.quiet,
    };
    bench::delay_study::delay_study(&opts).failure()?;
    if !args.quiet {
        println!(
            "wrote {}/{{cells.csv, summary.txt, final_return.png, final_return.svg, curves-*.png, curves-*.svg, */}}",
            args.out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}
