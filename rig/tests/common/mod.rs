//! What the `rig` integration tests share: the binary, scratch directories, and finding
//! and signalling the processes a `rig run` started.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

pub mod drivers;
pub mod gaps;
pub mod hosts;
pub mod python;

/// The flags of VGBP-LSTD on the §6.4.2 manipulator.
pub const ARM64_VGBP_LSTD: [&str; 6] =
    ["--system", "arm-6.4", "--algo", "vgbp", "--approx", "lstd"];

/// The `rig` binary under test.
pub fn rig() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rig"))
}

/// The flags of `rig run` against driver `id`, waiting up to 20 s for it (a Python
/// driver's start on a loaded machine).
pub fn external(id: &str) -> [&str; 6] {
    [
        "--plant",
        "external",
        "--driver",
        id,
        "--driver-timeout",
        "20",
    ]
}

/// A fresh scratch directory `rig-<suite>-<pid>-<name>` in the temporary directory.
pub fn tmp(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rig-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `out`, after asserting that the command succeeded (showing its stderr if not).
pub fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Asserts that `summary` names every stage of `present` and none of `absent`.
pub fn names_stages(summary: &str, present: &[&str], absent: &[&str]) {
    for stage in present {
        assert!(summary.contains(stage), "{stage} missing: {summary}");
    }
    for stage in absent {
        assert!(!summary.contains(stage), "{stage} present: {summary}");
    }
}

/// Waits (at most 60 s) until the file at `path` has at least `n` lines: a run under way.
pub fn wait_for_lines(path: &Path, n: usize) {
    let t0 = Instant::now();
    while std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .count()
        < n
    {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the run did not get going: {}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// The child processes of process `pid`.
pub fn children_of(pid: u32) -> Vec<u32> {
    let out = Command::new("pgrep")
        .args(["-P", &pid.to_string()])
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.trim().parse().ok())
        .collect()
}

/// The child of `pid` that runs `role` (`plant`, `observer`, `agent`: an argument of its
/// command line).
pub fn child_running(pid: u32, role: &str) -> u32 {
    children_of(pid)
        .into_iter()
        .find(|child| {
            std::fs::read(format!("/proc/{child}/cmdline"))
                .unwrap_or_default()
                .split(|&b| b == 0)
                .any(|arg| arg == role.as_bytes())
        })
        .unwrap_or_else(|| panic!("no {role} process under {pid}"))
}

/// Sends `signal` (e.g. `-9`, `-STOP`) to process `pid`.
pub fn signal(pid: u32, signal: &str) {
    Command::new("kill")
        .args([signal, &pid.to_string()])
        .status()
        .unwrap();
}

/// Messages per topic: (log time, data) in order.
pub fn messages(mcap_path: &Path) -> BTreeMap<String, Vec<(u64, Vec<u8>)>> {
    let bytes = std::fs::read(mcap_path).unwrap();
    let mut out: BTreeMap<String, Vec<(u64, Vec<u8>)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        out.entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, m.data.to_vec()));
    }
    out
}

/// The `run` metadata of the recording `DIR/run.mcap` and its plant measurements (JSON).
pub fn run_metadata_and_measurements(
    dir: &Path,
) -> (BTreeMap<String, String>, Vec<serde_json::Value>) {
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let meta = summary
        .metadata_indexes
        .iter()
        .map(|mi| mcap::read::metadata(&bytes, mi).unwrap())
        .find(|m| m.name == "run")
        .expect("the run's metadata");
    let measurements = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/plant/measurement")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    (meta.metadata, measurements)
}

/// Per sample `seq`: a field of a recorded JSON message on `topic`.
pub fn field(
    msgs: &BTreeMap<String, Vec<(u64, Vec<u8>)>>,
    topic: &str,
    key: &str,
) -> BTreeMap<u64, f64> {
    msgs[topic]
        .iter()
        .map(|(_, data)| {
            let v: serde_json::Value = serde_json::from_slice(data).unwrap();
            (v["seq"].as_u64().unwrap(), v[key].as_f64().unwrap())
        })
        .collect()
}

/// Predictive timing, from a recording: the action the plant announces at sample k
/// (`u_next`, not all zero) is the one it applies over the interval after it (as the
/// plant saturates it, to the pendulum's ±3 V). Returns how many consecutive sample pairs
/// were checked.
pub fn pipelined(mcap_path: &Path) -> usize {
    let msgs = messages(mcap_path);
    let values = |key: &str| -> Vec<f64> {
        field(&msgs, "/plant/measurement", key)
            .into_values()
            .collect()
    };
    let (next, applied, steps) = (values("u_next_0"), values("u_applied_0"), values("step"));
    assert!(next.iter().any(|u| *u != 0.0));
    let mut checked = 0;
    for k in 0..next.len() - 1 {
        if steps[k + 1] == steps[k] + 1.0 {
            assert_eq!(next[k].clamp(-3.0, 3.0), applied[k + 1], "sample {k}");
            checked += 1;
        }
    }
    checked
}

/// Checks the recording in run folder `dir` with `tests/python/check_mcap.py` (the
/// official Python `mcap` reader: the file is whole, its CRCs hold, its returns are those
/// of `returns.csv`, its `/returns`, `/latency` and `/scene` are there and hold what
/// they should), where `$RIG_PYTHON` (default `python3`) has `mcap` and
/// `mcap_protobuf`; says so and checks nothing where it has not.
pub fn check_mcap(dir: &Path) {
    let Some(python) = python::with("mcap, mcap_protobuf") else {
        println!("check_mcap.py skipped");
        return;
    };
    let out = python::script(&python, "tests/python/check_mcap.py")
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "check_mcap.py {}: {}{}",
        dir.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Kills (`kill -9`) the `rig run` process `pid` and the processes it started, all at
/// once, as a power cut would: each is stopped first, so that none sees another die.
pub fn kill_run(pid: u32) {
    let mut all = children_of(pid);
    all.push(pid);
    for p in &all {
        signal(*p, "-STOP");
    }
    for p in &all {
        signal(*p, "-KILL");
    }
}
