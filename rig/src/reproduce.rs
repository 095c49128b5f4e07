//! `rig reproduce`: the thesis's learning-curve figures, regenerated.

use crate::exit::{Failed, Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;

#[derive(Flags)]
pub struct Args {
    /// Only these figures (comma-separated or repeated): 3.12, 3.17, 3.22, 3.23, 4.4,
    /// 5.5, 5.9, 6.1, 6.5 [default: all].
    #[arg(long, value_name = "ID", value_delimiter = ',')]
    only: Vec<String>,
    /// Runs per experiment [default: the thesis's, 30 for Chapter 3, 20 otherwise].
    #[arg(long)]
    runs: Option<u32>,
    /// Trials per run [default: the presets']; for a quick look, not a reproduction.
    #[arg(long)]
    trials: Option<u32>,
    /// Output directory: one directory per figure and REPORT.md.
    #[arg(long, value_name = "DIR", default_value = "out/reproduce")]
    out: PathBuf,
    /// No progress bars.
    #[arg(long)]
    quiet: bool,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    if args.runs == Some(0) || args.trials == Some(0) {
        return Err(Failed::usage("`--runs` and `--trials` must be at least 1"));
    }
    let opts = bench::reproduce::ReproduceOptions {
        out: args.out.clone(),
        only: args.only.clone(),
        runs: args.runs,
        trials: args.trials,
        progress: !args.quiet,
    };
    let figs = bench::reproduce::reproduce(&opts).failure()?;
    for f in &figs {
        let confirmed = f.claims.iter().filter(|c| c.1).count();
        println!(
            "Figure {}: {:.0} s, {confirmed} of {} claims confirmed",
            f.id,
            f.wall.as_secs_f64(),
            f.claims.len()
        );
    }
    println!("wrote {}", args.out.join("REPORT.md").display());
    Ok(ExitCode::SUCCESS)
}
