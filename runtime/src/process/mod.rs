//! The plant, observer and agent as processes: each joins a run over iceoryx2
//! ([`wire`]), waits for its peers, and runs its component one sample at a time in
//! lockstep — simulated time advances only when the action for the sample has arrived.
//!
//! The step order is exactly that of the in-process driver
//! ([`crate::experiment::Experiment`]), so a run over three processes gives the same
//! numbers, bit for bit:
//!
//! ```text
//! plant:    reset x_0 ─► Measurement{START}            ... u_k ─► r, x_{k+1} ─► Measurement{k+1 (END)}
//! observer: Measurement ─► x̂ (reset at START)          ─► Estimate
//! agent:    Estimate ─► start_trial / learn / greedy    ─► Action (an acknowledgement at END)
//! ```
//!
//! In predictive timing the start takes two exchanges before the first interval:
//! `Measurement{START}` (the agent's answer is `u_0`) and `Measurement{PRIMED}` (`x_0`
//! again, `u_next = u_0`; the answer is `u_1`), [`::observer::timing`].
//!
//! Trials, greedy evaluation trials and the end of the run are the plant's to decide and
//! announce ([`wire::flags`]).

pub mod agent;
pub mod external;
pub mod observer;
pub mod plant;

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;

use crate::config::{ExperimentConfig, Overrides, resolve};

/// The realtime plant's default spin before each sampling instant \[µs\] (`--spin-us`).
pub const SPIN_US: u64 = 100;
/// How long a process waits for a message before deciding a peer has died.
pub const SILENCE: Duration = Duration::from_secs(10);
/// How long a process waits for its peers to connect at start.
pub const STARTUP: Duration = Duration::from_secs(30);

/// How the realtime loop is scheduled: flags of `rig run`, `rig latency` and of each
/// process (which `rig run` passes on, [`Scheduling::process_args`]).
#[derive(Args, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scheduling {
    /// Realtime: the plant spins (a busy core) instead of sleeping for the last this many
    /// µs before each sampling instant, so that the instant does not depend on the
    /// operating system's wake-up latency; larger values trade CPU for less jitter.
    #[arg(long, value_name = "US", default_value_t = SPIN_US)]
    pub spin_us: u64,
    /// Run the processes under the real-time scheduling policy SCHED_FIFO at this
    /// priority (1–99; the plant, the clock, one above the observer and the agent), ahead
    /// of all ordinary work on the machine, their memory locked (mlockall); needs root,
    /// CAP_SYS_NICE and CAP_IPC_LOCK, or rtprio and memlock limits.
    #[arg(long, value_name = "PRIORITY", value_parser = clap::value_parser!(u8).range(1..=99))]
    pub rt_priority: Option<u8>,
    /// Pin the plant (the clock) alone on the last CPU and the observer, the agent and
    /// the recorder on the others, so that the rig's own work does not disturb the
    /// sampling instants (sched_setaffinity; needs at least two CPUs).
    #[arg(long)]
    pub pin_cpus: bool,
}

impl Scheduling {
    /// The flags that give a process this scheduling (`--spin-us` is the plant's only,
    /// see [`ProcessArgs`]).
    pub fn process_args(&self) -> Vec<String> {
        let mut args = Vec::new();
        if self.pin_cpus {
            args.push("--pin-cpus".to_string());
        }
        if let Some(p) = self.rt_priority {
            args.extend(["--rt-priority".to_string(), p.to_string()]);
        }
        args
    }
}

/// Command-line arguments every process takes.
#[derive(Args, Debug, Clone)]
pub struct ProcessArgs {
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
    /// Plant only: `lockstep` (simulated time advances when the action has arrived) or
    /// `realtime` (the plant samples at absolute deadlines of Ts / speed; a late action is
    /// applied from the moment it arrives, the previous one held until then).
    #[arg(long, default_value = "lockstep", value_parser = ["lockstep", "realtime"])]
    pub timing: String,
    /// Plant only, realtime: how many times faster than real time (Ts / speed per sample).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// How the realtime loop is scheduled.
    #[command(flatten)]
    pub scheduling: Scheduling,
    /// Agent only: answer every estimate with a zero action, without learning (for loop
    /// benchmarks).
    #[arg(long)]
    pub trivial: bool,
    /// Plant only: write the time from publishing each measurement to receiving its
    /// action (ns, one per line) to this file.
    #[arg(long, value_name = "FILE")]
    pub latency_out: Option<PathBuf>,
    /// Plant only: do not simulate; be the episode master for the external driver with
    /// this id (services rig/driver/ID/..., docs/driver.md), which is the clock.
    /// `--timing` and `--speed` do not apply then.
    #[arg(long, value_name = "ID")]
    pub driver: Option<String>,
    /// Plant only, with `--driver`: how long to wait for the driver to appear [seconds].
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    pub driver_timeout: f64,
    /// Plant only, with `--driver`: how long the driver may take for one reset (bring
    /// the system to rest at the start state) [seconds].
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    pub reset_timeout: f64,
    /// Plant only, realtime: write every sample's timing to this CSV file
    /// ([`plant::CYCLES_HEADER`]: sequence number, nominal sampling instant, wake-up,
    /// arrival of the answering action; monotonic ns) — for `rig latency`.
    #[arg(long, value_name = "FILE")]
    pub cycles_out: Option<PathBuf>,
    /// Agent only: write a checkpoint of the learned state at the end of every learning
    /// trial into this directory (`trial-NNNNNN.ckpt`, atomically).
    #[arg(long, value_name = "DIR")]
    pub checkpoints: Option<PathBuf>,
    /// Agent only: start from this checkpoint's learned state (the run's trials continue
    /// after the checkpoint's trial; the plant is started with `--after-trial`).
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
    /// Plant only: continue a run after this trial (its greedy evaluations done).
    #[arg(long, value_name = "TRIAL", default_value_t = 0)]
    pub after_trial: u32,
    /// Plant only, with `--after-trial`: the simulated learning time at that trial's end
    /// [seconds].
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
    pub sim_time: f64,
    /// Plant only, with `--after-trial`: the sequence number of the first sample.
    #[arg(long, value_name = "SEQ", default_value_t = 0)]
    pub first_seq: u64,
}

