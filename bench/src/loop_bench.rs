//! `rig bench-loop`: how fast the three-process lockstep loop goes, next to a raw
//! iceoryx2 ping-pong between two processes measured in the same run.
//!
//! * **Raw baseline**: this process and a `rig pong` child exchange a `Measurement`
//!   over the same transport (publish + event, blocking receive); one round trip is two
//!   one-way hops.
//! * **Lockstep loop**: `rig plant`, `rig observer` and `rig agent --trivial` (zero
//!   actions, no learning) run the pendulum without a recorder; the plant times every
//!   sample from publishing its measurement to receiving the action — three one-way
//!   hops, the observer's and the trivial agent's work.
//!
//! This project's target: one lockstep step ≤ 1.5 × three raw one-way hops (median).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use wire::{Bus, Measurement, now_ns};

use runtime::learn::write_atomic;
use runtime::process::wire_err;

/// Percentiles of a sample of durations \[µs\].
#[derive(Clone, Debug)]
pub struct Stats {
    /// Number of values.
    pub n: usize,
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.9th percentile.
    pub p999: f64,
    /// Largest.
    pub max: f64,
}

impl Stats {
    /// From durations in nanoseconds.
    pub fn of(ns: &mut [u64]) -> Self {
        ns.sort_unstable();
        let q = |p: f64| ns[((ns.len() as f64 * p) as usize).min(ns.len() - 1)] as f64 / 1e3;
        Self {
            n: ns.len(),
            p50: q(0.5),
            p90: q(0.9),
            p99: q(0.99),
            p999: q(0.999),
            max: q(1.0),
        }
    }

    /// `name,n,p50,p90,p99,p999,max` (µs).
    pub fn row(&self, name: &str) -> String {
        format!(
            "{name},{},{:.2},{:.2},{:.2},{:.2},{:.2}",
            self.n, self.p50, self.p90, self.p99, self.p999, self.max
        )
    }
}

/// The benchmark's result.
#[derive(Clone, Debug)]
pub struct LoopReport {
    /// Raw round trips between two processes.
    pub raw_rtt: Stats,
    /// Lockstep samples (plant publish → action received).
    pub step: Stats,
}

impl LoopReport {
    /// Median lockstep step over three median raw one-way hops (RTT / 2 each).
    pub fn ratio(&self) -> f64 {
        self.step.p50 / (1.5 * self.raw_rtt.p50)
    }
}

struct Kill(Vec<Child>);

