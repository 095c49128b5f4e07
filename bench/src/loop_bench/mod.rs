//! `rig bench-loop`: what the three-process loop costs against one process, and against
//! the transport's own limits, measured side by side in one invocation.
//!
//! * **The experiment**: the default experiment (`--trials` trials) in one process
//!   (`rig learn --runs 1 --threads 1`), as three processes with the recorder (`rig
//!   run`), and as the three processes alone (no recorder), alternating, each
//!   `--repetitions` times: wall and CPU time (all processes), the medians, their ratios,
//!   and whether `rig run`'s `returns.csv` equals `rig learn`'s byte for byte. The
//!   processes wait as `--wait` says.
//! * **The step**: per sample of the run without the recorder, the time from the plant
//!   publishing a measurement to receiving its action (three hops and the observer's and
//!   the agent's work), the first trial left out.
//! * **The transport**: a ping-pong of `Measurement`s between two `rig pong` processes
//!   started as the loop's are: waiting as the loop does, blocking on events (an
//!   operating-system wake-up per hop), and busy-polling without events (the transport's
//!   limit). One one-way hop is half a round trip.
//! * **External drivers** (with [`LoopOptions::external`]): `rig run --plant external`
//!   against drivers in lockstep, beside the built-in `rig run` or their own yardstick
//!   ([`external`]).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use runtime::error::AtFile;
use runtime::output::write_atomic;
use runtime::process::CpuLayout;
use wire::{FOREVER, Waiting};

mod error;
pub mod external;
mod raw;
mod runs;

pub use error::LoopError;
pub use external::{ExternalCase, ExternalOptions};
pub use raw::{pong, raw_round_trips};
pub use runs::Timed;

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

struct Kill(Vec<Child>);

impl Drop for Kill {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn spawn(exe: &Path, args: &[&str], log: &Path) -> Result<Child, LoopError> {
    let f = std::fs::File::create(log).at("cannot create", log)?;
    Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(f.try_clone()?)
        .stderr(f)
        .spawn()
        .map_err(|source| LoopError::Start {
            program: args[0].to_owned(),
            source,
        })
}

/// What to measure.
#[derive(Clone, Debug)]
pub struct LoopOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Trials of the default experiment per run.
    pub trials: u32,
    /// Runs of each kind (alternating).
    pub repetitions: usize,
    /// Round trips per ping-pong.
    pub samples: usize,
    /// How the processes wait for their next message.
    pub waiting: Waiting,
    /// Where the three processes and the recorder run.
    pub layout: CpuLayout,
    /// Also runs against external drivers in lockstep, from here.
    pub external: Option<ExternalOptions>,
}

/// What `rig bench-loop` measured.
#[derive(Clone, Debug)]
pub struct LoopReport {
    /// Where the processes ran.
    pub layout: CpuLayout,
    /// `rig learn --runs 1`, per repetition.
    pub in_process: Vec<Timed>,
    /// `rig run`, per repetition.
    pub three_processes: Vec<Timed>,
    /// The three processes without the recorder, per repetition.
    pub unrecorded: Vec<Timed>,
    /// Whether every `rig run` wrote `rig learn`'s `runs.csv` byte for byte.
    pub identical: bool,
    /// Samples per run (all trials, evaluations included).
    pub samples_per_run: usize,
    /// Lockstep steps of the runs without the recorder \[µs\].
    pub step: Stats,
    /// Ping-pong round trips, waiting as the loop does \[µs\].
    pub raw_waiting: Stats,
    /// Ping-pong round trips, blocking on events \[µs\].
    pub raw_block: Stats,
    /// Ping-pong round trips, busy-polling without events \[µs\].
    pub raw_poll: Stats,
    /// Runs against external drivers in lockstep.
    pub external: Vec<ExternalCase>,
}

