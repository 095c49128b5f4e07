//! Where a run's processes sit on the machine's CPUs (`--cpus`, `sched_setaffinity`).
//!
//! Two layouts set one CPU apart — the last one online — and put the rest of the rig on
//! the others:
//!
//! - [`CpuLayout::PlantAlone`] (real time, `--pin-cpus`): the plant, the clock, alone, so
//!   that the rig's own work does not disturb the sampling instants;
//! - [`CpuLayout::RecorderAlone`] (lockstep): the recorder and the checkpoint writer alone,
//!   so that their work does not take the CPU a polling loop process needs. On a machine
//!   with fewer CPUs than the loop's three processes and the recorder, the loop then
//!   shares its CPUs and hands each message on with a context switch instead of waiting
//!   for the recorder's time slice to end (`docs/results/speed.md`).

use super::SystemError;
use wire::{FOREVER, Waiting};

plant::choice! {
    /// Where the processes of a run are placed (`--cpus`).
    #[derive(Debug, PartialEq, Eq)]
    pub enum CpuLayout {
        /// Wherever the operating system puts them.
        Shared => "shared",
        /// The plant (the clock) alone on the last CPU; the observer, the agent and the
        /// recorder on the others.
        PlantAlone => "plant-alone",
        /// The recorder and the checkpoint writer alone on the last CPU; the plant, the
        /// observer and the agent on the others.
        RecorderAlone => "recorder-alone",
    }
}

/// A part of a run, as far as its placement goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The plant process.
    Plant,
    /// The observer or the agent process.
    Node,
    /// The recording supervisor (`rig run`).
    Recorder,
    /// The agent's checkpoint writer thread.
    CheckpointWriter,
}

/// A set of the CPUs online.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CpuSet {
    /// The last one.
    Last,
    /// All but the last.
    Others,
}

impl CpuLayout {
    /// The `--cpus` value of this layout.
    pub fn name(self) -> &'static str {
        match self {
            CpuLayout::Shared => "shared",
            CpuLayout::PlantAlone => "plant-alone",
            CpuLayout::RecorderAlone => "recorder-alone",
        }
    }

    /// Where `part` goes; `None`: where the operating system (or the parent) put it.
    pub fn cpus(self, part: Part) -> Option<CpuSet> {
        use {CpuSet::*, Part::*};
        match (self, part) {
            (CpuLayout::Shared, _) => None,
            (CpuLayout::PlantAlone, Plant) => Some(Last),
            (CpuLayout::PlantAlone, Node | Recorder) => Some(Others),
            // A thread of the agent: on the agent's CPUs.
            (CpuLayout::PlantAlone, CheckpointWriter) => None,
            (CpuLayout::RecorderAlone, Plant | Node) => Some(Others),
            (CpuLayout::RecorderAlone, Recorder | CheckpointWriter) => Some(Last),
        }
    }

    /// An error if this layout cannot be had here: one that sets a CPU apart on a
    /// machine with one CPU online.
    pub fn check(self) -> Result<(), SystemError> {
        if self != CpuLayout::Shared && online() < 2 {
            return Err(SystemError::OneCpu {
                layout: Some(self.name()),
            });
        }
        Ok(())
    }

    /// Pins the calling thread as this layout places `part` (nothing for
    /// [`CpuLayout::Shared`]).
    pub fn place(self, part: Part) -> Result<(), SystemError> {
        match self.cpus(part) {
            Some(set) => pin(set),
            None => Ok(()),
        }
    }

    /// The layout of a lockstep run whose processes wait as `waiting` says: the recorder
    /// alone when the loop polls without end (it wants a CPU whenever it has a message)
    /// on a machine of two or three CPUs, fewer than the four processes, all of which
    /// this process may use; shared otherwise.
    pub fn lockstep(waiting: Waiting) -> CpuLayout {
        let polls = matches!(waiting, Waiting::Yield(b) | Waiting::Spin(b) if b == FOREVER);
        let n = online();
        if polls && (2..=3).contains(&n) && allowed().len() == n {
            CpuLayout::RecorderAlone
        } else {
            CpuLayout::Shared
        }
    }
}

