//! `rig latency`: the latency budget of the three-process loop in real time.
//!
//! In one invocation:
//! * **Raw baseline**: a raw iceoryx2 ping-pong (publish + event, blocking receive)
//!   between this process and a `rig pong` child ([`crate::loop_bench`]); one one-way
//!   hop is half a round trip.
//! * **The rig**: `rig run` in realtime timing with angle-only sensing and the chosen
//!   observer, for at least `cycles` samples at period `period_ms` (the simulated system
//!   runs `Ts / period` times faster than real time), recorded to `DIR/run/run.mcap` as
//!   every run is. Every message carries its stamps (`t_sample_ns`, `t_received_ns`,
//!   `t_publish_ns`, the `/timing/...` channels of the recording); the plant adds, per
//!   sample, when it woke for the sampling instant and when it found the answering action
//!   (the plant node's `cycles_out`).
//!
//! Stages of a cycle (sample `k`, all on `CLOCK_MONOTONIC`):
//!
//! ```text
//! jitter              woke − t_k                 (the plant's wake-up after the instant)
//! plant               measurement published − t_k (sensor, ground truth, publish)
//! plant→observer      observer received − measurement published
//! observer            observer published − observer received
//! observer→agent      agent received − observer published
//! agent               agent published − agent received
//! agent→plant         plant found the action − agent published (the plant waits on the
//!                     action topic's event and wakes on arrival, so this hop includes a
//!                     wake-up, as the raw hop does)
//! sample→actuation    plant found the action − t_k (direct timing: the action is applied
//!                     from then on; predictive timing: it is applied at t_{k+1}, so this
//!                     is the budget used of the one-sample pipeline)
//! slack               t_k + period − plant found the action
//! ```
//!
//! **Against an external driver** (`rig latency --driver ID`, [`DRIVER_STAGES`]) the
//! driver is the clock and the plant process is its episode master: a cycle runs from
//! driver sample `k` to the command answering it. Across hosts the rig's bridge records
//! the link's share per sample (`/driver/link`): the round trip through both bridges
//! (`link_round_trip`, each host's share on its own clock), the rig's turnaround from
//! the sample's arrival to the command, and — only where both hosts read one clock —
//! the one-way hops and `t_k` to the command.
//!
//! A cycle whose action did not arrive within the period is a deadline miss (its later
//! stages are left empty in `latency.csv`). The summary also reports what the machine
//! did meanwhile ([`MachineLoad`]: load average, the hypervisor's steal time, interrupts
//! on the plant's CPU), to tell the rig's outliers from the machine's. Outputs: `DIR/latency.csv` (one row per
//! cycle: the timestamps, then every stage in ns), `DIR/summary.txt` (what is printed),
//! `DIR/latency.png` / `.svg` (histograms of the stages).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use observer::config::{ObserverKind, ObserverMode, SensorKind};
use runtime::error::AtFile;

use crate::loop_bench::{Stats, raw_round_trips};

pub use error::LatencyError;

mod cycles;
mod error;
mod external;
mod machine;
mod sweep;

pub use external::{DRIVER_STAGES, DRIVER_STAMPS, Reach};
use machine::Counters;
pub use machine::MachineLoad;
use runtime::clock::Clock;
use runtime::config::Overrides;
use runtime::output::write_atomic;
use runtime::process::{CpuLayout, CpuSet, Scheduling, Spin, Wakeup};
use runtime::report::plot::{Histogram, plot_histograms};
use runtime::run::{NodeCommand, RunOptions, run};
pub use sweep::{SweepPoint, sweep};

/// What `rig latency` runs.
#[derive(Clone, Debug)]
pub struct LatencyOptions {
    /// Samples (cycles) to time, at least; whole trials are run.
    pub cycles: usize,
    /// The clock: the simulated plant in real time at its period (checked by
    /// [`period`]), or an external driver at its own, with its stamps and, across hosts,
    /// the link's ([`DRIVER_STAGES`]).
    pub clock: Clock,
    /// How the run's processes are started (`rig`'s subcommands).
    pub nodes: NodeCommand,
    /// A task file in place of the pendulum (the driver's task).
    pub task: Option<PathBuf>,
    /// Output directory.
    pub out: PathBuf,
    /// The observer (the sensor is the angle encoder).
    pub observer: ObserverKind,
    /// The timing: direct (an action is applied when it arrives) or predictive (at the
    /// next sample instant; `observer` must be predictive; simulated plant only).
    pub mode: ObserverMode,
    /// Raw ping-pong round trips for the baseline.
    pub raw_samples: usize,
    /// How the three processes (and the raw ping-pong's two, with the echo on the
    /// plant's CPU when pinned) are scheduled.
    pub scheduling: Scheduling,
    /// How the plant waits for a sampling instant.
    pub spin: Spin,
    /// How the processes wait for their next message.
    pub waiting: wire::Waiting,
    /// The CPU wake-up latency limit held while measuring (`--cpu-wakeup-us`).
    pub wakeup: Wakeup,
    /// Print the summary.
    pub verbose: bool,
}

