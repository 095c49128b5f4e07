//! The plant, observer and agent as processes: each joins a run over iceoryx2
//! ([`wire`]), waits for its peers, and runs its component one sample at a time in
//! lockstep — simulated time advances only when the action for the sample has arrived.
//!
//! The step order is exactly that of the in-process runner
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
//! Trials, greedy evaluation trials and the end of the run are the plant's to decide (the
//! run's schedule, [`::plant::schedule`], as in process) and announce ([`wire::flags`]).

pub mod agent;
mod args;
pub mod cpus;
mod error;
pub mod node;
pub mod observer;
pub mod plant;
pub mod wakeup;

use std::time::Duration;

pub use error::{NodeError, Result, SystemError};

pub use cpus::{CpuLayout, CpuSet, Part};
pub use wakeup::{Wakeup, WakeupLimit};

pub use args::{LOCKSTEP_WAIT, SPIN_US, Scheduling, Spin, Wait, WaitKind};
pub use node::{AgentSettings, NodeSettings, ObserverSettings, PlantSettings, Settings};

/// How long a process waits for a message before deciding a peer has died.
pub const SILENCE: Duration = Duration::from_secs(10);
/// How long a process waits for its peers to connect at start.
pub const STARTUP: Duration = Duration::from_secs(30);

/// Puts this process under `SCHED_FIFO` at `priority` (`--rt-priority`) and locks its
/// memory (`mlockall`, no page faults in the loop); nothing for `None`. A control loop's
/// usual remedy against being preempted by other work on the machine (measured in
/// `docs/results/latency.md`).
pub fn set_rt_priority(priority: Option<u8>) -> Result<(), SystemError> {
    let Some(p) = priority else {
        return Ok(());
    };
    let param = libc::sched_param {
        sched_priority: i32::from(p),
    };
    // SAFETY: `sched_setscheduler` reads the parameter struct for this process (pid 0)
    // and has no other effect on memory.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        return Err(SystemError::RtPriority {
            priority: p,
            os: std::io::Error::last_os_error(),
        });
    }
    // No page fault in the loop: every page mapped now and later stays in memory.
    // SAFETY: `mlockall` takes flags only.
    if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } != 0 {
        return Err(SystemError::Mlock {
            priority: p,
            os: std::io::Error::last_os_error(),
        });
    }
    Ok(())
}

/// Copies `v` into a fixed-size wire array (the rest zero).
pub fn pack<const N: usize>(v: &[f64]) -> [f64; N] {
    let mut a = [0.0; N];
    a[..v.len()].copy_from_slice(v);
    a
}

/// Marks the calling thread as batch work (SCHED_BATCH: a fair share of the CPU, but
/// no preemption of the running process when it wakes up), for work beside the lockstep
/// loop — the recorder, the checkpoint writer — so that on a machine with fewer cores
/// than processes a wake-up of theirs does not stall the loop process on that core.
/// Silently nothing where the operating system refuses.
pub fn batch_thread() {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: `sched_setscheduler` reads the parameter struct for the calling thread
    // (pid 0) and has no other effect on memory.
    unsafe {
        libc::sched_setscheduler(0, libc::SCHED_BATCH, &param);
    }
}

/// How long a process of a recorded run waits, after its last message, for the recorder
/// to have read everything ([`Linger`]).
const LINGER: Duration = Duration::from_secs(10);

/// A process's last duty in a recorded run (`receivers = 2`): after its last message it
/// waits until the recorder announces that it has read everything
/// ([`wire::RecordedSignal`]), since what the process sent may be gone from the
/// recorder's queue once the process is.
pub struct Linger(Option<wire::RecordedSignal>);

impl Linger {
    /// Opens the run's signal on `bus` if a recorder listens (`receivers` ≥ 2).
    pub fn open(bus: &wire::Bus, receivers: usize) -> Result<Self> {
        Ok(Self(if receivers >= 2 {
            Some(bus.recorded()?)
        } else {
            None
        }))
    }

    /// Waits for the recorder's announcement (at most 10 s, or until the
    /// recorder's process is gone).
    pub fn wait(&self, bus: &wire::Bus) -> Result<()> {
        if let Some(r) = &self.0 {
            r.wait(bus, LINGER)?;
        }
        Ok(())
    }
}