/// CPUs online: a layout's CPUs are numbered among them (the last set apart).
pub fn online() -> usize {
    // SAFETY: `sysconf` reads a system constant.
    let n = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) };
    n.max(1) as usize
}

/// The CPU a layout sets apart: the last one online.
pub fn last_cpu() -> usize {
    online() - 1
}

/// The CPUs this thread may run on, in increasing order.
pub fn allowed() -> Vec<usize> {
    // SAFETY: `cpu_set_t` is plain data; `sched_getaffinity` writes the calling thread's
    // set into it; `CPU_ISSET` reads bits below `CPU_SETSIZE`.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) != 0 {
            return Vec::new();
        }
        (0..libc::CPU_SETSIZE as usize)
            .filter(|&c| libc::CPU_ISSET(c, &set))
            .collect()
    }
}

/// Pins the calling thread (and the threads and processes it starts afterwards) to
/// `set` of the CPUs online; an error if fewer than two are online or the operating
/// system refuses (a CPU outside this process's cgroup or `taskset`).
pub fn pin(set: CpuSet) -> Result<(), SystemError> {
    let last = last_cpu();
    if last < 1 {
        return Err(SystemError::OneCpu { layout: None });
    }
    let chosen = match set {
        CpuSet::Last => last..last + 1,
        CpuSet::Others => 0..last,
    };
    // SAFETY: `cpu_set_t` is plain data (all zeros: the empty set); `CPU_SET` writes bits
    // below `CPU_SETSIZE`; `sched_setaffinity` reads the set for the calling thread
    // (pid 0).
    let ok = unsafe {
        let mut mask: libc::cpu_set_t = std::mem::zeroed();
        for c in chosen.clone() {
            libc::CPU_SET(c, &mut mask);
        }
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mask) == 0
    };
    if !ok {
        return Err(SystemError::Pin {
            first: chosen.start,
            last: chosen.end - 1,
            os: std::io::Error::last_os_error(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_layout_sets_one_part_apart() {
        use {CpuSet::*, Part::*};
        let parts = [Plant, Node, Recorder, CheckpointWriter];
        let on = |l: CpuLayout| parts.map(|p| l.cpus(p));
        assert_eq!(on(CpuLayout::Shared), [None; 4]);
        assert_eq!(
            on(CpuLayout::PlantAlone),
            [Some(Last), Some(Others), Some(Others), None]
        );
        assert_eq!(
            on(CpuLayout::RecorderAlone),
            [Some(Others), Some(Others), Some(Last), Some(Last)]
        );
    }

    #[test]
    fn a_lockstep_run_sets_the_recorder_apart_only_when_it_polls_on_few_cpus() {
        let few = (2..=3).contains(&online()) && allowed().len() == online();
        let apart = if few {
            CpuLayout::RecorderAlone
        } else {
            CpuLayout::Shared
        };
        assert_eq!(CpuLayout::lockstep(Waiting::Yield(FOREVER)), apart);
        assert_eq!(CpuLayout::lockstep(Waiting::Spin(FOREVER)), apart);
        assert_eq!(CpuLayout::lockstep(Waiting::Block), CpuLayout::Shared);
        let bounded = std::time::Duration::from_micros(100);
        assert_eq!(
            CpuLayout::lockstep(Waiting::Yield(bounded)),
            CpuLayout::Shared
        );
    }

    #[test]
    fn pinning_puts_the_thread_on_the_cpus_of_its_set() {
        // In threads of their own: the test harness's threads keep their CPUs.
        let on = |set| {
            std::thread::spawn(move || pin(set).map(|()| allowed()).map_err(|e| e.to_string()))
                .join()
                .unwrap()
        };
        if online() < 2 {
            let e = on(CpuSet::Last).unwrap_err();
            assert!(e.contains("at least two CPUs"), "{e}");
            return;
        }
        if allowed().len() == online() {
            assert_eq!(on(CpuSet::Last), Ok(vec![last_cpu()]));
            assert_eq!(on(CpuSet::Others), Ok((0..last_cpu()).collect()));
        }
    }
}