/// The median of `runs`' wall and CPU times.
pub fn median(runs: &[Timed]) -> Timed {
    let pick = |f: fn(&Timed) -> std::time::Duration| {
        let mut v: Vec<_> = runs.iter().map(f).collect();
        v.sort();
        v[v.len() / 2]
    };
    Timed {
        wall: pick(|t| t.wall),
        cpu: pick(|t| t.cpu),
    }
}

impl LoopReport {
    /// Median wall time of `rig run` over that of `rig learn --runs 1`.
    pub fn ratio(&self) -> f64 {
        median(&self.three_processes).wall.as_secs_f64()
            / median(&self.in_process).wall.as_secs_f64()
    }

    /// The one-screen summary.
    pub fn summary(&self) -> String {
        let row = |name: &str, runs: &[Timed]| {
            let m = median(runs);
            format!(
                "{name:<34} wall {:>7.3} s  cpu {:>7.3} s  ({:.1} µs wall per sample; n = {})\n",
                m.wall.as_secs_f64(),
                m.cpu.as_secs_f64(),
                m.wall.as_secs_f64() * 1e6 / self.samples_per_run as f64,
                runs.len()
            )
        };
        let hop = |name: &str, s: &Stats| {
            format!(
                "{name:<34} one-way hop p50 {:.2} µs  p99 {:.2}  p99.9 {:.2}  (round trips n = {})\n",
                s.p50 / 2.0,
                s.p99 / 2.0,
                s.p999 / 2.0,
                s.n
            )
        };
        let un = median(&self.unrecorded).wall.as_secs_f64();
        format!(
            "three processes placed --cpus {}\n{}{}{}three processes / one process: {:.2} (medians of wall time); recorder's share: {:.2} × the loop without it; rig run {} rig learn's runs.csv byte for byte\n{}{}{}{}",
            self.layout.name(),
            row("one process (rig learn --runs 1)", &self.in_process),
            row("three processes (rig run)", &self.three_processes),
            row("three processes, no recorder", &self.unrecorded),
            self.ratio(),
            median(&self.three_processes).wall.as_secs_f64() / un,
            if self.identical {
                "wrote"
            } else {
                "DID NOT write"
            },
            format_args!(
                "{:<34} p50 {:.2} µs  p99 {:.2}  p99.9 {:.2}  (n = {})\n",
                "lockstep step (3 hops + work)",
                self.step.p50,
                self.step.p99,
                self.step.p999,
                self.step.n
            ),
            hop("ping-pong, waiting as the loop", &self.raw_waiting),
            hop("ping-pong, blocking on events", &self.raw_block),
            hop("ping-pong, busy-polling", &self.raw_poll),
        ) + &self.external_summary()
    }

    /// The external drivers' lines of the summary: each against its yardstick.
    fn external_summary(&self) -> String {
        let built_in =
            median(&self.three_processes).wall.as_secs_f64() * 1e6 / self.samples_per_run as f64;
        let mut s = String::new();
        for c in &self.external {
            let (yard, what) = match c.yardstick_us() {
                Some(y) => (y, "env.step alone"),
                None => (built_in, "rig run"),
            };
            s += &format!(
                "{:<34} wall {:>7.3} s  ({:.1} µs per sample; n = {}); {what} {yard:.1} µs: {:.2} ×\n",
                c.name,
                median(&c.runs).wall.as_secs_f64(),
                c.per_sample_us(),
                c.runs.len(),
                c.per_sample_us() / yard
            );
        }
        s
    }

