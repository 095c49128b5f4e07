//! The command lines of the nodes: what every node takes ([`NodeArgs`]: run id,
//! configuration, operating-system scheduling) and what each adds ([`PlantArgs`], [`ObserverArgs`],
//! [`AgentArgs`]).

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use wire::{Bus, FOREVER, Waiting};

use super::{Layout, Part};
use crate::config::{ExperimentConfig, Overrides, resolve};

/// The realtime plant's default spin before each sampling instant \[µs\] (`--spin-us`).
pub const SPIN_US: u64 = 100;

/// How a node is scheduled by the operating system: flags of `rig run`, `rig latency`
/// and of each node (which `rig run` passes on, [`Scheduling::process_args`]).
#[derive(Args, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scheduling {
    /// Run the processes under the real-time scheduling policy SCHED_FIFO at this
    /// priority (1–99; the plant, the clock, one above the observer and the agent), ahead
    /// of all ordinary work on the machine, their memory locked (mlockall); needs root,
    /// CAP_SYS_NICE and CAP_IPC_LOCK, or rtprio and memlock limits.
    #[arg(long, value_name = "PRIORITY", value_parser = clap::value_parser!(u8).range(1..=99))]
    pub rt_priority: Option<u8>,
    /// Pin the plant (the clock) alone on the last CPU and the observer, the agent and
    /// the recorder on the others, so that the rig's own work does not disturb the
    /// sampling instants (the same as `--cpus plant-alone`).
    #[arg(long, conflicts_with = "cpus")]
    pub pin_cpus: bool,
    /// Where the processes run (sched_setaffinity; the layouts that set a CPU apart need
    /// at least two): `shared` wherever the operating system puts them; `plant-alone` the
    /// plant alone on the last CPU, for real time; `recorder-alone` the recorder and the
    /// checkpoint writer alone on the last CPU and the loop on the others [rig run's
    /// default: recorder-alone in lockstep when the processes poll without end on a
    /// machine of 2 or 3 CPUs, otherwise shared; a node's: shared].
    #[arg(long, value_enum, value_name = "LAYOUT")]
    pub cpus: Option<Layout>,
}

impl Scheduling {
    /// The layout asked for (`--cpus`, `--pin-cpus`), if any.
    pub fn layout(&self) -> Option<Layout> {
        if self.pin_cpus {
            Some(Layout::PlantAlone)
        } else {
            self.cpus
        }
    }

    /// Places the calling process's `part` as [`Scheduling::layout`] says.
    pub fn place(&self, part: Part) -> Result<()> {
        self.layout().unwrap_or(Layout::Shared).place(part)
    }

    /// The flags that give a node this scheduling.
    pub fn process_args(&self) -> Vec<String> {
        let mut args = Vec::new();
        if let Some(l) = self.layout() {
            args.extend(["--cpus".to_string(), l.name().to_string()]);
        }
        if let Some(p) = self.rt_priority {
            args.extend(["--rt-priority".to_string(), p.to_string()]);
        }
        args
    }
}

/// How the realtime plant waits for a sampling instant: a flag of `rig run`,
/// `rig latency` and the plant node.
#[derive(Args, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Spin {
    /// Realtime: the plant spins (a busy core) instead of sleeping for the last this many
    /// µs before each sampling instant, so that the instant does not depend on the
    /// operating system's wake-up latency; larger values trade CPU for less jitter.
    #[arg(long, value_name = "US", default_value_t = SPIN_US)]
    pub spin_us: u64,
}

impl Default for Spin {
    fn default() -> Self {
        Self { spin_us: SPIN_US }
    }
}

/// How the loop's processes wait for their next message (`--wait`, [`Waiting`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum WaitKind {
    /// Sleep until woken: no CPU while waiting, an operating-system wake-up per message.
    Block,
    /// Poll with the CPU's spin hint: for a machine with a core per process.
    Spin,
    /// Poll, handing the CPU to the other processes between polls.
    Yield,
}

/// How a process waits for its next message: a flag of `rig run` and of each node.
#[derive(Args, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Wait {
    /// How each process waits for its next message: `block` sleeps until woken (no CPU
    /// while waiting, an operating-system wake-up per message); `spin` polls with the
    /// CPU's spin hint (for a core per process); `yield` polls and hands the CPU to the
    /// other processes between polls. Polling lasts `--wait-us`, then blocks [rig run's
    /// default: yield in lockstep, with the simulated plant or a driver that keeps the
    /// lockstep clock; block in real time; a node's: block].
    #[arg(long, value_enum, value_name = "HOW")]
    pub wait: Option<WaitKind>,
    /// With `--wait spin` or `yield`: how long to poll before blocking [µs; default:
    /// poll without end, and senders do not wake their receivers].
    #[arg(long, value_name = "US")]
    pub wait_us: Option<u64>,
}

impl Wait {
    /// The waiting asked for, `default` if none was.
    pub fn waiting(&self, default: WaitKind) -> Waiting {
        let bound = self.wait_us.map_or(FOREVER, Duration::from_micros);
        match self.wait.unwrap_or(default) {
            WaitKind::Block => Waiting::Block,
            WaitKind::Spin => Waiting::Spin(bound),
            WaitKind::Yield => Waiting::Yield(bound),
        }
    }

    /// The flags that give a node `waiting`.
    pub fn process_args(waiting: Waiting) -> Vec<String> {
        let (how, bound) = match waiting {
            Waiting::Block => ("block", None),
            Waiting::Spin(d) => ("spin", Some(d)),
            Waiting::Yield(d) => ("yield", Some(d)),
        };
        let mut args = vec!["--wait".to_string(), how.to_string()];
        if let Some(d) = bound.filter(|&d| d != FOREVER) {
            args.extend(["--wait-us".to_string(), d.as_micros().to_string()]);
        }
        args
    }
}

