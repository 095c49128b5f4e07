//! A driver that provides the reward and the trials' endings (docs/driver.md,
//! `PROVIDES_REWARD`): `rig/tests/scripts/ending_driver.py`, a lockstep driver whose
//! every step is worth 1 and whose trials end at a known step. The rig learns its
//! rewards as they are, ends each trial where the driver says — terminated: a terminal
//! state (`END | TERMINAL`), truncated: bootstrapped through (`END` alone) — and says so
//! in the recording; a NaN reward, a learner that needs the reward's gradient, and a
//! driver of the previous protocol version are one-line errors.
//!
//! Needs `iceoryx2==0.10.0` importable by `$RIG_PYTHON` (default `python3`); without it
//! the tests print why and pass — CI installs it, so they run there.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::drivers::{Driver, python};
use common::rig;

/// `flags` bits of the recorded messages (wire::flags).
const END: u64 = 2;
const TERMINAL: u64 = 16;
const DRIVER_REWARD: u64 = 1024;

fn tmp(name: &str) -> PathBuf {
    common::tmp("driver-reward", name)
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The test driver with `extra` flags.
fn ending_driver(python: &str, name: &str, extra: &[&str]) -> Driver {
    Driver::script(python, "rig/tests/scripts/ending_driver.py", name, extra)
}

/// `rig run --plant external` against driver `id`: MLAC (the default), 4 trials, a
/// greedy evaluation after every 2, with `extra` flags.
fn run(id: &str, extra: &[&str], dir: &Path) -> Output {
    rig()
        .arg("run")
        .args(common::external(id))
        .args(["--trials", "4", "--eval-every", "2"])
        .arg("--out")
        .arg(dir)
        .args(extra)
        .output()
        .unwrap()
}

/// A run against a driver whose trials end at step `end_at`, `ending`: every trial's
/// return (and greedy return) is `end_at` (a reward of 1 per step); each trial's last
/// measurement is its step `end_at`, marked `END` with `TERMINAL` exactly when
/// terminated; every measurement carries `DRIVER_REWARD` and the recording says
/// `reward_from = driver`.
fn ends_where_the_driver_says(ending: &str, end_at: u32, terminal: bool) {
    let Some(python) = python() else { return };
    let at = end_at.to_string();
    let d = ending_driver(&python, ending, &["--end-at", &at, "--ending", ending]);
    let dir = tmp(ending);
    let out = run(&d.id, &[], &dir);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    let rows: Vec<&str> = returns.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{returns}");
    for (i, row) in rows.iter().enumerate() {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells[3], at, "return of trial {}: {returns}", i + 1);
        let greedy = if i % 2 == 1 { at.as_str() } else { "" };
        assert_eq!(cells[4], greedy, "greedy return: {returns}");
    }
    let (meta, measurements) = common::run_metadata_and_measurements(&dir);
    assert_eq!(meta.get("reward_from").map(String::as_str), Some("driver"));
    let mut ends = 0;
    for m in &measurements {
        let f = m["flags"].as_u64().unwrap();
        assert_ne!(f & DRIVER_REWARD, 0, "{m}");
        if f & END != 0 {
            ends += 1;
            assert_eq!(m["step"].as_u64(), Some(u64::from(end_at)), "{m}");
            assert_eq!(f & TERMINAL != 0, terminal, "{ending}: {m}");
            assert_eq!(m["reward"].as_f64(), Some(1.0), "{m}");
        }
    }
    assert_eq!(ends, 4 + 2, "four learning and two greedy trials ended");
    assert!(
        stdout.contains("rewards and trial endings: the driver's own"),
        "{stdout}"
    );
}

#[test]
fn a_trial_the_driver_terminates_ends_at_a_terminal_state() {
    ends_where_the_driver_says("terminated", 5, true);
}

#[test]
fn a_trial_the_driver_truncates_ends_without_a_terminal_state() {
    ends_where_the_driver_says("truncated", 7, false);
}

/// A one-line error on stderr containing every one of `parts`, exit code 1 (beside it
/// only the note that the rig waits for a driver still starting, on a loaded machine).
fn refused(out: &Output, parts: &[&str]) {
    let (stdout, stderr) = text(out);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    let said: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("waiting up to "))
        .collect();
    assert_eq!(said.len(), 1, "one line: {stderr}");
    for part in parts {
        assert!(said[0].contains(part), "{part:?} in {stderr}");
    }
}

#[test]
fn a_nan_reward_from_the_driver_is_refused_at_the_boundary() {
    let Some(python) = python() else { return };
    let d = ending_driver(&python, "nan", &["--end-at", "9", "--nan-at", "3"]);
    let out = run(&d.id, &[], &tmp("nan"));
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    // The plant process stops with the error, and the run names it.
    let line = format!(
        "error: driver {:?}: sample 3: reward = NaN: a driver that provides the reward sends a finite one",
        d.id
    );
    assert!(stderr.contains(&line), "{stderr}");
}

#[test]
fn a_learner_that_needs_the_rewards_gradient_is_refused_with_a_drivers_reward() {
    let Some(python) = python() else { return };
    let d = ending_driver(&python, "vgbp", &[]);
    let dir = tmp("vgbp");
    let out = run(&d.id, &["--algo", "vgbp", "--approx", "lstd"], &dir);
    refused(&out, &["error: --algo vgbp", "∂ρ/∂u", &d.id, "pendulum"]);
    assert!(
        !dir.join("returns.csv").exists(),
        "a refused run writes nothing"
    );
}

#[test]
fn a_driver_of_the_previous_protocol_version_is_named() {
    let Some(python) = python() else { return };
    let d = ending_driver(&python, "old", &["--old-version"]);
    // Let the driver create its services first.
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let out = run(&d.id, &[], &tmp("old"));
    refused(
        &out,
        &[
            "speaks another protocol version than this rig's 3",
            "rig.DriverInfo.v2",
            "update the driver to protocol version 3",
        ],
    );
}
