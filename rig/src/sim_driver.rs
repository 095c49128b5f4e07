//! `rig sim-driver`: a simulated system served as a driver, through the driver kit.

use std::process::ExitCode;

use clap::Args as Flags;
use plant::SystemName;
use plant::config::Choice;

#[derive(Flags)]
pub struct Args {
    /// The driver id: its services are rig/driver/ID/{info,sample,command}; letters,
    /// digits, '-' and '_'.
    #[arg(long, value_name = "ID", default_value = "pendulum")]
    driver_id: String,
    /// The system simulated: pendulum, arm-horizontal, arm-6.4, double-integrator
    /// (arm-vertical cannot rest at its start state within its torque limits).
    #[arg(long, value_parser = SystemName::parse, default_value = "pendulum")]
    system: SystemName,
    /// Run SPEED times faster than real time (a sample every Ts / SPEED of wall time,
    /// advertised as time_scale SPEED); in (0, 1000].
    #[arg(long, value_name = "SPEED", default_value_t = 1.0)]
    speed: f64,
    /// Run under SCHED_FIFO at this priority (1–99), as a hardware driver should, so that
    /// a loaded machine does not delay the sample instants by milliseconds; needs root,
    /// CAP_SYS_NICE or an rtprio limit [default: normal scheduling].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=99))]
    rt_priority: Option<u8>,
    /// Spin (a busy core) instead of sleeping for the last this many µs before each
    /// sample instant, so that the instant does not depend on the operating system's
    /// wake-up latency; larger values trade CPU for less jitter.
    #[arg(long, value_name = "US", default_value_t = 1000)]
    spin_us: u64,
    /// What the samples report: `full` — the whole state; `angle` — an encoder-only
    /// setup, as the physical pendulum of §6.4.1: positions quantised to
    /// `--counts-per-rev`, velocities NaN (not measured). Against an `angle` driver, run
    /// the rig with `--sensor angle` and an observer that estimates the velocities.
    #[arg(long, value_name = "SENSOR", value_parser = ["full", "angle"], default_value = "full")]
    sensor: String,
    /// Encoder counts per revolution with `--sensor angle`.
    #[arg(long, value_name = "N", default_value_t = 4096)]
    counts_per_rev: u32,
    /// Log resets, rejected commands, watchdog trips and missed periods to stderr.
    #[arg(long)]
    verbose: bool,
}

/// Runs the command.
pub fn main(args: &Args) -> ExitCode {
    use driver::{Serving, Simulated, serve};
    let device = driver::contract::check_id(&args.driver_id)
        .map_err(|e| anyhow::anyhow!("`--driver-id`: {e}"))
        .and_then(|()| Simulated::new(args.system, args.speed))
        .and_then(|d| match args.sensor.as_str() {
            "angle" => d.measuring_positions_only(args.counts_per_rev),
            _ => Ok(d),
        });
    let mut device = match device {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let served = runtime::process::set_rt_priority(args.rt_priority).and_then(|()| {
        let ts = driver::Device::task(&device).ts;
        eprintln!(
            "driver {:?}: {} ({}), Ts {} ms, period {:.3} ms of wall time (speed {})",
            args.driver_id,
            args.system,
            match args.sensor.as_str() {
                "angle" => format!("positions only, {} counts/rev", args.counts_per_rev),
                _ => "full state".to_string(),
            },
            ts * 1e3,
            ts * 1e3 / args.speed,
            args.speed
        );
        let how = Serving {
            stop_after: None,
            spin_ns: args.spin_us.saturating_mul(1000),
            verbose: args.verbose,
        };
        serve(&mut device, &args.driver_id, &how)
    });
    match served {
        Ok(s) => {
            eprintln!(
                "driver: stopped after {} samples ({} periods missed)",
                s.samples, s.missed
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
