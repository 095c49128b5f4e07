//! `rig`: run the thesis's learning experiments.

use std::path::PathBuf;
use std::process::ExitCode;

use agent::config::{
    Algo, ApproxKind, Choice, HorizonKind, ObserverKind, ObserverMode, ObserverModel, Overrides,
    SensorKind, resolve,
};
use clap::{Args, Parser, Subcommand};
use plant::{SystemName, Task};
use runtime::check_driver::{CheckOptions, check};
use runtime::learn::{LearnOptions, learn};
use runtime::process::ProcessArgs;
use runtime::run::{ExternalDriver, RunOptions, run};

/// Learning controllers of Grondman's thesis "Online Model Learning Algorithms for
/// Actor-Critic Control": run experiments, write learning curves.
#[derive(Parser)]
#[command(name = "rig", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run independent learning experiments in one process, in parallel on all cores,
    /// and write runs.csv, curve.csv, greedy_curve.csv, curve.png/svg and config.toml.
    Learn(LearnArgs),
    /// Run one experiment as three processes — plant, observer, agent — exchanging
    /// measurements, estimates and actions over iceoryx2 shared memory in lockstep;
    /// writes returns.csv, config.toml and one log per process.
    Run(RunArgs),
    /// Print the resolved configuration (preset ← --config file ← flags) as TOML, to
    /// start a configuration file from.
    Config(Selection),
    /// Check a running external driver against the driver contract (docs/driver.md):
    /// payload types, advertised limits, reset, sample rate and jitter, step response,
    /// the stale-action watchdog, clamping and rejection of bad actions. Prints one
    /// PASS/FAIL line per check; exits non-zero if any fails.
    CheckDriver(CheckDriverArgs),
    /// Be a driver (docs/driver.md) for a simulated system, in Rust: a sample every
    /// Ts / SPEED on the monotonic clock, actions applied from their arrival (clamped,
    /// non-finite ones rejected), the watchdog, resets by a PD brake.
    /// The stand-in for a motor driver process (`rig run --plant external`); its code,
    /// the driver kit (`driver`), is the template for one (`driver/examples/motor_driver.rs`).
    /// Runs until Ctrl-C or SIGTERM.
    SimDriver(SimDriverArgs),
    /// Compute the optimal return of the pendulum swing-up from [π, 0] (one 3 s trial,
    /// Eq. 3.16) by dynamic programming on a grid, run the DP's policy on the plant, and
    /// write its trajectory to DIR/optimal.csv (t, angle, velocity, u, reward).
    Optimal(OptimalArgs),
    /// Measure the three-process lockstep loop (trivial agent, no recorder) next to a
    /// raw iceoryx2 ping-pong between two processes, in the same run; writes loop.csv.
    BenchLoop(BenchLoopArgs),
    /// Measure the latency budget of the three-process loop in real time (angle sensor,
    /// an observer, the default learner, recorded): per hop and per stage percentiles
    /// from every message's timestamps, deadline misses, sample-instant jitter, next to
    /// a raw iceoryx2 ping-pong measured in the same run. Writes DIR/latency.csv (one row
    /// per cycle), DIR/summary.txt, a histogram (DIR/latency.png, .svg) and DIR/run/.
    Latency(LatencyArgs),
    /// How a sample-to-actuation delay hurts learning and how much predictive timing
    /// recovers: VGBP-LSTD and MLAC/LLR on the pendulum with angle-only sensing and the
    /// predictive estimator, direct vs predictive timing (`--observer-mode`), injected
    /// delays 0, 5, 10, 20 ms. Writes DIR/cells.csv (final greedy return per cell: mean,
    /// sd, 95 % CI), DIR/final_return.png/.svg, DIR/curves-*.png/.svg, DIR/summary.txt
    /// (the table and the acceptance checks at 10 ms, one-sided Welch t-test) and each
    /// cell's `rig learn` output.
    DelayStudy(DelayStudyArgs),
    /// The echo side of `rig bench-loop`'s raw ping-pong.
    #[command(hide = true)]
    Pong {
        /// Run id of the ping-pong.
        #[arg(long)]
        run_id: String,
        /// Pin to the last CPU (the plant's under `--pin-cpus`).
        #[arg(long)]
        pin_cpus: bool,
    },
    /// Regenerate the thesis's learning-curve figures (3.12, 3.17, 3.22, 3.23, 4.4, 5.5,
    /// 5.9, 6.1, 6.5) from the presets with the thesis's numbers of runs, and write
    /// DIR/REPORT.md: per figure the plot (PNG, SVG), "thesis says / we measured" and the
    /// thesis's claims checked against the new data.
    Reproduce(ReproduceArgs),
    /// The plant process of a run (started by `rig run`, or by hand).
    Plant(ProcessArgs),
    /// The observer process of a run (started by `rig run`, or by hand).
    Observer(ProcessArgs),
    /// The agent process of a run (started by `rig run`, or by hand).
    Agent(ProcessArgs),
}