/// Stage names, in cycle order, as `latency.csv` columns (ns) and summary rows.
pub const STAGES: [&str; 9] = [
    "jitter",
    "plant",
    "plant_to_observer",
    "observer",
    "observer_to_agent",
    "agent",
    "agent_to_plant",
    "sample_to_actuation",
    "slack",
];

/// Timestamp columns of `latency.csv` (monotonic ns; 0: not recorded).
pub const STAMPS: [&str; 9] = [
    "t_sample_ns",
    "t_woke_ns",
    "t_measurement_publish_ns",
    "t_observer_received_ns",
    "t_observer_publish_ns",
    "t_agent_received_ns",
    "t_agent_publish_ns",
    "t_action_found_ns",
    "deadline_ns",
];

/// Stages that are not one local hop: no ratio to the raw hop.
const SPANS_HOSTS: [&str; 4] = [
    "driver_to_rig",
    "rig_to_driver",
    "sample_to_command",
    "sample_to_actuation",
];

/// What `rig latency` measured.
#[derive(Clone, Debug)]
pub struct LatencyReport {
    /// Sampling period \[ns\].
    pub period_ns: u64,
    /// Cycles timed.
    pub cycles: usize,
    /// Cycles whose action did not arrive within the period.
    pub misses: usize,
    /// How the processes were scheduled.
    pub scheduling: Scheduling,
    /// How the plant waited for a sampling instant.
    pub spin: Spin,
    /// The CPU wake-up latency limit held \[µs\], if one was.
    pub wakeup_us: Option<u32>,
    /// The external driver's id and how its samples reached the rig; `None`: the
    /// simulated plant.
    pub driver: Option<(String, Reach)>,
    /// Raw round trips \[µs\].
    pub raw_rtt: Stats,
    /// Per stage ([`STAGES`]), over the cycles that met their deadline \[µs\].
    pub stages: Vec<(&'static str, Stats)>,
    /// What the machine did meanwhile (Linux `/proc`; `None` elsewhere).
    pub machine: Option<MachineLoad>,
}

impl LatencyReport {
    /// The raw one-way hop's median \[µs\] (half the round trip).
    pub fn raw_hop_p50(&self) -> f64 {
        self.raw_rtt.p50 / 2.0
    }

    /// A stage's statistics.
    pub fn stage(&self, name: &str) -> Option<&Stats> {
        self.stages.iter().find(|(n, _)| *n == name).map(|(_, s)| s)
    }

    /// The one-screen summary.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let scheduling = self
            .scheduling
            .rt_priority
            .map_or("ordinary scheduling".to_string(), |p| {
                format!("SCHED_FIFO {p}")
            });
        let mut pinned = if self.scheduling.layout() == Some(CpuLayout::PlantAlone) {
            ", plant pinned to its own CPU".to_string()
        } else {
            String::new()
        };
        if let Some(us) = self.wakeup_us {
            let _ = write!(pinned, ", CPU wake-up limit {us} µs");
        }
        let period = self.period_ns as f64 * 1e-6;
        let _ = match &self.driver {
            None => writeln!(
                s,
                "rig latency: {} cycles at {period:.3} ms, angle sensor, plant spins {} µs, {scheduling}{pinned}; deadline misses: {}",
                self.cycles, self.spin.spin_us, self.misses
            ),
            Some((id, reach)) => writeln!(
                s,
                "rig latency: {} cycles against driver {id:?} at its period {period:.3} ms, angle sensor, {scheduling}{pinned}; actions not applied by the next sample: {}\n{}",
                self.cycles,
                self.misses,
                external::describe(*reach)
            ),
        };
        let _ = writeln!(
            s,
            "raw iceoryx2 ping-pong ({} round trips): RTT p50 {:.1} µs, p99 {:.1} µs → one-way hop p50 {:.1} µs",
            self.raw_rtt.n,
            self.raw_rtt.p50,
            self.raw_rtt.p99,
            self.raw_hop_p50()
        );
        if let Some(m) = &self.machine {
            let cpu = m
                .plant_cpu
                .map_or("all CPUs".to_string(), |c| format!("the plant's CPU {c}"));
            let _ = writeln!(
                s,
                "machine during the run: load average {:.2} at the start, guest steal {:.0} ms, {} interrupts on {cpu} ({:.1} per cycle)",
                m.load_avg,
                m.steal_ms,
                m.interrupts,
                m.interrupts as f64 / self.cycles.max(1) as f64
            );
        }
        let _ = writeln!(
            s,
            "{:<20} {:>9} {:>9} {:>9} {:>9} {:>9}  {:>10}",
            "stage [µs]", "p50", "p90", "p99", "p99.9", "max", "p50 / hop"
        );
        for (name, st) in &self.stages {
            let ratio = if name.contains("_to_") && !SPANS_HOSTS.contains(name) {
                format!("{:.2}", st.p50 / self.raw_hop_p50())
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "{:<20} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1}  {:>10}",
                name, st.p50, st.p90, st.p99, st.p999, st.max, ratio
            );
        }
        s
    }
}

