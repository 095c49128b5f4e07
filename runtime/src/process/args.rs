//! How the processes of a run are scheduled and wait: flags of `rig run` and `rig
//! latency`, and settings of each node ([`super::node`]).

use std::time::Duration;

use super::SystemError;
use serde::{Deserialize, Serialize};
use wire::{FOREVER, Waiting};

use super::node::Invalid;
use super::{CpuLayout, Part};

/// The realtime plant's default spin before each sampling instant \[µs\] (`--spin-us`).
pub const SPIN_US: u64 = 100;

/// How a node is scheduled by the operating system: flags of `rig run` and `rig
/// latency`, and a setting of each node (`scheduling`, [`super::node`]).
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scheduling {
    /// Run the processes under the real-time scheduling policy SCHED_FIFO at this
    /// priority (1–99; the plant, the clock, one above the observer and the agent), ahead
    /// of all ordinary work on the machine, their memory locked (mlockall); needs root,
    /// CAP_SYS_NICE and CAP_IPC_LOCK, or rtprio and memlock limits.
    #[cfg_attr(feature = "cli", arg(long, value_name = "PRIORITY", value_parser = clap::value_parser!(u8).range(1..=99)))]
    pub rt_priority: Option<u8>,
    /// Pin the plant (the clock) alone on the last CPU and the observer, the agent and
    /// the recorder on the others, so that the rig's own work does not disturb the
    /// sampling instants (the same as `--cpus plant-alone`).
    #[cfg_attr(feature = "cli", arg(long, conflicts_with = "cpus"))]
    pub pin_cpus: bool,
    /// Where the processes run (sched_setaffinity; the layouts that set a CPU apart need
    /// at least two): `shared` wherever the operating system puts them; `plant-alone` the
    /// plant alone on the last CPU, for real time; `recorder-alone` the recorder and the
    /// checkpoint writer alone on the last CPU and the loop on the others [rig run's
    /// default: recorder-alone in lockstep when the processes poll without end on a
    /// machine of 2 or 3 CPUs, otherwise shared; a node's: shared].
    #[cfg_attr(feature = "cli", arg(long, value_enum, value_name = "LAYOUT"))]
    pub cpus: Option<CpuLayout>,
}

impl Scheduling {
    /// The layout asked for (`--cpus`, `--pin-cpus`), if any.
    pub fn layout(&self) -> Option<CpuLayout> {
        if self.pin_cpus {
            Some(CpuLayout::PlantAlone)
        } else {
            self.cpus
        }
    }

    /// The layout of a lockstep run whose processes wait as `waiting` says: the one
    /// asked for, or else [`CpuLayout::lockstep`] — the one place this is decided.
    pub fn lockstep_layout(&self, waiting: Waiting) -> CpuLayout {
        self.layout()
            .unwrap_or_else(|| CpuLayout::lockstep(waiting))
    }

    /// This scheduling for a lockstep run whose processes wait as `waiting` says: the
    /// layout [`Scheduling::lockstep_layout`].
    pub fn in_lockstep(mut self, waiting: Waiting) -> Self {
        if !self.pin_cpus {
            self.cpus = Some(self.lockstep_layout(waiting));
        }
        self
    }

    /// Places the calling process's `part` as [`Scheduling::layout`] says.
    pub fn place(&self, part: Part) -> Result<(), SystemError> {
        self.layout().unwrap_or(CpuLayout::Shared).place(part)
    }

    /// Refuses a priority outside 1–99 (a node's settings are not checked by a flag).
    pub fn check(&self) -> Result<(), Invalid> {
        match self.rt_priority {
            Some(p) if !(1..=99).contains(&p) => Err(Invalid::Priority(p)),
            _ => Ok(()),
        }
    }
}

/// How the realtime plant waits for a sampling instant: a flag of `rig run` and
/// `rig latency`, and a setting of the plant node.
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Spin {
    /// Realtime: the plant spins (a busy core) instead of sleeping for the last this many
    /// µs before each sampling instant, so that the instant does not depend on the
    /// operating system's wake-up latency; larger values trade CPU for less jitter.
    #[cfg_attr(feature = "cli", arg(long, value_name = "US", default_value_t = SPIN_US))]
    pub spin_us: u64,
}

impl Default for Spin {
    fn default() -> Self {
        Self { spin_us: SPIN_US }
    }
}

plant::choice! {
    /// How the loop's processes wait for their next message (`--wait`, [`Waiting`]).
    #[derive(Debug, PartialEq, Eq)]
    pub enum WaitKind {
        /// Sleep until woken: no CPU while waiting, an operating-system wake-up per message.
        Block => "block",
        /// Poll with the CPU's spin hint: for a machine with a core per process.
        Spin => "spin",
        /// Poll, handing the CPU to the other processes between polls.
        Yield => "yield",
    }
}

/// How the processes of a lockstep run wait for their next message unless told
/// (`--wait`): polling without end, handing the CPU on between polls (measured with
/// `rig bench-loop`, `docs/results/speed.md`: about 6 × faster than blocking on a 2-core
/// machine, at the price of busy CPUs while the run lasts). In real time they block.
pub const LOCKSTEP_WAIT: WaitKind = WaitKind::Yield;

/// How a process waits for its next message: a flag of `rig run` and a setting of
/// each node.
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wait {
    /// How each process waits for its next message: `block` sleeps until woken (no CPU
    /// while waiting, an operating-system wake-up per message); `spin` polls with the
    /// CPU's spin hint (for a core per process); `yield` polls and hands the CPU to the
    /// other processes between polls. Polling lasts `--wait-us`, then blocks [rig run's
    /// default: yield in lockstep, with the simulated plant or a driver that keeps the
    /// lockstep clock; block in real time; a node's: block].
    #[cfg_attr(feature = "cli", arg(long, value_enum, value_name = "HOW"))]
    pub wait: Option<WaitKind>,
    /// With `--wait spin` or `yield`: how long to poll before blocking [µs; default:
    /// poll without end, and senders do not wake their receivers].
    #[cfg_attr(feature = "cli", arg(long, value_name = "US"))]
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

    /// The waiting asked for, or that of a run in `lockstep` ([`LOCKSTEP_WAIT`]) or in
    /// real time (blocking) if none was.
    pub fn waiting_in(&self, lockstep: bool) -> Waiting {
        self.waiting(if lockstep {
            LOCKSTEP_WAIT
        } else {
            WaitKind::Block
        })
    }

    /// The flags that give a process `waiting` (`rig pong`).
    pub fn process_args(waiting: Waiting) -> Vec<String> {
        let w = Self::of(waiting);
        let how = w.wait.map_or("block", |k| match k {
            WaitKind::Block => "block",
            WaitKind::Spin => "spin",
            WaitKind::Yield => "yield",
        });
        let mut args = vec!["--wait".to_string(), how.to_string()];
        if let Some(us) = w.wait_us {
            args.extend(["--wait-us".to_string(), us.to_string()]);
        }
        args
    }

    /// The setting that gives a node `waiting`.
    pub fn of(waiting: Waiting) -> Self {
        let (how, bound) = match waiting {
            Waiting::Block => (WaitKind::Block, None),
            Waiting::Spin(d) => (WaitKind::Spin, Some(d)),
            Waiting::Yield(d) => (WaitKind::Yield, Some(d)),
        };
        Self {
            wait: Some(how),
            wait_us: bound
                .filter(|&d| d != FOREVER)
                .map(|d| d.as_micros() as u64),
        }
    }
}
