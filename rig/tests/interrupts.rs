//! Interrupted runs resume from their last complete trial, never from zero.
//!
//! * Lockstep: Ctrl-C (SIGINT to the process group, as a terminal sends it) and `kill
//!   -9` of every process at points drawn from a seeded generator; `--resume` continues
//!   after a trial > 0 once any trial is complete, and `returns.csv`, continued for 40
//!   trials past the interruption, is the uninterrupted run's, byte for byte.
//! * Against a realtime driver (`rig sim-driver`): Ctrl-C and `--resume` with the driver's
//!   flags continue after the last trial in `returns.csv`.
//! * A failed run's message counts the rows of `returns.csv` and, against a driver, the
//!   resume hint carries the flags it needs; a resumed run's summary says how many trials
//!   it ran and how many there are in all.

use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Output, Stdio};
use std::time::Duration;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;
use common::drivers::{Driver, Kind};
use common::{ok, rig};

fn tmp(name: &str) -> PathBuf {
    common::tmp("interrupts", name)
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn rows(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("returns.csv"))
        .unwrap_or_default()
        .lines()
        .count()
        .saturating_sub(1)
}

/// The trials of the checkpoints in run folder `dir`.
fn checkpoints(dir: &Path) -> Vec<usize> {
    std::fs::read_dir(dir.join("checkpoints"))
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().ok()?;
            name.strip_prefix("trial-")?
                .strip_suffix(".ckpt")?
                .parse()
                .ok()
        })
        .collect()
}

/// `rig run` with `args` in a process group of its own, as a terminal starts it.
fn start(args: &[&str], out: &Path) -> Child {
    rig()
        .arg("run")
        .args(args)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0)
        .spawn()
        .unwrap()
}

/// Ctrl-C (`-INT`: SIGINT to the run's process group, as a terminal sends it) or a
/// power cut (`-KILL`: every process of the run killed at once); waits for the run to
/// end.
fn interrupt(run: Child, signal: &str) -> Output {
    match signal {
        "-KILL" => common::kill_run(run.id()),
        _ => {
            std::process::Command::new("kill")
                .args([signal, "--", &format!("-{}", run.id())])
                .status()
                .unwrap();
        }
    }
    run.wait_with_output().unwrap()
}

/// `rig run --resume dir` with `extra` flags; returns its output and the trial it
/// continued after: the last one in `returns.csv` (`done`) unless its note says that
/// trials are redone, after which one.
fn resume(dir: &Path, extra: &[&str]) -> (Output, u32) {
    let done = rows(dir) as u32;
    let out = rig()
        .args(["run", "--resume"])
        .arg(dir)
        .args(extra)
        .output()
        .unwrap();
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    // "note: trials C+1..=done are redone: the last trial complete in ... is C"
    let after = match stderr.lines().find(|l| l.contains("are redone")) {
        Some(note) => note
            .rsplit(' ')
            .next()
            .and_then(|c| c.parse().ok())
            .unwrap_or_else(|| panic!("{note}")),
        None => done,
    };
    (out, after)
}

/// Trials of the uninterrupted run: enough for the latest interruption point and the trials
/// learned past it.
const WHOLE: usize = 1000;
/// Trials an interrupted run is started for: so many that it is still under way when the
/// signal comes, however fast the machine (a run learns fewer trials than asked for, so
/// its rows are the first of any longer run's).
const INTERRUPTED: &str = "100000";
/// Trials a resumed run learns past its interruption (`--resume --trials`): its rows are
/// the uninterrupted run's, byte for byte, as a whole resumed run's are.
const AFTER_RESUME: usize = 40;

/// Interrupts at points drawn from seed 36: after a number of rows, then a pause,
/// alternately SIGINT and SIGKILL. The interrupted runs are asked for far more trials than
/// they get to, so that each is still under way when the signal comes. The last complete
/// trial is the resume point: after
/// Ctrl-C the rows in `returns.csv`; after `kill -9` as many as the recording kept.
#[test]
fn lockstep_runs_interrupted_at_random_points_resume_from_their_last_complete_trial() {
    let dir = tmp("lockstep");
    let args = ["--trials", INTERRUPTED, "--quiet"];
    ok(rig()
        .arg("run")
        .args(["--trials", &WHOLE.to_string(), "--quiet"])
        .arg("--out")
        .arg(dir.join("whole"))
        .output()
        .unwrap());
    let whole = std::fs::read_to_string(dir.join("whole/returns.csv")).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(36);
    for point in 0..6 {
        let out = dir.join(format!("point-{point}"));
        let after_rows = rng.random_range(20..450);
        let pause_ms = rng.random_range(0..100);
        let signal = ["-INT", "-KILL"][point % 2];
        let run = start(&args, &out);
        common::wait_for_lines(&out.join("returns.csv"), after_rows + 1);
        std::thread::sleep(Duration::from_millis(pause_ms));
        let stopped = interrupt(run, signal);
        let (_, err) = text(&stopped);
        assert!(!stopped.status.success(), "{signal}: {err}");
        let done = rows(&out);
        assert!(whole.starts_with(&std::fs::read_to_string(out.join("returns.csv")).unwrap()));
        // The newest checkpoint of a trial in returns.csv (the agent's writer skips
        // checkpoints while the disk is behind, so it may be of an earlier trial).
        let newest = checkpoints(&out).into_iter().filter(|&t| t <= done).max();
        // On for AFTER_RESUME trials past the interruption: the bytes of the uninterrupted
        // run's first trials, as many.
        let upto = done + AFTER_RESUME;
        assert!(
            upto <= WHOLE,
            "{signal} after {done} rows: past the whole run"
        );
        let (_, after) = resume(&out, &["--trials", &upto.to_string()]);
        println!(
            "{signal} after {done} rows: resumed after trial {after} (newest checkpoint {newest:?})"
        );
        assert!(
            after > 0,
            "{signal} after {done} rows (point {point}): resumed from zero"
        );
        if signal == "-INT" {
            // The recording was finished: it holds every trial of returns.csv, and the
            // checkpoint decides.
            assert_eq!(Some(after as usize), newest, "{signal} (point {point})");
        } else {
            assert!(Some(after as usize) <= newest, "{signal} (point {point})");
        }
        let first: String = whole.split_inclusive('\n').take(upto + 1).collect();
        assert_eq!(
            std::fs::read_to_string(out.join("returns.csv")).unwrap(),
            first,
            "{signal} after {done} rows (point {point})"
        );
    }
}

