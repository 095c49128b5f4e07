//! `rig check-driver`: a running driver checked against the driver contract.

use crate::exit::{Fails, Outcome};
use std::process::ExitCode;

use std::sync::Arc;

use clap::Args as Flags;
use driver::link::conformance::{CheckOptions, check};

use crate::external::{DriverArgs, TaskArgs};

#[derive(Flags)]
pub struct Args {
    #[command(flatten)]
    driver: DriverArgs,
    /// The task the driver must fit.
    #[command(flatten)]
    task: TaskArgs,
    /// How long to measure the sample rate, answering every sample with zero [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 5.0)]
    rate_seconds: f64,
    /// Largest allowed p99 of the samples' lateness against a regular grid (jitter), as
    /// a fraction of the period.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.1)]
    max_jitter: f64,
    /// Largest allowed fraction of periods without a sample.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.01)]
    max_missed: f64,
    /// Size of the step input, as a fraction of the way from the middle of the action
    /// range to its upper limit (0.25: 0.75 V for the pendulum's ±3 V).
    #[arg(long, value_name = "FRACTION", default_value_t = 0.25)]
    step: f64,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    let fraction = |flag: &str, v: f64| {
        if v.is_finite() && (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            Err(anyhow::anyhow!(
                "`{flag}` {v} is out of range: must be a fraction in [0, 1]"
            ))
        }
    };
    let opts = (|| -> anyhow::Result<CheckOptions> {
        let task = args.task.task()?;
        let d = args.driver.resolve(&task.name)?;
        let rate_seconds =
            runtime::clock::seconds("--rate-seconds", args.rate_seconds)?.as_secs_f64();
        Ok(CheckOptions {
            serve: driver::link::how_to_serve(&task, &d.id, args.task.named().as_deref()),
            driver: d.id,
            task: Arc::new(task),
            timeout: d.timeout,
            reset_timeout: d.reset_timeout,
            rate_seconds,
            max_jitter: fraction("--max-jitter", args.max_jitter)?,
            max_missed: fraction("--max-missed", args.max_missed)?,
            step: fraction("--step", args.step)?,
        })
    })()
    .usage()?;
    println!(
        "rig check-driver: driver {:?} (rig/driver/{}/...) against the {} task",
        opts.driver, opts.driver, opts.task.name
    );
    let outcomes = check(&opts, &mut |o| println!("{o}")).failure()?;
    let failed = outcomes.iter().filter(|o| !o.pass).count();
    if failed == 0 {
        println!("check-driver: PASS ({} checks)", outcomes.len());
        Ok(ExitCode::SUCCESS)
    } else {
        println!(
            "check-driver: FAIL ({failed} of {} checks failed)",
            outcomes.len()
        );
        Ok(ExitCode::FAILURE)
    }
}