impl Drop for Kill {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn spawn(exe: &Path, args: &[&str], log: &Path) -> Result<Child> {
    let f =
        std::fs::File::create(log).with_context(|| format!("cannot create {}", log.display()))?;
    Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(f.try_clone()?)
        .stderr(f)
        .spawn()
        .with_context(|| format!("cannot start {}", args[0]))
}

/// The echo side of the raw baseline: returns every message on `pong` until a message
/// with `seq == u64::MAX`; pinned to the plant's CPU with `pin_cpus`.
pub fn pong(run_id: &str, pin_cpus: bool) -> Result<()> {
    if pin_cpus {
        runtime::process::pin(runtime::process::Cpus::Clock)?;
    }
    let bus = Bus::join(run_id, "pong").map_err(wire_err)?;
    let rx = bus.rx::<Measurement>("ping").map_err(wire_err)?;
    let tx = bus.tx::<Measurement>("pong").map_err(wire_err)?;
    tx.wait_for_receivers(1, Duration::from_secs(30), &bus)
        .map_err(wire_err)?;
    loop {
        let m = rx.recv(&bus, Duration::from_secs(30)).map_err(wire_err)?;
        tx.send(m).map_err(wire_err)?;
        if m.header.seq == u64::MAX {
            return Ok(());
        }
    }
}

/// `samples` raw round trips (after 1000 of warm-up) between this process and a `rig
/// pong` child \[ns\] (pinned to the plant's CPU with `pin_cpus`).
pub fn raw_round_trips(exe: &Path, out: &Path, samples: usize, pin_cpus: bool) -> Result<Vec<u64>> {
    let run_id = format!("raw{}", std::process::id());
    let bus = Bus::join(&run_id, "ping").map_err(wire_err)?;
    let rx = bus.rx::<Measurement>("pong").map_err(wire_err)?;
    let tx = bus.tx::<Measurement>("ping").map_err(wire_err)?;
    let mut args = vec!["pong", "--run-id", &run_id];
    if pin_cpus {
        args.push("--pin-cpus");
    }
    let mut kids = Kill(vec![spawn(exe, &args, &out.join("pong.log"))?]);
    tx.wait_for_receivers(1, Duration::from_secs(30), &bus)
        .map_err(wire_err)?;
    let warmup = 1000;
    let mut rtt = Vec::with_capacity(samples);
    let mut m = Measurement::default();
    for i in 0..samples + warmup {
        m.header.seq = i as u64;
        let t0 = now_ns();
        tx.send(m).map_err(wire_err)?;
        let back = rx.recv(&bus, Duration::from_secs(10)).map_err(wire_err)?;
        let dt = now_ns() - t0;
        if back.header.seq != i as u64 {
            bail!("ping-pong out of step: sent {i}, got {}", back.header.seq);
        }
        if i >= warmup {
            rtt.push(dt);
        }
    }
    m.header.seq = u64::MAX;
    tx.send(m).map_err(wire_err)?;
    let _ = rx.recv(&bus, Duration::from_secs(10));
    let status = kids.0[0].wait()?;
    kids.0.clear();
    if !status.success() {
        bail!("the pong process failed ({status})");
    }
    Ok(rtt)
}

fn lockstep_steps(exe: &Path, out: &Path, samples: usize) -> Result<Vec<u64>> {
    let mut cfg =
        runtime::config::resolve(None, &Default::default()).map_err(|e| anyhow::anyhow!("{e}"))?;
    let steps = plant::Task::new(cfg.system).steps_per_trial();
    cfg.run.trials = samples.div_ceil(steps + 1) as u32;
    cfg.run.eval_every = 0;
    let config = out.join("config.toml");
    write_atomic(&config, &cfg.to_toml())?;
    let latencies = out.join("lockstep_ns.txt");
    let run_id = format!("loop{}", std::process::id());
    let config_s = config.to_string_lossy().to_string();
    let lat_s = latencies.to_string_lossy().to_string();
    let common = ["--run-id", run_id.as_str(), "--config", config_s.as_str()];
    let mut kids = Kill(Vec::new());
    kids.0.push(spawn(
        exe,
        &[&["agent", "--trivial"][..], &common].concat(),
        &out.join("agent.log"),
    )?);
    kids.0.push(spawn(
        exe,
        &[&["observer"][..], &common].concat(),
        &out.join("observer.log"),
    )?);
    kids.0.push(spawn(
        exe,
        &[&["plant", "--latency-out", lat_s.as_str()][..], &common].concat(),
        &out.join("plant.log"),
    )?);
    for (c, name) in kids.0.iter_mut().zip(["agent", "observer", "plant"]) {
        let status = c.wait()?;
        if !status.success() {
            bail!(
                "the {name} process failed ({status}); see {}",
                out.join(format!("{name}.log")).display()
            );
        }
    }
    kids.0.clear();
    let text = std::fs::read_to_string(&latencies)
        .with_context(|| format!("cannot read {}", latencies.display()))?;
    let mut ns: Vec<u64> = text.lines().filter_map(|l| l.parse().ok()).collect();
    // Drop the first trial as warm-up.
    ns.drain(..(steps + 1).min(ns.len()));
    Ok(ns)
}

/// Runs both measurements (`samples` each) and writes `DIR/loop.csv`.
pub fn bench_loop(out: &PathBuf, samples: usize) -> Result<LoopReport> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let exe = std::env::current_exe().context("cannot find the rig executable")?;
    let mut raw = raw_round_trips(&exe, out, samples, false)?;
    let mut steps = lockstep_steps(&exe, out, samples)?;
    let report = LoopReport {
        raw_rtt: Stats::of(&mut raw),
        step: Stats::of(&mut steps),
    };
    let csv = format!(
        "measurement,n,p50_us,p90_us,p99_us,p999_us,max_us\n{}\n{}\n",
        report.raw_rtt.row("raw_round_trip"),
        report.step.row("lockstep_step")
    );
    write_atomic(&out.join("loop.csv"), &csv)?;
    Ok(report)
}