/// A driver with a realtime clock (`rig sim-driver --speed 20`), its resets logged.
fn realtime_driver(name: &str) -> Driver {
    Driver::launch(&Kind::Rust, name, &["--speed", "20", "--verbose"])
}

/// Ctrl-C mid-trial against a realtime driver; `--resume` with the driver's flags
/// continues after the last trial in `returns.csv` and runs to the end.
#[test]
fn a_run_against_a_realtime_driver_interrupted_resumes_from_its_last_complete_trial() {
    let d = realtime_driver("interrupt");
    let out = tmp("realtime").join("run");
    // At 20 × real time on a shared machine, learning across gaps (counted as deadline
    // misses): a trial cut short and redone would not be what this test is about.
    let flags = [
        "--plant",
        "external",
        "--driver",
        &d.id,
        "--driver-timeout",
        "20",
        "--gaps",
        "learn",
    ];
    let run = start(
        &[&flags[..], &["--trials", "8", "--eval-every", "2"]].concat(),
        &out,
    );
    common::wait_for_lines(&out.join("returns.csv"), 4);
    std::thread::sleep(Duration::from_millis(70));
    let stopped = interrupt(run, "-INT");
    let (_, err) = text(&stopped);
    assert!(err.contains("interrupted"), "{err}");
    let hint = format!(
        "rig run --resume {} --plant external --driver {}",
        out.display(),
        d.id
    );
    assert!(err.contains(&hint), "{err}");
    let done = rows(&out);
    assert!(
        err.contains(&format!("{done} completed trials are in returns.csv")),
        "{err}"
    );
    let (resumed, after) = resume(&out, &flags);
    assert_eq!(after as usize, done);
    let (stdout, _) = text(&resumed);
    assert!(
        stdout.contains(&format!("{} trials now", 8 - done)) && stdout.contains("8 in all"),
        "{stdout}"
    );
    assert_eq!(rows(&out), 8);
    common::check_mcap(&out);
}

/// The driver stops during the reset after trial 1: that trial is complete (no greedy
/// evaluation is due), and the message's count is the rows of `returns.csv`, with the
/// resume hint naming the driver.
#[test]
fn a_failed_external_run_counts_the_rows_of_returns_csv_and_hints_the_driver_flags() {
    let mut d = realtime_driver("stalled");
    let log = BufReader::new(d.child.stderr.take().unwrap());
    let out = tmp("stalled").join("run");
    let run = start(
        &[
            "--plant",
            "external",
            "--driver",
            &d.id,
            "--driver-timeout",
            "20",
            "--reset-timeout",
            "2",
            "--trials",
            "4",
            "--eval-every",
            "0",
            "--gaps",
            "learn",
            "--quiet",
        ],
        &out,
    );
    // The second reset starts when trial 1 has ended (no attempt is redone: `--gaps
    // learn`): the driver stops there.
    let (tx, resets) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in log.lines().map_while(Result::ok) {
            if line.contains("driver: reset ") && !line.contains("done") {
                let _ = tx.send(());
            }
        }
    });
    for _ in 0..2 {
        resets.recv_timeout(Duration::from_secs(60)).unwrap();
    }
    common::signal(d.child.id(), "-STOP");
    let failed = run.wait_with_output().unwrap();
    common::signal(d.child.id(), "-CONT");
    let (_, err) = text(&failed);
    assert!(!failed.status.success(), "{err}");
    let done = rows(&out);
    assert_eq!(done, 1, "{err}");
    assert!(
        err.contains(&format!("{done} completed trials are in returns.csv")),
        "{err}"
    );
    let hint = format!(
        "rig run --resume {} --plant external --driver {}",
        out.display(),
        d.id
    );
    assert!(err.contains(&hint), "{err}");
}