/// Runs the baseline and the rig, writes the outputs and returns what was measured.
pub fn latency(opts: &LatencyOptions) -> Result<LatencyReport, LatencyError> {
    validate(opts)?;
    std::fs::create_dir_all(&opts.out).at("cannot create", &opts.out)?;
    let exe = std::env::current_exe().map_err(LatencyError::Executable)?;
    // The baseline under the same policy: the ping-pong's partner process inherits it.
    runtime::process::set_rt_priority(opts.scheduling.rt_priority)?;
    let _wakeup = opts.wakeup.hold()?;
    let plant_alone = opts.scheduling.layout() == Some(CpuLayout::PlantAlone);
    if plant_alone {
        runtime::process::cpus::pin(CpuSet::Others)?;
    }
    let mut raw = raw_round_trips(
        &exe,
        &opts.out,
        opts.raw_samples,
        plant_alone,
        wire::Waiting::Block,
    )?;
    let raw_rtt = Stats::of(&mut raw);
    // This process records the run: under SCHED_FIFO at the loop's priority, each chunk's
    // compression (about once a second at 1 kHz) would hold the observer and the agent
    // on its CPU until done. As batch work it yields to them at once.
    runtime::process::batch_thread();

    let run_dir = opts.out.join("run");
    let cycles_path = run_dir.join("plant_cycles.csv");
    let (period_ns, machine) = run_realtime(opts, &run_dir, &cycles_path)?;
    let (mut c, reach) = if opts.clock.is_external() {
        let (c, reach) = external::read(&cycles::messages(&run_dir)?, period_ns)?;
        (c, Some(reach))
    } else {
        (cycles::read(&run_dir, &cycles_path, period_ns)?, None)
    };
    write_atomic(&opts.out.join("latency.csv"), &c.csv)?;
    let stages: Vec<(&'static str, Stats)> = c
        .names
        .iter()
        .zip(&mut c.stage_ns)
        .filter(|(_, v)| !v.is_empty())
        .map(|(name, v)| (*name, Stats::of(v)))
        .collect();
    let report = LatencyReport {
        period_ns,
        cycles: c.cycles,
        misses: c.misses,
        scheduling: opts.scheduling,
        spin: opts.spin,
        wakeup_us: opts.wakeup.cpu_wakeup_us,
        driver: opts
            .clock
            .driver()
            .zip(reach)
            .map(|(d, r)| (d.id.clone(), r)),
        raw_rtt,
        stages,
        machine,
    };
    let summary = report.summary();
    write_atomic(&opts.out.join("summary.txt"), &summary)?;
    if opts.verbose {
        print!("{summary}");
    }
    plot_stages(&opts.out, &report, c.names, &c.stage_ns)?;
    Ok(report)
}

/// The simulated plant's period of `--period-ms`, refused out of [0.1, 1000] ms in one
/// line.
pub fn period(period_ms: f64) -> Result<Duration, LatencyError> {
    if !(period_ms.is_finite() && (0.1..=1000.0).contains(&period_ms)) {
        return Err(LatencyError::Period(period_ms));
    }
    Ok(Duration::from_secs_f64(period_ms * 1e-3))
}

/// Refuses options out of range, in one line naming the flag.
fn validate(opts: &LatencyOptions) -> Result<(), LatencyError> {
    match &opts.clock {
        Clock::Lockstep => {
            return Err(LatencyError::Lockstep);
        }
        Clock::Realtime { period: p } => {
            period(p.as_nanos() as f64 * 1e-6)?;
        }
        Clock::External(_) if opts.mode == ObserverMode::Predictive => {
            return Err(LatencyError::PredictiveDriver);
        }
        Clock::External(_) => {}
    }
    if opts.cycles == 0 {
        return Err(LatencyError::NoCyclesAsked);
    }
    if let Some(layout) = opts.scheduling.layout() {
        layout.check()?;
    }
    if opts.mode == ObserverMode::Predictive && opts.observer != ObserverKind::Predictive {
        return Err(LatencyError::PredictiveObserver(opts.observer));
    }
    Ok(())
}

/// `rig run` in real time for at least the cycles of `opts` into `run_dir`: the
/// simulated plant at the period of `opts`, its cycles into `cycles_path`, or the
/// external driver at its own. Returns the period \[ns\] and what the machine did
/// meanwhile.
fn run_realtime(
    opts: &LatencyOptions,
    run_dir: &Path,
    cycles_path: &Path,
) -> Result<(u64, Option<MachineLoad>), LatencyError> {
    let mode = opts.mode;
    let mut cfg = runtime::config::resolve(
        None,
        &Overrides {
            task: opts.task.clone(),
            sensor: Some(SensorKind::Angle),
            observer: Some(opts.observer),
            observer_mode: Some(mode),
            eval_every: Some(0),
            ..Default::default()
        },
    )?;
    let task = cfg.task();
    let per_trial = task.steps_per_trial() + 1;
    cfg.change_run(|r| r.trials = opts.cycles.div_ceil(per_trial) as u32)?;
    let period = opts.clock.period();
    let before = Counters::read();
    let summary = run(
        &cfg,
        &RunOptions {
            out: run_dir.to_owned(),
            run_id: None,
            progress: false,
            clock: opts.clock.clone(),
            checked: opts
                .clock
                .check(&cfg, opts.waiting)
                .map_err(runtime::run::RunError::from)?,
            nodes: opts.nodes.clone(),
            resume: false,
            cycles_out: opts.clock.is_realtime().then(|| cycles_path.to_owned()),
            scheduling: opts.scheduling,
            spin: opts.spin,
            waiting: opts.waiting,
            lockstep_waiting: None,
            // The loop's timing is measured, gaps and all.
            learn_across_gaps: true,
            scene: None,
        },
    )?;
    let machine = before.zip(Counters::read()).map(|(b, a)| {
        b.until(
            &a,
            (opts.scheduling.layout() == Some(CpuLayout::PlantAlone))
                .then(runtime::process::cpus::last_cpu),
        )
    });
    let period_ns = match (summary.driver, period) {
        (Some(info), _) => info.period_ns,
        (None, period) => period.map_or(0, |p| p.as_nanos() as u64),
    };
    Ok((period_ns, machine))
}

/// Histograms of the hops and compute stages, up to the largest p99.9 among them, as
/// `DIR/latency.png` and `.svg`.
fn plot_stages(
    out: &Path,
    report: &LatencyReport,
    names: &[&'static str],
    stage_ns: &[Vec<u64>],
) -> Result<(), LatencyError> {
    let shown: Vec<&str> = names
        .iter()
        .copied()
        .filter(|s| !matches!(*s, "plant" | "slack" | "sample_to_command"))
        .collect();
    let values: Vec<(&str, Vec<f64>)> = shown
        .iter()
        .filter_map(|name| {
            let i = names.iter().position(|s| s == name)?;
            Some((
                *name,
                stage_ns[i].iter().map(|&ns| ns as f64 / 1e3).collect(),
            ))
        })
        .collect();
    let x_max = shown
        .iter()
        .filter_map(|n| report.stage(n).map(|s| s.p999))
        .fold(1.0, f64::max)
        * 1.1;
    let series: Vec<Histogram> = values
        .iter()
        .map(|(label, v)| Histogram { label, values: v })
        .collect();
    plot_histograms(
        &out.join("latency.png"),
        &out.join("latency.svg"),
        &format!(
            "Loop stages, {} cycles at {:.3} ms",
            report.cycles,
            report.period_ns as f64 * 1e-6
        ),
        "Duration [µs] (values beyond the axis in the last bin)",
        &series,
        x_max,
        120,
    )?;
    Ok(())
}

/// `DIR` relative to a base, for messages.
pub fn describe(out: &Path) -> String {
    format!(
        "{}/{{latency.csv, summary.txt, latency.png, latency.svg, run/}}",
        out.display()
    )
}