/// Command-line arguments every node takes.
#[derive(Args, Debug, Clone)]
pub struct NodeArgs {
    /// Run id: the processes of one run share it; runs with different ids never see
    /// each other (letters, digits, '-', '_').
    #[arg(long)]
    pub run_id: String,
    /// The run's configuration (a `config.toml` written by `rig run`/`rig learn`, or any
    /// file `rig config` describes).
    #[arg(long, value_name = "FILE")]
    pub config: PathBuf,
    /// Receivers to wait for before publishing: the next process, plus the recorder of
    /// `rig run` if one is listening.
    #[arg(long, default_value_t = 1)]
    pub receivers: usize,
    /// Which run of the experiment this is (seeds the random streams as run `N` of
    /// `rig learn` would be).
    #[arg(long, default_value_t = 0)]
    pub run_index: u32,
    /// How the realtime loop is scheduled.
    #[command(flatten)]
    pub scheduling: Scheduling,
    /// How the process waits for its next message.
    #[command(flatten)]
    pub wait: Wait,
}

impl NodeArgs {
    /// Joins the run as process `role`, waiting as `--wait` says.
    pub fn join(&self, role: &str) -> Result<Bus> {
        Ok(Bus::join(&self.run_id, role)?.with_waiting(self.wait.waiting(WaitKind::Block)))
    }

    /// Reads and validates the configuration.
    pub fn config(&self) -> Result<ExperimentConfig> {
        let text = std::fs::read_to_string(&self.config)
            .with_context(|| format!("{}: cannot read", self.config.display()))?;
        resolve(Some((&self.config, &text)), &Overrides::default())
            .map_err(|e| anyhow::anyhow!("{e}"))
    }
}

/// Command-line arguments of the plant node ([`super::plant::run`]).
#[derive(Args, Debug, Clone)]
pub struct PlantArgs {
    /// What every node takes.
    #[command(flatten)]
    pub node: NodeArgs,
    /// `lockstep` (simulated time advances when the action has arrived) or `realtime`
    /// (the plant samples at absolute deadlines of Ts / speed; a late action is applied
    /// from the moment it arrives, the previous one held until then).
    #[arg(long, default_value = "lockstep", value_parser = ["lockstep", "realtime"])]
    pub timing: String,
    /// Realtime: how many times faster than real time (Ts / speed per sample).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Realtime: how the plant waits for a sampling instant.
    #[command(flatten)]
    pub spin: Spin,
    /// Write the time from publishing each measurement to receiving its action (ns, one
    /// per line) to this file.
    #[arg(long, value_name = "FILE")]
    pub latency_out: Option<PathBuf>,
    /// Do not simulate; be the episode master for the external driver with this id
    /// (services rig/driver/ID/..., docs/driver.md), which is the clock. `--timing` and
    /// `--speed` do not apply then.
    #[arg(long, value_name = "ID")]
    pub driver: Option<String>,
    /// With `--driver`: how long to wait for the driver to appear, and for each sample
    /// of a driver in lockstep (a simulator's step may take long) (seconds).
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    pub driver_timeout: f64,
    /// With `--driver`: how long the driver may take for one reset (bring the system to
    /// rest at the start state), in seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    pub reset_timeout: f64,
    /// Realtime: write every sample's timing to this CSV file (columns
    /// `seq,t_sample_ns,t_woke_ns,t_action_ns`: sequence number, nominal sampling
    /// instant, wake-up, arrival of the answering action; monotonic ns) — for
    /// `rig latency`.
    #[arg(long, value_name = "FILE")]
    pub cycles_out: Option<PathBuf>,
    /// Continue a run after this trial (its greedy evaluations done).
    #[arg(long, value_name = "TRIAL", default_value_t = 0)]
    pub after_trial: u32,
    /// With `--after-trial`: the simulated learning time at that trial's end (seconds).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
    pub sim_time: f64,
    /// With `--after-trial`: the sequence number of the first sample.
    #[arg(long, value_name = "SEQ", default_value_t = 0)]
    pub first_seq: u64,
    /// Realtime and `--driver`: what a gap in the loop's timing does — samples missing,
    /// or one a period late (docs/run.md). `cut`: the attempt ends there, unlearned, and
    /// the trial is run again. `learn`: the trial goes on and learns across it, the gap
    /// counted only as deadline misses (a simulation run faster than this machine can
    /// keep up with).
    #[arg(long, default_value = "cut", value_parser = ["cut", "learn"])]
    pub gaps: String,
}

/// Command-line arguments of the observer node ([`super::observer::run`]).
#[derive(Args, Debug, Clone)]
pub struct ObserverArgs {
    /// What every node takes.
    #[command(flatten)]
    pub node: NodeArgs,
}

/// Command-line arguments of the agent node ([`super::agent::run`]).
#[derive(Args, Debug, Clone)]
pub struct AgentArgs {
    /// What every node takes.
    #[command(flatten)]
    pub node: NodeArgs,
    /// Answer every estimate with a zero action, without learning (for loop benchmarks).
    #[arg(long)]
    pub trivial: bool,
    /// Write a checkpoint of the learned state at the end of every learning trial into
    /// this directory (`trial-NNNNNN.ckpt`, atomically).
    #[arg(long, value_name = "DIR")]
    pub checkpoints: Option<PathBuf>,
    /// With `--checkpoints`: keep only the N newest checkpoints (0: keep all; `rig run`
    /// passes 0 and removes those a resume can no longer need itself).
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub keep_checkpoints: usize,
    /// Start from this checkpoint's learned state (the run's trials continue after the
    /// checkpoint's trial; the plant is started with `--after-trial`).
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
}
