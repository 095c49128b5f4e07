//! What the machine did during a measurement: load average, the hypervisor's steal
//! time, interrupts on the plant's CPU (Linux `/proc`).

/// The machine's own counters over the rig's run, to tell the rig's outliers from the
/// machine's: time the hypervisor ran something else on the virtual CPUs (steal), and the
/// interrupts taken by the plant's CPU.
#[derive(Clone, Debug, PartialEq)]
pub struct MachineLoad {
    /// 1-minute load average when the run started.
    pub load_avg: f64,
    /// Steal time over the run, all CPUs \[ms\].
    pub steal_ms: f64,
    /// The CPU the plant ran on (the last one when pinned), if known.
    pub plant_cpu: Option<usize>,
    /// Interrupts the plant's CPU took over the run (all CPUs' when not pinned).
    pub interrupts: u64,
}

/// Counters of `/proc/stat`, `/proc/interrupts` and `/proc/loadavg` at one moment.
pub(super) struct Counters {
    load_avg: f64,
    /// Steal, in clock ticks (`USER_HZ`).
    steal_ticks: u64,
    /// Interrupts per CPU since boot.
    interrupts: Vec<u64>,
}

impl Counters {
    /// The counters now; `None` where `/proc` does not have them.
    pub(super) fn read() -> Option<Self> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        // cpu  user nice system idle iowait irq softirq steal ...
        let steal_ticks = stat
            .lines()
            .next()?
            .split_whitespace()
            .nth(8)?
            .parse()
            .ok()?;
        let irq = std::fs::read_to_string("/proc/interrupts").ok()?;
        let mut lines = irq.lines();
        let ncpu = lines.next()?.split_whitespace().count();
        let mut interrupts = vec![0u64; ncpu];
        for line in lines {
            let counts = line.split_whitespace().skip(1).take(ncpu);
            for (total, c) in interrupts.iter_mut().zip(counts) {
                match c.parse::<u64>() {
                    Ok(c) => *total += c,
                    Err(_) => break,
                }
            }
        }
        let load_avg = std::fs::read_to_string("/proc/loadavg")
            .ok()?
            .split_whitespace()
            .next()?
            .parse()
            .ok()?;
        Some(Self {
            load_avg,
            steal_ticks,
            interrupts,
        })
    }

    /// What changed from `self` to `after`, with the interrupts of `plant_cpu` (all
    /// CPUs' if `None`: the plant was not pinned).
    pub(super) fn until(&self, after: &Self, plant_cpu: Option<usize>) -> MachineLoad {
        // SAFETY: sysconf has no preconditions.
        let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as f64;
        let plant_cpu = plant_cpu.filter(|&c| c < after.interrupts.len());
        let delta = |i: usize| after.interrupts[i].saturating_sub(self.interrupts[i]);
        let interrupts = match plant_cpu {
            Some(c) => delta(c),
            None => (0..after.interrupts.len()).map(delta).sum(),
        };
        MachineLoad {
            load_avg: self.load_avg,
            steal_ms: after.steal_ticks.saturating_sub(self.steal_ticks) as f64 * 1e3 / hz,
            plant_cpu,
            interrupts,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn machine_counters_are_read_and_differenced() {
        if !cfg!(target_os = "linux") {
            return;
        }
        let now = Counters::read().expect("/proc/stat, /proc/interrupts, /proc/loadavg");
        // SAFETY: sysconf has no preconditions.
        let online = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) } as usize;
        assert_eq!(now.interrupts.len(), online);
        assert!(
            now.interrupts.iter().all(|&n| n > 0),
            "{:?}",
            now.interrupts
        );
        assert!(now.load_avg >= 0.0);
        let later = Counters {
            load_avg: 9.0,
            steal_ticks: now.steal_ticks + 3,
            interrupts: now
                .interrupts
                .iter()
                .enumerate()
                .map(|(i, n)| n + 10 * (i as u64 + 1))
                .collect(),
        };
        let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as f64;
        let pinned = now.until(&later, Some(runtime::process::cpus::last_cpu()));
        assert_eq!(pinned.load_avg, now.load_avg);
        assert!((pinned.steal_ms - 3e3 / hz).abs() < 1e-9);
        assert_eq!(pinned.plant_cpu, Some(online - 1));
        assert_eq!(pinned.interrupts, 10 * online as u64);
        let all = now.until(&later, None);
        assert_eq!(all.plant_cpu, None);
        assert_eq!(
            all.interrupts,
            (1..=online as u64).map(|i| 10 * i).sum::<u64>()
        );
    }
}