#[derive(Args)]
struct ReproduceArgs {
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

#[derive(Args)]
struct DelayStudyArgs {
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
    #[arg(long, default_value = "learned", value_parser = ObserverModel::parse)]
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

#[derive(Args)]
struct BenchLoopArgs {
    /// Samples to time in each measurement (after 1000 / one trial of warm-up).
    #[arg(long, default_value_t = 20_000)]
    samples: usize,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/bench-loop")]
    out: PathBuf,
}

#[derive(Args)]
struct LatencyArgs {
    /// Samples (cycles) to time, at least (whole 3 s trials are run).
    #[arg(long, default_value_t = 10_000)]
    cycles: usize,
    /// Sampling period [ms] (the pendulum's Ts is 30 ms; a shorter period runs the
    /// simulation faster than real time).
    #[arg(long, value_name = "MS", default_value_t = 30.0)]
    period_ms: f64,
    /// State observer on the angle encoder: finite-difference or predictive.
    #[arg(long, default_value = "predictive", value_parser = ObserverKind::parse)]
    observer: ObserverKind,
    /// Timing: predictive (the plant applies the action answering sample k at the next
    /// sample instant t_{k+1}; a deadline miss when it has not arrived by then; needs
    /// `--observer predictive`) or direct (applied when it arrives, within the interval).
    #[arg(long, default_value = "predictive", value_parser = ObserverMode::parse)]
    observer_mode: ObserverMode,
    /// Raw ping-pong round trips for the baseline.
    #[arg(long, default_value_t = 20_000)]
    raw_samples: usize,
    #[command(flatten)]
    scheduling: runtime::process::Scheduling,
    /// Measure at `--period-ms`, then at periods shortened 1.5 × each (DIR/period-MS/),
    /// until one misses a deadline; writes DIR/sweep.csv and names the fastest period
    /// sustained for `--cycles` cycles without a miss.
    #[arg(long)]
    sweep: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/latency")]
    out: PathBuf,
}

#[derive(Args)]
struct OptimalArgs {
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

#[derive(Args)]
struct RunArgs {
    #[command(flatten)]
    selection: Selection,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/run")]
    out: PathBuf,
    /// Run id shared by the three processes [default: unique per invocation].
    #[arg(long)]
    run_id: Option<String>,
    /// `lockstep`: simulated time advances only when the action for a sample has
    /// arrived (deterministic). `realtime`: the plant samples at absolute deadlines of
    /// Ts / speed; a late action is applied from the moment it arrives, the previous one
    /// held until then, and the miss is counted.
    #[arg(long, default_value = "lockstep", value_parser = ["lockstep", "realtime"])]
    timing: String,
    /// Realtime only: how many times faster than real time to run (e.g. 10: a 30 ms
    /// sample period takes 3 ms).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    #[command(flatten)]
    scheduling: runtime::process::Scheduling,
    /// `sim`: the plant process simulates the system. `external`: a driver someone else
    /// started (docs/driver.md; e.g. examples/python_driver/driver.py) is the system and
    /// the clock; `rig run` waits for it, and the plant process resets it before each
    /// trial and passes its samples and the agent's actions on (`--timing` and `--speed`
    /// do not apply).
    #[arg(long, default_value = "sim", value_parser = ["sim", "external"])]
    plant: String,
    #[command(flatten)]
    driver: DriverArgs,
    /// Continue the run in DIR after a crash, a killed process or Ctrl-C: from its last
    /// trial that is complete in returns.csv, in the agent's checkpoints
    /// (DIR/checkpoints) and in run.mcap. The configuration is DIR/config.toml; of the
    /// experiment flags only `--trials` may be given (to learn on past the original
    /// end). `--timing`, `--speed`, `--plant` and the driver flags apply to the part that
    /// is run now. Completed trials stay in returns.csv and run.mcap.
    #[arg(long, value_name = "DIR", conflicts_with = "out")]
    resume: Option<PathBuf>,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
}

/// The experiment flags given besides `--trials` (which `rig run --resume` refuses).
fn experiment_flags(s: &Selection) -> Vec<&'static str> {
    [
        ("--system", s.system.is_some()),
        ("--algo", s.algo.is_some()),
        ("--approx", s.approx.is_some()),
        ("--horizon", s.horizon.is_some()),
        ("--runs", s.runs.is_some()),
        ("--seed", s.seed.is_some()),
        ("--eval-every", s.eval_every.is_some()),
        ("--sensor", s.sensor.is_some()),
        ("--observer", s.observer.is_some()),
        ("--delay-ms", s.delay_ms.is_some()),
        ("--delay-from", s.delay_from.is_some()),
        ("--delay-column", s.delay_column.is_some()),
        ("--observer-mode", s.observer_mode.is_some()),
        ("--config", s.config.is_some()),
    ]
    .into_iter()
    .filter_map(|(flag, given)| given.then_some(flag))
    .collect()
}

/// The configuration of a run to resume: `DIR/config.toml`, with `--trials` if given.
fn resume_selection(
    dir: &std::path::Path,
    s: &Selection,
) -> Result<agent::config::ExperimentConfig, String> {
    let flags = experiment_flags(s);
    if !flags.is_empty() {
        return Err(format!(
            "`--resume` continues the run with its own configuration ({}); {} cannot change it (only `--trials` can)",
            dir.join("config.toml").display(),
            flags.join(", ")
        ));
    }
    let path = dir.join("config.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!(
            "{}: cannot read ({e}); is {} a `rig run` directory?",
            path.display(),
            dir.display()
        )
    })?;
    let o = Overrides {
        trials: s.trials,
        ..Overrides::default()
    };
    resolve(Some((&path, &text)), &o).map_err(|e| e.to_string())
}

