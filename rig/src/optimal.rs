//! `rig optimal`: the optimal return of the pendulum swing-up, by dynamic programming.

use crate::exit::{Fails, Outcome};
use anyhow::Context as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;

#[derive(Flags)]
pub struct Args {
    /// Grid nodes per state dimension: the angle (periodic, on [-π, π)) and the velocity
    /// (on [−8π, 8π] rad/s); an integer in [21, 4001], with grid² × actions ≤ 2·10⁸.
    #[arg(long, value_name = "N", default_value_t = 401)]
    grid: usize,
    /// Action levels, evenly spaced on [−3, 3] V with both bounds (61: steps of 0.1 V);
    /// an integer in [2, 1001].
    #[arg(long, value_name = "M", default_value_t = 61)]
    actions: usize,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR", default_value = "out/optimal")]
    out: PathBuf,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    use bench::optimal::{OptimumOptions, pendulum_optimum, write_trajectory};
    let opts = OptimumOptions {
        grid: args.grid,
        actions: args.actions,
    };
    opts.validate().usage()?;
    let o = pendulum_optimum(&opts).usage()?;
    let csv = args.out.join("optimal.csv");
    let written = std::fs::create_dir_all(&args.out)
        .map_err(anyhow::Error::from)
        .and_then(|()| write_trajectory(&csv, &o.trajectory).map_err(anyhow::Error::from));
    written
        .with_context(|| csv.display().to_string())
        .failure()?;
    println!(
        "pendulum swing-up from [π, 0], 3 s (100 samples), Eq. 3.16: grid {0}×{0} (velocity ±{1:.2} rad/s), {2} action levels",
        opts.grid, o.velocity_limit, opts.actions
    );
    println!(
        "  optimal return, grid value V_0:          {:.2}",
        o.value_grid
    );
    println!(
        "  optimal return, DP policy on the plant:  {:.2}  (gap {:.3} %; max |velocity| {:.1} rad/s)",
        o.simulated_return,
        100.0 * o.relative_gap(),
        o.max_speed
    );
    println!(
        "  wall time {:.1} s (transitions {:.1} s, {} backups {:.1} s)",
        o.wall.as_secs_f64(),
        o.transitions_time.as_secs_f64(),
        o.trajectory.len(),
        o.backups_time.as_secs_f64()
    );
    println!("  wrote {}", csv.display());
    Ok(ExitCode::SUCCESS)
}
