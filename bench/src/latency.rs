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
//!   (`rig plant --cycles-out`).
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
//! A cycle whose action did not arrive within the period is a deadline miss (its later
//! stages are left empty in `latency.csv`). The summary also reports what the machine
//! did meanwhile ([`MachineLoad`]: load average, the hypervisor's steal time, interrupts
//! on the plant's CPU), to tell the rig's outliers from the machine's. Outputs: `DIR/latency.csv` (one row per
//! cycle: the timestamps, then every stage in ns), `DIR/summary.txt` (what is printed),
//! `DIR/latency.png` / `.svg` (histograms of the stages).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use observer::config::{ObserverKind, ObserverMode, SensorKind};

use crate::loop_bench::{Stats, raw_round_trips};
use runtime::config::Overrides;
use runtime::learn::write_atomic;
use runtime::process::Scheduling;
use runtime::report::plot::{Histogram, plot_histograms};
use runtime::run::{RunOptions, run};

/// What `rig latency` runs.
#[derive(Clone, Debug)]
pub struct LatencyOptions {
    /// Samples (cycles) to time, at least; whole trials are run.
    pub cycles: usize,
    /// Sampling period \[ms\].
    pub period_ms: f64,
    /// Output directory.
    pub out: PathBuf,
    /// The observer (the sensor is the angle encoder).
    pub observer: ObserverKind,
    /// The timing: direct (an action is applied when it arrives) or predictive (at the
    /// next sample instant; `observer` must be predictive).
    pub mode: ObserverMode,
    /// Raw ping-pong round trips for the baseline.
    pub raw_samples: usize,
    /// How the three processes (and the raw ping-pong's two, with the echo on the
    /// plant's CPU when pinned) are scheduled.
    pub scheduling: Scheduling,
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
    /// Raw round trips \[µs\].
    pub raw_rtt: Stats,
    /// Per stage ([`STAGES`]), over the cycles that met their deadline \[µs\].
    pub stages: Vec<(&'static str, Stats)>,
    /// What the machine did meanwhile (Linux `/proc`; `None` elsewhere).
    pub machine: Option<MachineLoad>,
}

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
struct Counters {
    load_avg: f64,
    /// Steal, in clock ticks (`USER_HZ`).
    steal_ticks: u64,
    /// Interrupts per CPU since boot.
    interrupts: Vec<u64>,
}

impl Counters {
    /// The counters now; `None` where `/proc` does not have them.
    fn read() -> Option<Self> {
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
    fn until(&self, after: &Self, plant_cpu: Option<usize>) -> MachineLoad {
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
        let _ = writeln!(
            s,
            "rig latency: {} cycles at {:.3} ms, angle sensor, plant spins {} µs, {}{}; deadline misses: {}",
            self.cycles,
            self.period_ns as f64 * 1e-6,
            self.scheduling.spin_us,
            self.scheduling
                .rt_priority
                .map_or("ordinary scheduling".to_string(), |p| format!(
                    "SCHED_FIFO {p}"
                )),
            if self.scheduling.pin_cpus {
                ", plant pinned to its own CPU"
            } else {
                ""
            },
            self.misses
        );
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
            let ratio = if name.contains("_to_") {
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

/// Per-sequence-number stamps of a `/timing/...` channel.
fn timing(
    msgs: &BTreeMap<String, Vec<Vec<u8>>>,
    topic: &str,
    keys: &[&str],
) -> Result<BTreeMap<u64, Vec<u64>>> {
    let list = msgs
        .get(topic)
        .ok_or_else(|| anyhow!("the recording has no {topic}"))?;
    let mut out = BTreeMap::new();
    for data in list {
        let v: serde_json::Value = serde_json::from_slice(data)?;
        let seq = v["seq"]
            .as_u64()
            .ok_or_else(|| anyhow!("{topic}: a message without seq"))?;
        out.insert(
            seq,
            keys.iter().map(|k| v[*k].as_u64().unwrap_or(0)).collect(),
        );
    }
    Ok(out)
}

/// Runs the baseline and the rig, writes the outputs and returns what was measured.
pub fn latency(opts: &LatencyOptions) -> Result<LatencyReport> {
    if !(opts.period_ms.is_finite() && opts.period_ms >= 0.1 && opts.period_ms <= 1000.0) {
        bail!(
            "`--period-ms` {} is out of range: must be a number in [0.1, 1000]",
            opts.period_ms
        );
    }
    if opts.cycles == 0 {
        bail!("`--cycles` must be at least 1");
    }
    if opts.mode == ObserverMode::Predictive && opts.observer != ObserverKind::Predictive {
        bail!(
            "`--observer-mode predictive` (rig latency's default) needs `--observer predictive` (its process model predicts x̂_(k+1|k)); with `--observer {}` add `--observer-mode direct`",
            opts.observer
        );
    }
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create {}", opts.out.display()))?;
    let exe = std::env::current_exe().context("cannot find the rig executable")?;
    // The baseline under the same policy: the ping-pong's partner process inherits it.
    runtime::process::set_rt_priority(opts.scheduling.rt_priority)?;
    if opts.scheduling.pin_cpus {
        runtime::process::pin(runtime::process::Cpus::Rest)?;
    }
    let mut raw = raw_round_trips(&exe, &opts.out, opts.raw_samples, opts.scheduling.pin_cpus)?;
    let raw_rtt = Stats::of(&mut raw);

    let mut cfg = runtime::config::resolve(
        None,
        &Overrides {
            sensor: Some(SensorKind::Angle),
            observer: Some(opts.observer),
            observer_mode: Some(opts.mode),
            eval_every: Some(0),
            ..Default::default()
        },
    )
    .map_err(|e| anyhow!("{e}"))?;
    let task = plant::Task::new(cfg.system);
    let per_trial = task.steps_per_trial() + 1;
    cfg.run.trials = opts.cycles.div_ceil(per_trial) as u32;
    let speed = task.ts / (opts.period_ms * 1e-3);
    let run_dir = opts.out.join("run");
    let cycles_path = run_dir.join("plant_cycles.csv");
    let before = Counters::read();
    run(
        &cfg,
        &RunOptions {
            out: run_dir.clone(),
            run_id: None,
            progress: false,
            realtime: Some(speed),
            driver: None,
            resume: false,
            cycles_out: Some(cycles_path.clone()),
            scheduling: opts.scheduling,
        },
    )?;
    let machine = before.zip(Counters::read()).map(|(b, a)| {
        b.until(
            &a,
            opts.scheduling.pin_cpus.then(runtime::process::clock_cpu),
        )
    });

    let bytes = std::fs::read(run_dir.join("run.mcap"))?;
    let mut msgs: BTreeMap<String, Vec<Vec<u8>>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes)? {
        let m = m?;
        if m.channel.topic.starts_with("/timing/") {
            msgs.entry(m.channel.topic.clone())
                .or_default()
                .push(m.data.into_owned());
        }
    }
    let meas = timing(&msgs, "/timing/plant/measurement", &["t_publish_ns"])?;
    let est = timing(
        &msgs,
        "/timing/observer/estimate",
        &["t_received_ns", "t_publish_ns"],
    )?;
    let act = timing(
        &msgs,
        "/timing/agent/action",
        &["t_received_ns", "t_publish_ns"],
    )?;
    let text = std::fs::read_to_string(&cycles_path)
        .with_context(|| format!("cannot read {}", cycles_path.display()))?;
    let period_ns = (task.ts * 1e9 / speed).round() as u64;

    let mut csv = format!(
        "seq,{},{},deadline_miss\n",
        STAMPS.join(","),
        STAGES.join(",")
    );
    let mut stage_ns: Vec<Vec<u64>> = vec![Vec::new(); STAGES.len()];
    let (mut cycles, mut misses) = (0, 0);
    for line in text.lines().skip(1) {
        let c: Vec<u64> = line
            .split(',')
            .map(|v| v.parse())
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}: bad line {line:?}", cycles_path.display()))?;
        let [seq, t_k, woke, t_action] = c[..] else {
            bail!("{}: bad line {line:?}", cycles_path.display());
        };
        let get = |m: &BTreeMap<u64, Vec<u64>>, i: usize| m.get(&seq).map_or(0, |v| v[i]);
        let stamps = [
            t_k,
            woke,
            get(&meas, 0),
            get(&est, 0),
            get(&est, 1),
            get(&act, 0),
            get(&act, 1),
            t_action,
            t_k + period_ns,
        ];
        cycles += 1;
        let missed = t_action == 0 || stamps[2..7].contains(&0);
        let _ = write!(csv, "{seq},{}", stamps.map(|s| s.to_string()).join(","));
        let mut stage = vec![woke.saturating_sub(t_k)];
        if missed {
            misses += usize::from(t_action == 0);
            stage_ns[0].push(stage[0]);
            let _ = writeln!(csv, ",{}{},1", stage[0], ",".repeat(STAGES.len() - 1));
            continue;
        }
        stage.extend([
            stamps[2].saturating_sub(t_k),
            stamps[3].saturating_sub(stamps[2]),
            stamps[4].saturating_sub(stamps[3]),
            stamps[5].saturating_sub(stamps[4]),
            stamps[6].saturating_sub(stamps[5]),
            t_action.saturating_sub(stamps[6]),
            t_action.saturating_sub(t_k),
            (t_k + period_ns).saturating_sub(t_action),
        ]);
        for (all, v) in stage_ns.iter_mut().zip(&stage) {
            all.push(*v);
        }
        let _ = writeln!(
            csv,
            ",{},0",
            stage
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(",")
        );
    }
    if cycles == 0 {
        bail!("{}: no cycles were recorded", cycles_path.display());
    }
    write_atomic(&opts.out.join("latency.csv"), &csv)?;
    let stages: Vec<(&'static str, Stats)> = STAGES
        .iter()
        .zip(&mut stage_ns)
        .filter(|(_, v)| !v.is_empty())
        .map(|(name, v)| (*name, Stats::of(v)))
        .collect();
    let report = LatencyReport {
        period_ns,
        cycles,
        misses,
        scheduling: opts.scheduling,
        raw_rtt,
        stages,
        machine,
    };
    let summary = report.summary();
    write_atomic(&opts.out.join("summary.txt"), &summary)?;
    if opts.verbose {
        print!("{summary}");
    }

    // Histograms of the hops and compute stages, up to the largest p99.9 among them.
    let shown: Vec<&str> = STAGES
        .into_iter()
        .filter(|s| !matches!(*s, "plant" | "slack"))
        .collect();
    let values: Vec<(&str, Vec<f64>)> = shown
        .iter()
        .filter_map(|name| {
            let i = STAGES.iter().position(|s| s == name)?;
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
        &opts.out.join("latency.png"),
        &opts.out.join("latency.svg"),
        &format!(
            "Loop stages, {} cycles at {:.3} ms",
            report.cycles,
            period_ns as f64 * 1e-6
        ),
        "Duration [µs] (values beyond the axis in the last bin)",
        &series,
        x_max,
        120,
    )?;
    Ok(report)
}

/// `DIR` relative to a base, for messages.
pub fn describe(out: &Path) -> String {
    format!(
        "{}/{{latency.csv, summary.txt, latency.png, latency.svg, run/}}",
        out.display()
    )
}

/// One period of a [`sweep`].
#[derive(Clone, Debug)]
pub struct SweepPoint {
    /// Sampling period \[ms\].
    pub period_ms: f64,
    /// What was measured at it.
    pub report: LatencyReport,
}

/// `rig latency --sweep`: [`latency`] at `opts.period_ms`, then at periods shortened by
/// `factor` each (each into `DIR/period-<ms>/`), until a period misses a deadline or the
/// period would go below 0.1 ms. Writes `DIR/sweep.csv` (one row per period) and
/// returns the periods measured; the fastest sustained is the last without misses.
pub fn sweep(opts: &LatencyOptions, factor: f64) -> Result<Vec<SweepPoint>> {
    if !(factor.is_finite() && factor > 1.0) {
        bail!("sweep factor {factor} must be > 1");
    }
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create {}", opts.out.display()))?;
    let mut points = Vec::new();
    let mut csv = String::from(
        "period_ms,cycles,deadline_misses,jitter_p999_us,sample_to_actuation_p50_us,sample_to_actuation_p99_us,sample_to_actuation_p999_us,sample_to_actuation_max_us,raw_hop_p50_us\n",
    );
    let mut period = opts.period_ms;
    while period >= 0.1 {
        let sub = LatencyOptions {
            period_ms: period,
            out: opts.out.join(format!("period-{period:.3}")),
            ..opts.clone()
        };
        let report = latency(&sub)?;
        let stat = |name: &str| report.stage(name).cloned();
        let (jitter, e2e) = (stat("jitter"), stat("sample_to_actuation"));
        let f = |s: &Option<Stats>, g: fn(&Stats) -> f64| s.as_ref().map_or(f64::NAN, g);
        let _ = writeln!(
            csv,
            "{period:.3},{},{},{:.1},{:.1},{:.1},{:.1},{:.1},{:.2}",
            report.cycles,
            report.misses,
            f(&jitter, |s| s.p999),
            f(&e2e, |s| s.p50),
            f(&e2e, |s| s.p99),
            f(&e2e, |s| s.p999),
            f(&e2e, |s| s.max),
            report.raw_hop_p50()
        );
        write_atomic(&opts.out.join("sweep.csv"), &csv)?;
        let missed = report.misses > 0;
        points.push(SweepPoint {
            period_ms: period,
            report,
        });
        if missed {
            break;
        }
        period = (period / factor * 1000.0).round() / 1000.0;
    }
    Ok(points)
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
        let pinned = now.until(&later, Some(runtime::process::clock_cpu()));
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