/// Which external driver, and how long to wait for it (`rig run`: with `--plant
/// external` only).
#[derive(Args)]
struct DriverArgs {
    /// The external driver's id: its services are rig/driver/ID/{info,sample,command}
    /// (`rig run`: needs `--plant external`) [default: the system's name, e.g. pendulum].
    #[arg(long, value_name = "ID")]
    driver: Option<String>,
    /// How long to wait for the driver to appear (its first info message) [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    driver_timeout: f64,
    /// How long the driver may take for one reset (to bring the system to rest at the
    /// start state and report READY) [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    reset_timeout: f64,
}

impl DriverArgs {
    fn resolve(&self, system: SystemName) -> Result<ExternalDriver, String> {
        let id = self
            .driver
            .clone()
            .unwrap_or_else(|| system.as_str().to_string());
        driver::contract::check_id(&id).map_err(|e| format!("`--driver`: {e}"))?;
        Ok(ExternalDriver {
            id,
            timeout: runtime::process::seconds("--driver-timeout", self.driver_timeout)
                .map_err(|e| e.to_string())?,
            reset_timeout: runtime::process::seconds("--reset-timeout", self.reset_timeout)
                .map_err(|e| e.to_string())?,
        })
    }
}

#[derive(Args)]
struct SimDriverArgs {
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

#[derive(Args)]
struct CheckDriverArgs {
    #[command(flatten)]
    driver: DriverArgs,
    /// The task the driver must fit: pendulum, arm-vertical, arm-horizontal,
    /// double-integrator.
    #[arg(long, value_parser = SystemName::parse, default_value = "pendulum")]
    system: SystemName,
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

/// Which experiment: the preset for (system, algorithm, approximator), a TOML file
/// overriding any of its keys, and flags overriding both.
#[derive(Args)]
struct Selection {
    /// System to learn on: pendulum (§3.6, §6.4.1), arm-vertical (Case I, §5.3),
    /// arm-horizontal (Case II, §5.4), arm-6.4 (the manipulator of §6.4.2: ±0.1 N m,
    /// ±1.2 rad operating range, four start states) or double-integrator (LQR check)
    /// [default: pendulum].
    #[arg(long, value_parser = SystemName::parse)]
    system: Option<SystemName>,
    /// Algorithm: sac (Algorithm 1), mlac (Algorithm 2), rmac (Algorithm 3), vgbp
    /// (Algorithm 7) or sarsa (§6.2) [default: mlac].
    #[arg(long, value_parser = Algo::parse)]
    algo: Option<Algo>,
    /// Function approximator: llr, rbf, tiles (sac only) or lstd (vgbp only: an LSTD
    /// critic on RBFs with an LLR process model); sarsa uses rbf [default: llr].
    #[arg(long, value_parser = ApproxKind::parse)]
    approx: Option<ApproxKind>,
    /// Horizon of the cost function. `infinite`: discounted rewards without end
    /// (Chapters 3, 5, 6). `finite`: a trial is the horizon — its return is the rewards
    /// plus a terminal reward τ_N = −xᵀQx of the final state, and actor and critic take
    /// time as an extra input (Chapter 4, Eq. 4.6; sac, mlac, rmac with rbf: SAC-FH,
    /// MLAC-FH, RMAC-FH, Algorithms 4–6, with the parameters of §4.4) [default:
    /// infinite].
    #[arg(long, value_parser = HorizonKind::parse)]
    horizon: Option<HorizonKind>,
    /// Trials per run [preset: 400 for the pendulum (vgbp, sarsa: 200; finite horizon:
    /// 600), 600 for the arms (vgbp, sarsa: 200)].
    #[arg(long)]
    trials: Option<u32>,
    /// Independent runs [preset: 30 for the pendulum (vgbp, sarsa, finite horizon: 20),
    /// 20 for the arm].
    #[arg(long)]
    runs: Option<u32>,
    /// Seed of every random stream of every run [preset: 1].
    #[arg(long)]
    seed: Option<u64>,
    /// A greedy evaluation trial (no exploration, no learning) after every N trials; 0
    /// disables [preset: 10; vgbp, sarsa: 5; vgbp on arm-6.4: 4]. With several start
    /// states (arm-6.4) the evaluation runs from each and reports the mean.
    #[arg(long)]
    eval_every: Option<u32>,
    /// What the plant's sensor measures: full (the state) or angle (an encoder: angles
    /// quantised to `observer.counts_per_rev`, default 4096, plus optional Gaussian noise
    /// `observer.noise_std`; velocities must be estimated) [default: full].
    #[arg(long, value_parser = SensorKind::parse)]
    sensor: Option<SensorKind>,
    /// State observer: pass-through (full sensor only), finite-difference (backward
    /// difference, low-pass `observer.filter`) or predictive (model prediction corrected by
    /// the measured angle; `observer.model` = learned (LLR) or known (RK4 of the plant),
    /// velocity gain `observer.gain`) [default: pass-through].
    #[arg(long, value_parser = ObserverKind::parse)]
    observer: Option<ObserverKind>,
    /// Sample-to-actuation delay [ms], in [0, Ts): over each sample period the previous
    /// action stays in effect this long, then the new one — deterministic, for delay
    /// studies (`run.delay_ms`; lockstep only) [default: 0].
    #[arg(long, value_name = "MS", conflicts_with = "delay_from")]
    delay_ms: Option<f64>,
    /// A recorded distribution of sample-to-actuation delays: a CSV file (header row, one
    /// delay per row) — e.g. `rig latency`'s latency.csv or a real driver's recording.
    /// Each sample's delay is drawn from it with the run seed (its own stream) and applied
    /// as `--delay-ms` is; every value must be in [0, Ts) (`run.delay_from`; lockstep
    /// only; exclusive with `--delay-ms`).
    #[arg(long, value_name = "FILE")]
    delay_from: Option<PathBuf>,
    /// The column of `--delay-from` holding the delays; the unit is the name's suffix
    /// (_s, _ms, _us, _ns; latency.csv's sample_to_actuation is ns) (`run.delay_column`)
    /// [default: delay_ms, else sample_to_actuation].
    #[arg(long, value_name = "NAME", requires = "delay_from")]
    delay_column: Option<String>,
    /// Timing: direct (the agent acts on x̂_k; its action takes effect within the interval,
    /// after the delay) or predictive (the agent acts on the observer's prediction
    /// x̂_{k+1|k}; its action is applied at the next sample instant, so a delay below Ts
    /// does not reach the plant; needs `--observer predictive`) (`observer.mode`)
    /// [default: direct].
    #[arg(long, value_parser = ObserverMode::parse)]
    observer_mode: Option<ObserverMode>,
    /// TOML file overriding preset values; see `rig config` for every key.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

#[derive(Args)]
struct LearnArgs {
    #[command(flatten)]
    selection: Selection,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/learn")]
    out: PathBuf,
    /// Worker threads [default: one per core].
    #[arg(long)]
    threads: Option<usize>,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
}

fn resolve_selection(s: &Selection) -> Result<agent::config::ExperimentConfig, String> {
    let text = match &s.config {
        Some(p) => Some(
            std::fs::read_to_string(p).map_err(|e| format!("{}: cannot read: {e}", p.display()))?,
        ),
        None => None,
    };
    let o = Overrides {
        system: s.system,
        algo: s.algo,
        approx: s.approx,
        horizon: s.horizon,
        trials: s.trials,
        runs: s.runs,
        seed: s.seed,
        eval_every: s.eval_every,
        sensor: s.sensor,
        observer: s.observer,
        delay_ms: s.delay_ms,
        // An absolute path, so that the processes of `rig run` and the recorded
        // configuration find the file wherever they run.
        delay_from: s
            .delay_from
            .as_ref()
            .map(|p| std::path::absolute(p).unwrap_or_else(|_| p.clone()))
            .map(|p| p.display().to_string()),
        delay_column: s.delay_column.clone(),
        observer_mode: s.observer_mode,
    };
    resolve(s.config.as_deref().zip(text.as_deref()), &o).map_err(|e| match &e.file {
        Some(_) => e.to_string(),
        None => format!("{e} (from the command line or the preset)"),
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let process = |f: fn(&ProcessArgs) -> anyhow::Result<()>, args: &ProcessArgs| match f(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    };
    match cli.command {
        Command::Pong { run_id, pin_cpus } => match bench::loop_bench::pong(&run_id, pin_cpus) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        },
        Command::DelayStudy(args) => {
            let opts = bench::delay_study::DelayStudyOptions {
                runs: args.runs,
                trials: args.trials,
                delays_ms: args.delays.clone(),
                model: args.observer_model,
                out: args.out.clone(),
                threads: args.threads,
                verbose: !args.quiet,
            };
            match bench::delay_study::delay_study(&opts) {
                Ok(_) => {
                    if !args.quiet {
                        println!(
                            "wrote {}/{{cells.csv, summary.txt, final_return.png, final_return.svg, curves-*.png, curves-*.svg, */}}",
                            args.out.display()
                        );
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Command::Latency(args) => {
            let opts = bench::latency::LatencyOptions {
                cycles: args.cycles,
                period_ms: args.period_ms,
                out: args.out.clone(),
                observer: args.observer,
                mode: args.observer_mode,
                raw_samples: args.raw_samples,
                scheduling: args.scheduling,
                verbose: true,
            };
            let done = if args.sweep {
                bench::latency::sweep(&opts, 1.5).map(|points| {
                    match points.iter().rev().find(|p| p.report.misses == 0) {
                        Some(p) => println!(
                            "fastest period without a deadline miss in {} cycles: {} ms",
                            p.report.cycles, p.period_ms
                        ),
                        None => println!("every period measured missed a deadline"),
                    }
                    println!("wrote {0}/sweep.csv and {0}/period-*/", args.out.display());
                })
            } else {
                bench::latency::latency(&opts)
                    .map(|_| println!("wrote {}", bench::latency::describe(&args.out)))
            };
            match done {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Command::BenchLoop(args) => match bench::loop_bench::bench_loop(&args.out, args.samples) {
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
        },
        Command::CheckDriver(args) => check_driver(&args),
        Command::Optimal(args) => optimal(&args),
        Command::SimDriver(args) => sim_driver(&args),
        Command::Plant(args) => process(runtime::process::plant::run, &args),
        Command::Observer(args) => process(runtime::process::observer::run, &args),
        Command::Agent(args) => process(runtime::process::agent::run, &args),
        Command::Run(args) => {
            let selected = match &args.resume {
                Some(dir) => resume_selection(dir, &args.selection),
                None => resolve_selection(&args.selection),
            };
            let mut cfg = match selected {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            cfg.run.runs = 1;
            if !(args.speed.is_finite() && args.speed > 0.0 && args.speed <= 1000.0) {
                eprintln!(
                    "error: `--speed` {} is out of range: must be a number in (0, 1000]",
                    args.speed
                );
                return ExitCode::from(2);
            }
            let realtime = (args.timing == "realtime").then_some(args.speed);
            let delayed = cfg.run.delay_ms != 0.0 || !cfg.run.delay_from.is_empty();
            if delayed && (realtime.is_some() || args.plant == "external") {
                eprintln!(
                    "error: `--delay-ms`/`--delay-from` (run.delay_ms, run.delay_from) apply in lockstep with the simulated plant only: in real time the delays are real"
                );
                return ExitCode::from(2);
            }
            let driver = if args.plant == "external" {
                if realtime.is_some() || args.speed != 1.0 {
                    eprintln!(
                        "error: `--timing`/`--speed` do not apply with `--plant external`: the driver is the clock"
                    );
                    return ExitCode::from(2);
                }
                match args.driver.resolve(cfg.system) {
                    Ok(d) => Some(d),
                    Err(e) => {
                        eprintln!("error: {e}");
                        return ExitCode::from(2);
                    }
                }
            } else {
                if args.driver.driver.is_some() {
                    eprintln!("error: `--driver` needs `--plant external`");
                    return ExitCode::from(2);
                }
                None
            };
            let opts = RunOptions {
                out: args.resume.clone().unwrap_or_else(|| args.out.clone()),
                resume: args.resume.is_some(),
                run_id: args.run_id.clone(),
                progress: !args.quiet,
                realtime,
                driver,
                cycles_out: None,
                scheduling: args.scheduling,
            };
            match run(&cfg, &opts) {
                Ok(s) => {
                    if !args.quiet {
                        let steps = s.messages as f64 / 3.0;
                        println!(
                            "{} {}/{} over three processes: {} trials in {:.1} s wall ({:.1} µs per sample)",
                            cfg.system,
                            cfg.algo,
                            cfg.approx,
                            s.records.len(),
                            s.wall.as_secs_f64(),
                            s.wall.as_secs_f64() * 1e6 / steps
                        );
                        if let (Some(i), Some(d)) = (&s.driver, &opts.driver) {
                            println!(
                                "  driver {:?} ({}): period {:.3} ms × time scale {}; deadline misses: {} of {} samples",
                                d.id,
                                i.system_name(),
                                i.period_ns as f64 * 1e-6,
                                i.time_scale,
                                s.deadline_misses,
                                s.messages / 3
                            );
                        } else if realtime.is_some() {
                            println!(
                                "  deadline misses: {} of {} samples",
                                s.deadline_misses,
                                s.messages / 3
                            );
                        }
                        if let Some(g) = s.records.iter().rev().find_map(|r| r.greedy) {
                            println!("  last greedy return: {g:.1}");
                        }
                        println!(
                            "  wrote {}/{{returns.csv, run.mcap, config.toml, plant.log, observer.log, agent.log}}",
                            args.out.display()
                        );
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Command::Config(sel) => match resolve_selection(&sel) {
            Ok(cfg) => {
                print!("{}", cfg.to_toml());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Command::Reproduce(args) => {
            if args.runs == Some(0) || args.trials == Some(0) {
                eprintln!("error: `--runs` and `--trials` must be at least 1");
                return ExitCode::from(2);
            }
            let opts = bench::reproduce::ReproduceOptions {
                out: args.out.clone(),
                only: args.only.clone(),
                runs: args.runs,
                trials: args.trials,
                progress: !args.quiet,
            };
            match bench::reproduce::reproduce(&opts) {
                Ok(figs) => {
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
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Command::Learn(args) => {
            let cfg = match resolve_selection(&args.selection) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            let opts = LearnOptions {
                out: args.out.clone(),
                threads: args.threads,
                progress: if args.quiet {
                    runtime::learn::Progress::Hidden
                } else {
                    runtime::learn::Progress::Bar
                },
            };
            match learn(&cfg, &opts) {
                Ok(s) => {
                    if !args.quiet {
                        print_summary(&cfg, &s, &args.out);
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}

fn optimal(args: &OptimalArgs) -> ExitCode {
    use bench::optimal::{OptimumOptions, pendulum_optimum, write_trajectory};
    let opts = OptimumOptions {
        grid: args.grid,
        actions: args.actions,
    };
    if let Err(e) = opts.validate() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let o = match pendulum_optimum(&opts) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let csv = args.out.join("optimal.csv");
    let written = std::fs::create_dir_all(&args.out)
        .map_err(anyhow::Error::from)
        .and_then(|()| write_trajectory(&csv, &o.trajectory));
    if let Err(e) = written {
        eprintln!("error: {}: {e:#}", csv.display());
        return ExitCode::FAILURE;
    }
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
    ExitCode::SUCCESS
}

fn sim_driver(args: &SimDriverArgs) -> ExitCode {
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

fn check_driver(args: &CheckDriverArgs) -> ExitCode {
    let fraction = |flag: &str, v: f64| {
        if v.is_finite() && (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            Err(format!(
                "`{flag}` {v} is out of range: must be a fraction in [0, 1]"
            ))
        }
    };
    let opts = (|| -> Result<CheckOptions, String> {
        let d = args.driver.resolve(args.system)?;
        let rate_seconds = runtime::process::seconds("--rate-seconds", args.rate_seconds)
            .map_err(|e| e.to_string())?
            .as_secs_f64();
        Ok(CheckOptions {
            driver: d.id,
            system: args.system,
            timeout: d.timeout,
            reset_timeout: d.reset_timeout,
            rate_seconds,
            max_jitter: fraction("--max-jitter", args.max_jitter)?,
            max_missed: fraction("--max-missed", args.max_missed)?,
            step: fraction("--step", args.step)?,
        })
    })();
    let opts = match opts {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    println!(
        "rig check-driver: driver {:?} (rig/driver/{}/...) against the {} task",
        opts.driver, opts.driver, opts.system
    );
    match check(&opts, &mut |o| println!("{o}")) {
        Ok(outcomes) => {
            let failed = outcomes.iter().filter(|o| !o.pass).count();
            if failed == 0 {
                println!("check-driver: PASS ({} checks)", outcomes.len());
                ExitCode::SUCCESS
            } else {
                println!(
                    "check-driver: FAIL ({failed} of {} checks failed)",
                    outcomes.len()
                );
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn print_summary(
    cfg: &agent::config::ExperimentConfig,
    s: &runtime::learn::LearnSummary,
    out: &std::path::Path,
) {
    let steps = s.records.len() as f64 * Task::new(cfg.system).steps_per_trial() as f64;
    println!(
        "{} {}/{}: {} runs × {} trials in {:.1} s wall ({:.2} µs per learning step, all threads)",
        cfg.system,
        cfg.algo,
        cfg.approx,
        cfg.run.runs,
        cfg.run.trials,
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
