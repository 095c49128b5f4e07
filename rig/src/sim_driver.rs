//! `rig sim-driver`: a simulated system served as a driver, through the driver kit.

use crate::exit::{Fails, Outcome};
use observer::config::SensorKind;
use std::process::ExitCode;

use clap::Args as Flags;
use runtime::clock::Timing;

use crate::external::TaskArgs;

#[derive(Flags)]
pub struct Args {
    /// The driver id: its services are rig/driver/ID/{info,sample,command}; letters,
    /// digits, '-' and '_'.
    #[arg(long, value_name = "ID", default_value = "pendulum")]
    driver_id: String,
    /// The task simulated: `--system` pendulum, arm-horizontal, arm-6.4,
    /// double-integrator (arm-vertical cannot rest at its start state within its torque
    /// limits), or `--task FILE`, a task file with a `[simulation]`.
    #[command(flatten)]
    task: TaskArgs,
    /// How the driver keeps time: `realtime` — a sample every period of wall time (÷
    /// `--speed`), as hardware; `lockstep` — sample k+1 only after the action for sample
    /// k arrived, as fast as the rig answers, the same bytes every run; resets place the
    /// system at the start state at once.
    #[arg(long, value_name = "CLOCK", value_enum, default_value_t = Timing::Realtime)]
    clock: Timing,
    /// Run SPEED times faster than real time (a sample every Ts / SPEED of wall time,
    /// advertised as time_scale SPEED); in (0, 1000]; realtime only.
    #[arg(long, value_name = "SPEED", default_value_t = 1.0)]
    speed: f64,
    /// Run under SCHED_FIFO at this priority (1–99), as a hardware driver should, so that
    /// a loaded machine does not delay the sample instants by milliseconds; needs root,
    /// CAP_SYS_NICE or an rtprio limit [default: normal scheduling].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=99))]
    rt_priority: Option<u8>,
    #[command(flatten)]
    wakeup: runtime::process::Wakeup,
    /// Spin (a busy core) instead of sleeping for the last this many µs before each
    /// sample instant, so that the instant does not depend on the operating system's
    /// wake-up latency; larger values trade CPU for less jitter.
    #[arg(long, value_name = "US", default_value_t = 1000)]
    spin_us: u64,
    /// What the samples report: `full` — the whole state; `angle` — an encoder-only
    /// setup, as the physical pendulum of §6.4.1: positions quantised to
    /// `--counts-per-rev`, velocities NaN (not measured). Against an `angle` driver, run
    /// the rig with `--sensor angle` and an observer that estimates the velocities.
    #[arg(long, value_name = "SENSOR", value_enum, default_value_t = SensorKind::Full)]
    sensor: SensorKind,
    /// Encoder counts per revolution with `--sensor angle`.
    #[arg(long, value_name = "N", default_value_t = 4096)]
    counts_per_rev: u32,
    /// Log resets, rejected commands, watchdog trips and missed periods to stderr.
    #[arg(long)]
    verbose: bool,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    use driver::{Serving, Simulated, serve, serve_lockstep};
    let lockstep = args.clock == Timing::Lockstep;
    let device = driver::contract::check_id(&args.driver_id)
        .map_err(|e| anyhow::anyhow!("`--driver-id`: {e}"))
        .and_then(|()| {
            if lockstep && args.speed != 1.0 {
                anyhow::bail!("`--speed` applies to the realtime clock only: in lockstep the driver runs as fast as the rig answers");
            }
            args.task.task()
        })
        .and_then(|task| Ok(Simulated::of(task, args.speed)?))
        .map(|d| if lockstep { d.in_lockstep() } else { d })
        .and_then(|d| match args.sensor {
            SensorKind::Angle => Ok(d.measuring_positions_only(args.counts_per_rev)?),
            SensorKind::Full => Ok(d),
        });
    let mut device = device.usage()?;
    let served = runtime::process::set_rt_priority(args.rt_priority)
        .map_err(anyhow::Error::from)
        .and_then(|()| {
            let _wakeup = args.wakeup.hold()?;
            let task = driver::Device::task(&device);
            let sensed = match args.sensor {
                SensorKind::Angle => format!("positions only, {} counts/rev", args.counts_per_rev),
                SensorKind::Full => "full state".to_string(),
            };
            let clock = if lockstep {
                "lockstep".to_string()
            } else {
                format!(
                    "period {:.3} ms of wall time (speed {})",
                    task.ts * 1e3 / args.speed,
                    args.speed
                )
            };
            eprintln!(
                "driver {:?}: task {} ({sensed}), Ts {} ms, {clock}",
                args.driver_id,
                task.name,
                task.ts * 1e3,
            );
            let how = Serving {
                stop_after: None,
                spin_ns: args.spin_us.saturating_mul(1000),
                verbose: args.verbose,
            };
            if lockstep {
                Ok(serve_lockstep(&mut device, &args.driver_id, &how)?)
            } else {
                Ok(serve(&mut device, &args.driver_id, &how)?)
            }
        });
    let s = served.failure()?;
    eprintln!(
        "driver: stopped after {} samples ({} periods missed)",
        s.samples, s.missed
    );
    Ok(ExitCode::SUCCESS)
}
