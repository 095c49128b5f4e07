//! `rig bench-loop`: the lockstep loop next to a raw iceoryx2 ping-pong, and the
//! ping-pong's echo side.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;

#[derive(Flags)]
pub struct Args {
    /// Samples to time in each measurement (after 1000 / one trial of warm-up).
    #[arg(long, default_value_t = 20_000)]
    samples: usize,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/bench-loop")]
    out: PathBuf,
}

/// Runs the command.
pub fn main(args: &Args) -> ExitCode {
    match bench::loop_bench::bench_loop(&args.out, args.samples) {
        Ok(r) => {
            let (s, w) = (&r.step, &r.raw_rtt);
            println!(
                "raw iceoryx2 round trip (2 hops): p50 {:.1} µs  p90 {:.1}  p99 {:.1}  p99.9 {:.1}  max {:.1}  (n = {})",
                w.p50, w.p90, w.p99, w.p999, w.max, w.n
            );
            println!(
                "lockstep step (3 hops + work):   p50 {:.1} µs  p90 {:.1}  p99 {:.1}  p99.9 {:.1}  max {:.1}  (n = {})",
                s.p50, s.p90, s.p99, s.p999, s.max, s.n
            );
            println!(
                "step / three raw one-way hops (medians): {:.2} (target ≤ 1.5); {:.0} lockstep steps/s",
                r.ratio(),
                1e6 / s.p50
            );
            println!("wrote {}/loop.csv", args.out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// The echo side of the raw ping-pong (`rig pong`, hidden).
pub fn pong(run_id: &str, pin_cpus: bool) -> ExitCode {
    match bench::loop_bench::pong(run_id, pin_cpus) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
