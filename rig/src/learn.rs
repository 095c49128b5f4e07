//! `rig learn`: independent learning experiments in one process, in parallel.

use crate::exit::{Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;
use runtime::config::ExperimentConfig;
use runtime::learn::{LearnOptions, learn};

use crate::selection::{Selection, resolve_selection};

#[derive(Flags)]
pub struct Args {
    #[command(flatten)]
    selection: Selection,
    /// Output directory. It is this command's while it runs (DIR/.lock): another `rig
    /// run` or `rig learn` into it is refused, naming this process.
    #[arg(long, value_name = "DIR", default_value = "out/learn")]
    out: PathBuf,
    /// Worker threads [default: one per core].
    #[arg(long)]
    threads: Option<usize>,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    let simulated = |cfg: ExperimentConfig| match cfg.check_simulated() {
        Ok(()) => Ok(cfg),
        Err(e) => Err(anyhow::anyhow!(e)),
    };
    let cfg = resolve_selection(&args.selection)
        .and_then(simulated)
        .usage()?;
    let opts = LearnOptions {
        out: args.out.clone(),
        threads: args.threads,
        progress: if args.quiet {
            runtime::learn::Progress::Hidden
        } else {
            runtime::learn::Progress::Bar
        },
    };
    let s = learn(&cfg, &opts).failure()?;
    if !args.quiet {
        print_summary(&cfg, &s, &args.out);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_summary(cfg: &ExperimentConfig, s: &runtime::learn::LearnSummary, out: &std::path::Path) {
    let steps = s.records.len() as f64 * cfg.task().steps_per_trial() as f64;
    println!(
        "{} {}/{}: {} runs × {} trials in {:.1} s wall ({:.2} µs per learning step, all threads)",
        cfg.task_name(),
        cfg.agent().algo,
        cfg.agent().approx,
        cfg.run().runs,
        cfg.run().trials,
        s.wall.as_secs_f64(),
        s.wall.as_secs_f64() * 1e6 / steps
    );
    if let Some(last) = s.curve.last() {
        println!(
            "  last trial return: mean {:.1}  [95% CI {:.1} … {:.1}]  min {:.1}  max {:.1}",
            last.mean, last.ci_low, last.ci_high, last.min, last.max
        );
    }
    let g = &s.greedy_curve;
    if g.len() >= 3 {
        let tail = &g[g.len() - 3..];
        let mean = tail.iter().map(|p| p.mean).sum::<f64>() / 3.0;
        println!(
            "  greedy return, mean of the last 3 evaluations (trials {}–{}): {:.1}",
            tail[0].trial, tail[2].trial, mean
        );
    }
    if let Some(trial) = s
        .records
        .iter()
        .filter(|r| r.greedy.is_some())
        .map(|r| r.trial)
        .max()
    {
        // Table 4.1's statistic: the last greedy return of every run.
        let last: Vec<f64> = s
            .records
            .iter()
            .filter(|r| r.trial == trial)
            .filter_map(|r| r.greedy)
            .collect();
        let n = last.len() as f64;
        let mean = last.iter().sum::<f64>() / n;
        let var = last.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        // The median too: one run that spins the pendulum moves the mean by hundreds.
        let median = runtime::report::curve::median(&last);
        println!(
            "  greedy return after trial {trial}: mean {mean:.1}, sample std {:.1}, median {median:.1} ({} runs)",
            var.sqrt(),
            last.len()
        );
    }
    println!(
        "  wrote {}/{{runs.csv, curve.csv, greedy_curve.csv, curve.png, curve.svg, config.toml}}",
        out.display()
    );
}