    /// `loop.csv`: one row per measured run and per latency distribution.
    fn csv(&self) -> String {
        let mut s = String::from("measurement,repetition,wall_s,cpu_s\n");
        let external = self.external.iter().map(|c| (c.key, &c.runs));
        for (name, runs) in [
            ("in_process", &self.in_process),
            ("three_processes", &self.three_processes),
            ("unrecorded", &self.unrecorded),
        ]
        .into_iter()
        .chain(external)
        {
            for (i, t) in runs.iter().enumerate() {
                s += &format!(
                    "{name},{i},{},{}\n",
                    t.wall.as_secs_f64(),
                    t.cpu.as_secs_f64()
                );
            }
        }
        for c in &self.external {
            // The yardstick's loop for as many samples (its own CPU time not taken).
            for (i, y) in c.yardstick.iter().enumerate() {
                s += &format!("{}_yardstick,{i},{},\n", c.key, y * c.samples as f64 / 1e6);
            }
        }
        s += "\nmeasurement,n,p50_us,p90_us,p99_us,p999_us,max_us\n";
        for (name, st) in [
            ("lockstep_step", &self.step),
            ("raw_round_trip_waiting", &self.raw_waiting),
            ("raw_round_trip_block", &self.raw_block),
            ("raw_round_trip_poll", &self.raw_poll),
        ] {
            s += &st.row(name);
            s.push('\n');
        }
        s
    }
}

/// Runs every measurement and writes `DIR/loop.csv` and `DIR/summary.txt`; `progress`
/// is told what runs.
pub fn bench_loop(opts: &LoopOptions, progress: &dyn Fn(&str)) -> Result<LoopReport, LoopError> {
    let out = &opts.out;
    std::fs::create_dir_all(out).at("cannot create", out)?;
    let exe = std::env::current_exe().map_err(LoopError::Executable)?;
    let (mut in_process, mut three, mut unrecorded) = (Vec::new(), Vec::new(), Vec::new());
    let (mut steps, mut identical) = (Vec::new(), true);
    for i in 0..opts.repetitions.max(1) {
        progress(&format!(
            "repetition {} of {}",
            i + 1,
            opts.repetitions.max(1)
        ));
        let (learn, run) = (out.join(format!("learn-{i}")), out.join(format!("run-{i}")));
        in_process.push(runs::in_process(&exe, &learn, opts.trials)?);
        three.push(runs::three_processes(
            &exe,
            &run,
            opts.trials,
            opts.waiting,
            opts.layout,
        )?);
        let (t, s) = runs::unrecorded(
            &exe,
            &out.join(format!("loop-{i}")),
            opts.trials,
            opts.waiting,
            opts.layout,
        )?;
        unrecorded.push(t);
        steps.extend(s);
        identical &= same_file(&learn.join("runs.csv"), &run.join("returns.csv"));
    }
    progress("ping-pong");
    let raw = |w: Waiting| -> Result<Stats, LoopError> {
        Ok(Stats::of(&mut raw_round_trips(
            &exe,
            out,
            opts.samples,
            false,
            w,
        )?))
    };
    let cfg = runtime::config::resolve(None, &Default::default())?;
    let samples_per_run = samples_per_run(&cfg, opts.trials);
    let external = match &opts.external {
        Some(o) => external::external_cases(&exe, out, opts.trials, opts.repetitions, o, progress)?,
        None => Vec::new(),
    };
    let report = LoopReport {
        layout: opts.layout,
        in_process,
        three_processes: three,
        unrecorded,
        identical,
        samples_per_run,
        step: Stats::of(&mut steps),
        raw_waiting: raw(opts.waiting)?,
        raw_block: raw(Waiting::Block)?,
        raw_poll: raw(Waiting::Spin(FOREVER))?,
        external,
    };
    write_atomic(&out.join("loop.csv"), &report.csv())?;
    write_atomic(&out.join("summary.txt"), &report.summary())?;
    Ok(report)
}

/// Samples of one run of `cfg` with `trials` trials: every learning trial and greedy
/// evaluation runs to its end in the default experiment.
fn samples_per_run(cfg: &runtime::config::ExperimentConfig, trials: u32) -> usize {
    let task = cfg.task();
    let evals =
        trials.checked_div(cfg.run().eval_every).unwrap_or(0) as usize * task.initial_states.len();
    (trials as usize + evals) * (task.steps_per_trial() + 1)
}

/// Whether the files at `a` and `b` hold the same bytes (false if either is missing).
fn same_file(a: &Path, b: &Path) -> bool {
    matches!((std::fs::read(a), std::fs::read(b)), (Ok(x), Ok(y)) if x == y)
}
