//! `rig latency`: every stage of every cycle timed, under the scheduling asked for.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

mod common;
use common::drivers::{Driver, Kind};
use common::{names_stages, ok, pipelined, rig};

/// The tests' `rig latency` runs go one at a time: a run under SCHED_FIFO or with its
/// plant pinned takes a CPU from another run's processes, whose timing the tests assert.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn one_at_a_time() -> MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

fn tmp(name: &str) -> PathBuf {
    common::tmp("latency", name)
}

#[test]
fn latency_times_every_stage_of_every_cycle() {
    let _one = one_at_a_time();
    // A short `rig latency` at 3 ms periods (the pendulum 10 × faster than real time).
    let dir = tmp("latency");
    let out = ok(rig()
        .args([
            "latency",
            "--cycles",
            "150",
            "--period-ms",
            "3",
            "--raw-samples",
            "500",
            "--spin-us",
            "500",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("plant spins 500 µs"), "{summary}");
    // Predictive timing (the default): the action the plant announces at a sample
    // instant is the one it applies over the interval after it.
    let pipelined = pipelined(&dir.join("run/run.mcap"));
    assert!(pipelined >= 200, "{pipelined}");
    names_stages(
        &summary,
        &[
            "plant_to_observer",
            "observer_to_agent",
            "agent_to_plant",
            "slack",
        ],
        &[],
    );
    assert!(summary.contains("deadline misses") && summary.contains("raw iceoryx2"));
    let rows = latency_rows(&dir, 1 + 9 + 9 + 1);
    // Two whole trials (101 samples each), every sample a row.
    assert_eq!(rows.len(), 202);
    let mut met = 0;
    for r in &rows {
        if r["deadline_miss"] == "1" {
            continue;
        }
        met += 1;
        let v = |name: &str| r[name].parse::<u64>().unwrap();
        // The stamps are in cycle order and the stages add up.
        assert!(v("t_sample_ns") <= v("t_measurement_publish_ns"));
        assert!(v("t_measurement_publish_ns") <= v("t_observer_received_ns"));
        assert!(v("t_observer_publish_ns") <= v("t_agent_received_ns"));
        assert!(v("t_agent_publish_ns") <= v("t_action_found_ns"));
        assert!(v("t_action_found_ns") <= v("deadline_ns"));
        // plant … agent_to_plant: the stages between the wake-up and the action found.
        let parts: u64 = bench::latency::STAGES[1..7].iter().map(|s| v(s)).sum();
        assert_eq!(parts, v("sample_to_actuation"));
        assert_eq!(v("sample_to_actuation") + v("slack"), 3_000_000);
    }
    assert!(
        met > 150,
        "{met} of {} cycles met their deadline",
        rows.len()
    );
    for f in ["latency.png", "latency.svg", "summary.txt", "run/run.mcap"] {
        assert!(dir.join(f).exists(), "{f}");
    }
}

/// The rows of DIR/latency.csv, each a map from column to cell, checked to have
/// `columns` columns each.
fn latency_rows(dir: &Path, columns: usize) -> Vec<HashMap<String, String>> {
    let csv = std::fs::read_to_string(dir.join("latency.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), columns, "{header:?}");
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), columns, "{l}");
            header
                .iter()
                .zip(cells)
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

/// `rig latency` for 50 cycles at 3 ms with 200 raw round trips and `extra`, into
/// `tmp(name)`.
fn short_latency(name: &str, extra: &[&str]) -> std::process::Output {
    rig()
        .args([
            "latency",
            "--cycles",
            "50",
            "--period-ms",
            "3",
            "--raw-samples",
            "200",
        ])
        .args(extra)
        .arg("--out")
        .arg(tmp(name))
        .output()
        .unwrap()
}

#[test]
fn latency_pins_the_plant_to_a_cpu_of_its_own_or_says_why_not() {
    let _one = one_at_a_time();
    let out = short_latency("latency-pin", &["--pin-cpus"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let cpus = std::thread::available_parallelism().map_or(1, usize::from);
    if cpus >= 2 {
        assert!(out.status.success(), "{stderr}");
        assert!(stdout.contains("plant pinned to its own CPU"), "{stdout}");
    } else {
        assert!(stderr.contains("needs at least two CPUs"), "{stderr}");
    }
}

#[test]
fn latency_runs_under_a_real_time_priority_or_says_why_not() {
    let _one = one_at_a_time();
    let dir = tmp("latency-rt");
    let out = short_latency("latency-rt", &["--rt-priority", "5"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        // Root, CAP_SYS_NICE or an rtprio limit: every process ran under SCHED_FIFO.
        assert!(stdout.contains("SCHED_FIFO 5"), "{stdout}");
    } else {
        assert!(
            (stderr.contains("SCHED_FIFO") && stderr.contains("rtprio"))
                || (stderr.contains("mlockall") && stderr.contains("memlock")),
            "{stderr}"
        );
    }
    let bad = rig()
        .args(["latency", "--rt-priority", "0", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("1..=99"));
}

#[test]
fn the_cpu_wakeup_limit_is_held_or_refused_naming_the_device() {
    let _one = one_at_a_time();
    let out = short_latency("latency-wakeup", &["--cpu-wakeup-us", "0"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let refused = |stderr: &str| {
        stderr.contains("--cpu-wakeup-us") && stderr.contains("/dev/cpu_dma_latency")
    };
    if out.status.success() {
        assert!(stdout.contains("CPU wake-up limit 0 µs"), "{stdout}");
    } else {
        assert!(refused(&stderr), "{stderr}");
    }
    let dir = tmp("run-wakeup");
    let run = rig()
        .args([
            "run",
            "--quiet",
            "--trials",
            "2",
            "--cpu-wakeup-us",
            "0",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success() || refused(&stderr), "{stderr}");
    assert_eq!(run.status.success(), out.status.success(), "{stderr}");
    let bad = rig()
        .args(["run", "--cpu-wakeup-us", "3000000000", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("0..=2147483647"),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
}

#[test]
fn latency_against_a_driver_times_its_samples_to_the_commands() {
    let _one = one_at_a_time();
    // `rig sim-driver` at 10 × real time (3 ms periods) on this host: one clock.
    let driver = Driver::launch(&Kind::Rust, "latency", &["--speed", "10"]);
    let dir = tmp("latency-driver");
    let out = ok(rig()
        .args(["latency", "--driver", &driver.id])
        .args(["--cycles", "150", "--raw-samples", "200", "--out"])
        .arg(&dir)
        .output()
        .unwrap());
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary.contains(&format!(
            "against driver {:?} at its period 3.000 ms",
            driver.id
        )) && summary.contains("driver on this host (one clock)"),
        "{summary}"
    );
    // No bridge, no link.
    names_stages(
        &summary,
        &[
            "rig_to_measurement",
            "agent_to_command",
            "sample_to_command",
            "slack",
        ],
        &[
            "driver_to_rig",
            "link_round_trip",
            "rig_turnaround",
            "sample_to_actuation",
        ],
    );
    let rows = latency_rows(&dir, 1 + 11 + 13 + 1);
    // Two trials of 100 actions each (the END sample's answer is not sent).
    assert_eq!(rows.len(), 200);
    let mut in_time = 0;
    for r in &rows {
        let v = |name: &str| r[name].parse::<u64>().unwrap();
        // The stamps are in cycle order and the stages add up to t_k → command.
        assert!(v("t_sample_ns") <= v("t_measurement_publish_ns"));
        assert!(v("t_observer_publish_ns") <= v("t_agent_received_ns"));
        assert!(v("t_agent_publish_ns") <= v("t_command_publish_ns"));
        let parts: u64 = bench::latency::DRIVER_STAGES[1..7]
            .iter()
            .map(|s| v(s))
            .sum();
        assert_eq!(parts, v("sample_to_command"));
        if v("sample_to_command") <= 3_000_000 {
            in_time += 1;
            assert_eq!(v("sample_to_command") + v("slack"), 3_000_000);
        }
    }
    assert!(
        in_time > 150,
        "{in_time} of {} commands in time",
        rows.len()
    );
}

#[test]
fn latency_against_a_driver_refuses_what_only_the_simulated_plant_has() {
    let _one = one_at_a_time();
    let dir = tmp("latency-driver-bad");
    for (extra, says) in [
        (&["--period-ms", "3"][..], "cannot be used with"),
        (&["--sweep"][..], "cannot be used with"),
        (
            &["--observer-mode", "predictive"][..],
            "an external driver applies each action as it arrives",
        ),
    ] {
        let out = rig()
            .args(["latency", "--driver", "nobody"])
            .args(extra)
            .arg("--out")
            .arg(&dir)
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{extra:?}: {err}");
    }
}