impl ProcessArgs {
    /// Reads and validates the configuration.
    pub fn config(&self) -> Result<ExperimentConfig> {
        let text = std::fs::read_to_string(&self.config)
            .with_context(|| format!("{}: cannot read", self.config.display()))?;
        resolve(Some((&self.config, &text)), &Overrides::default())
            .map_err(|e| anyhow::anyhow!("{e}"))
    }
}

/// Puts this process under `SCHED_FIFO` at `priority` (`--rt-priority`) and locks its
/// memory (`mlockall`, no page faults in the loop); nothing for `None`. A control loop's
/// usual remedy against being preempted by other work on the machine (measured in the
/// README, "Latency budget").
pub fn set_rt_priority(priority: Option<u8>) -> Result<()> {
    let Some(p) = priority else {
        return Ok(());
    };
    let param = libc::sched_param {
        sched_priority: i32::from(p),
    };
    // SAFETY: `sched_setscheduler` reads the parameter struct for this process (pid 0)
    // and has no other effect on memory.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        anyhow::bail!(
            "cannot run under SCHED_FIFO at --rt-priority {p}: {} (needs root, CAP_SYS_NICE or an rtprio limit in /etc/security/limits.conf)",
            std::io::Error::last_os_error()
        );
    }
    // No page fault in the loop: every page mapped now and later stays in memory.
    // SAFETY: `mlockall` takes flags only.
    if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } != 0 {
        anyhow::bail!(
            "cannot lock this process's memory (mlockall) for --rt-priority {p}: {} (needs root, CAP_IPC_LOCK or a memlock limit in /etc/security/limits.conf)",
            std::io::Error::last_os_error()
        );
    }
    Ok(())
}

/// Where `--pin-cpus` puts a process.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cpus {
    /// The last CPU: the plant, the clock (and the echo side of `rig latency`'s raw
    /// ping-pong, so that the baseline crosses cores as plant → observer does).
    Clock,
    /// Every other CPU: the observer, the agent and the recording supervisor.
    Rest,
}

/// The CPU `--pin-cpus` gives the plant (the clock): the last one online.
pub fn clock_cpu() -> usize {
    // SAFETY: `sysconf` reads a system constant.
    let online = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) };
    online.max(1) as usize - 1
}

/// Pins this process to `cpus` (`--pin-cpus`, `sched_setaffinity`): the clock gets a CPU
/// that none of the rig's other work runs on (measured in the README, "Latency budget").
pub fn pin(cpus: Cpus) -> Result<()> {
    let last = clock_cpu();
    if last < 1 {
        anyhow::bail!(
            "--pin-cpus needs at least two CPUs; {} are online",
            last + 1
        );
    }
    let range = match cpus {
        Cpus::Clock => last..last + 1,
        Cpus::Rest => 0..last,
    };
    // SAFETY: `cpu_set_t` is plain data (all zeros: the empty set); `CPU_SET` writes a bit
    // of it for CPUs below `CPU_SETSIZE`; `sched_setaffinity` reads the set for this
    // process (pid 0).
    let ok = unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        for c in range.clone() {
            libc::CPU_SET(c, &mut set);
        }
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0
    };
    if !ok {
        anyhow::bail!(
            "cannot pin this process to CPUs {}–{} (--pin-cpus): {}",
            range.start,
            range.end - 1,
            std::io::Error::last_os_error()
        );
    }
    Ok(())
}

/// A positive, finite number of seconds as a duration, or an error naming `flag`.
pub fn seconds(flag: &str, s: f64) -> Result<Duration> {
    if !(s.is_finite() && s > 0.0 && s <= 1e6) {
        anyhow::bail!("`{flag}` {s} is out of range: must be a number of seconds in (0, 1e6]");
    }
    Ok(Duration::from_secs_f64(s))
}

/// Copies `v` into a fixed-size wire array (the rest zero).
pub fn pack<const N: usize>(v: &[f64]) -> [f64; N] {
    let mut a = [0.0; N];
    a[..v.len()].copy_from_slice(v);
    a
}

/// Converts a transport error.
pub fn wire_err(e: wire::Error) -> anyhow::Error {
    anyhow::anyhow!("{e}")
}
