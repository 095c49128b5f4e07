//! Faults with real processes: each of plant, observer and agent killed with `kill -9`
//! in the middle of a run — lockstep and realtime — and `rig run --resume`.
//!
//! * Lockstep: `rig run` names the dead process and exits non-zero, `run.mcap` is
//!   readable, no completed trial is lost, and `--resume` continues so that
//!   `returns.csv` and every recorded message equal those of a run never interrupted.
//! * Realtime: the plant's samples after the death show the safe action (zero) within
//!   two periods of the last action's arrival, on the plant's clock.
//! * Bad resumes: one-line errors naming the file and the problem.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Output, Stdio};
use std::time::Duration;

mod common;
use common::{child_running, ok, rig, signal};

fn tmp(name: &str) -> PathBuf {
    common::tmp("faults", name)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .count()
}

fn wait_for_rows(dir: &Path, n: usize) {
    common::wait_for_lines(&dir.join("returns.csv"), n);
}

/// Kills (`kill -9`) the child of `sup` that runs `role`.
/// Returns the time (`CLOCK_MONOTONIC`, the plant's clock) at which the process was dead.
fn kill_role(sup: &Child, role: &str) -> u64 {
    signal(child_running(sup.id(), role), "-9");
    wire::now_ns()
}

/// Messages per topic, in file order: (MCAP sequence, log time, data).
type Messages = BTreeMap<String, Vec<(u32, u64, Vec<u8>)>>;

/// Reads a recording with its summary (a finished file) and every message.
fn recording(path: &Path) -> Messages {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let summary = mcap::Summary::read(&bytes)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .expect("a summary: the recording was finished");
    assert!(summary.stats.is_some());
    let mut out = Messages::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        out.entry(m.channel.topic.clone()).or_default().push((
            m.sequence,
            m.log_time,
            m.data.into_owned(),
        ));
    }
    out
}

/// The run messages (plant, observer, agent, the returns, the system's pictures), without
/// the wall-clock timing channels and the latency taken of them.
fn run_messages(path: &Path) -> Messages {
    let mut m = recording(path);
    m.retain(|topic, _| !topic.starts_with("/timing/") && topic != "/latency");
    m
}

/// Asserts that run folders `a` and `b` hold the same `returns.csv` and run messages.
fn same_run(a: &Path, b: &Path) {
    assert_eq!(
        std::fs::read_to_string(a.join("returns.csv")).unwrap(),
        std::fs::read_to_string(b.join("returns.csv")).unwrap()
    );
    assert_eq!(
        run_messages(&a.join("run.mcap")),
        run_messages(&b.join("run.mcap"))
    );
}

/// The uninterrupted run's trials: enough for the killed runs' rows to stay below them
/// while the kill takes effect (a trial takes about 2 ms in lockstep; finding and
/// killing a process on a loaded machine, a few hundred ms).
const TRIALS: &str = "400";
/// The uninterrupted run.
const RUN: [&str; 6] = ["--trials", TRIALS, "--eval-every", "5", "--quiet", "--out"];
/// A run that is killed: asked for so many trials that it dies mid-run however fast or
/// loaded the machine; resumed with `--trials 400`, it is the uninterrupted run.
const KILLED: [&str; 6] = [
    "--trials",
    "100000",
    "--eval-every",
    "5",
    "--quiet",
    "--out",
];

#[test]
fn a_process_killed_in_lockstep_loses_no_trial_and_resume_continues_bit_for_bit() {
    let dir = tmp("lockstep");
    ok(rig()
        .arg("run")
        .args(RUN)
        .arg(dir.join("whole"))
        .output()
        .unwrap());
    let whole = std::fs::read_to_string(dir.join("whole/returns.csv")).unwrap();
    let whole_msgs = run_messages(&dir.join("whole/run.mcap"));
    for (i, role) in ["agent", "observer", "plant"].into_iter().enumerate() {
        let out = dir.join(role);
        let sup = rig()
            .arg("run")
            .args(KILLED)
            .arg(&out)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Different moments: after 4, 9 and 14 trials have been written.
        wait_for_rows(&out, 5 + 5 * i);
        kill_role(&sup, role);
        let died = sup.wait_with_output().unwrap();
        let err = stderr(&died);
        assert!(!died.status.success(), "{role}: rig run must fail");
        assert!(
            err.contains(&format!("the {role} process exited (signal: 9")),
            "{role}: {err}"
        );
        assert!(err.contains("rig run --resume"), "{role}: {err}");
        // Readable, and no completed trial lost: the rows written are the whole run's.
        let before = std::fs::read_to_string(out.join("returns.csv")).unwrap();
        assert!(whole.starts_with(&before), "{role}: {before}");
        let recorded = run_messages(&out.join("run.mcap"));
        let rows = before.lines().count() - 1;
        assert!(
            rows >= 4 + 5 * i && rows < TRIALS.parse().unwrap(),
            "{role}: {rows} rows"
        );
        for (topic, msgs) in &recorded {
            let n = msgs.len();
            assert_eq!(msgs[..], whole_msgs[topic][..n], "{role}: {topic}");
        }

        let resumed = ok(rig()
            .args(["run", "--quiet", "--trials", TRIALS, "--resume"])
            .arg(&out)
            .output()
            .unwrap());
        assert!(resumed.status.success());
        let after = std::fs::read_to_string(out.join("returns.csv")).unwrap();
        assert_eq!(after, whole, "{role}: returns.csv after --resume");
        assert_eq!(
            run_messages(&out.join("run.mcap")),
            whole_msgs,
            "{role}: run.mcap after --resume"
        );
    }
}

#[test]
fn a_finished_run_learns_on_with_more_trials() {
    let dir = tmp("more");
    let args = [
        "--algo",
        "vgbp",
        "--approx",
        "lstd",
        "--eval-every",
        "2",
        "--quiet",
        "--out",
    ];
    ok(rig()
        .arg("run")
        .args(["--trials", "8"])
        .args(args)
        .arg(dir.join("eight"))
        .output()
        .unwrap());
    ok(rig()
        .arg("run")
        .args(["--trials", "4"])
        .args(args)
        .arg(dir.join("four"))
        .output()
        .unwrap());
    let done = rig()
        .args(["run", "--quiet", "--resume"])
        .arg(dir.join("four"))
        .output()
        .unwrap();
    assert!(!done.status.success());
    assert!(
        stderr(&done).contains("nothing to resume"),
        "{}",
        stderr(&done)
    );
    ok(rig()
        .args(["run", "--quiet", "--trials", "8", "--resume"])
        .arg(dir.join("four"))
        .output()
        .unwrap());
    same_run(&dir.join("four"), &dir.join("eight"));
}

/// A run whose last checkpoint was never written (its agent stopped on a full disk as
/// the run ended) has every row of `returns.csv` but is not done: `--resume` redoes the
/// trials after its newest checkpoint and ends with the bytes of a run never stopped.
#[test]
fn a_run_without_its_last_checkpoint_is_not_done_and_resume_redoes_the_rest() {
    let dir = tmp("last-checkpoint");
    let run = |out: &str| {
        ok(rig()
            .arg("run")
            .args(["--trials", "4", "--eval-every", "2", "--quiet", "--out"])
            .arg(dir.join(out))
            .output()
            .unwrap())
    };
    run("whole");
    run("lost");
    let last = dir.join("lost/checkpoints/trial-000004.ckpt");
    std::fs::remove_file(&last).unwrap();
    let resumed = ok(rig()
        .args(["run", "--quiet", "--resume"])
        .arg(dir.join("lost"))
        .output()
        .unwrap());
    assert!(
        // Which trials: the writer may have skipped trial 3's checkpoint for trial 4's.
        stderr(&resumed).contains("..=4 are redone"),
        "{}",
        stderr(&resumed)
    );
    assert!(last.exists());
    same_run(&dir.join("lost"), &dir.join("whole"));
}

/// Trials that end early (the §6.4.2 manipulator's operating range): the agent stamps the
/// checkpoint with the trial's start plus its samples, returns.csv with whole trials less
/// the samples not run, which round apart; resuming still continues as the whole run.
#[test]
fn a_run_whose_trials_end_early_learns_on_with_more_trials() {
    let dir = tmp("early");
    let run = |trials: &str, out: &str| {
        ok(rig()
            .arg("run")
            .args(common::ARM64_VGBP_LSTD)
            .args(["--trials", trials, "--quiet", "--out"])
            .arg(dir.join(out))
            .output()
            .unwrap())
    };
    run("6", "six");
    run("4", "four");
    ok(rig()
        .args(["run", "--quiet", "--trials", "6", "--resume"])
        .arg(dir.join("four"))
        .output()
        .unwrap());
    let six = std::fs::read_to_string(dir.join("six/returns.csv")).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.join("four/returns.csv")).unwrap(),
        six
    );
    // Trials did end early: the simulated time is not a whole number of 10 s trials.
    let last = six.lines().last().unwrap().split(',').nth(2).unwrap();
    assert_ne!(last.parse::<f64>().unwrap(), 60.0, "{six}");
}

#[test]
fn bad_resumes_are_one_line_errors() {
    let dir = tmp("bad");
    let pendulum = dir.join("pendulum");
    ok(rig()
        .args(["run", "--trials", "3", "--quiet", "--out"])
        .arg(&pendulum)
        .output()
        .unwrap());
    let arm = dir.join("arm");
    ok(rig()
        .args([
            "run",
            "--system",
            "arm-vertical",
            "--trials",
            "3",
            "--quiet",
            "--out",
        ])
        .arg(&arm)
        .output()
        .unwrap());
    let resume = |extra: &[&str]| {
        let out = rig()
            .args(["run", "--quiet", "--trials", "6"])
            .args(extra)
            .arg("--resume")
            .arg(&pendulum)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{extra:?} must fail");
        let err = stderr(&out);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!err.contains("panicked"), "{err}");
        err
    };
    let ckpt = pendulum.join("checkpoints/trial-000003.ckpt");
    let good = std::fs::read(&ckpt).unwrap();

    // A simulated run does not continue against a driver (checked before waiting for one).
    let err = resume(&[
        "--plant",
        "external",
        "--driver",
        "absent",
        "--driver-timeout",
        "1",
    ]);
    assert!(
        err.contains("was run with the simulated plant") && err.contains("--plant external"),
        "{err}"
    );

    let err = resume(&["--seed", "2"]);
    assert!(
        err.contains("--seed") && err.contains("config.toml"),
        "{err}"
    );

    // A checkpoint of another system in its place.
    std::fs::copy(arm.join("checkpoints/trial-000003.ckpt"), &ckpt).unwrap();
    let err = resume(&[]);
    assert!(
        err.contains("trial-000003.ckpt") && err.contains("from system arm-vertical"),
        "{err}"
    );

    // A corrupt checkpoint.
    let mut bad = good.clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 0x40;
    std::fs::write(&ckpt, &bad).unwrap();
    let err = resume(&[]);
    assert!(
        err.contains("trial-000003.ckpt") && err.contains("corrupt"),
        "{err}"
    );

    // A checkpoint of a format this rig does not know.
    let mut newer = good.clone();
    newer[8] = 9;
    std::fs::write(&ckpt, &newer).unwrap();
    let err = resume(&[]);
    assert!(err.contains("version 9"), "{err}");

    // Not a run directory.
    let out = rig()
        .args(["run", "--quiet", "--resume"])
        .arg(dir.join("nothing"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("config.toml"), "{}", stderr(&out));

    // With the good checkpoint back, it resumes.
    std::fs::write(&ckpt, &good).unwrap();
    ok(rig()
        .args(["run", "--quiet", "--trials", "6", "--resume"])
        .arg(&pendulum)
        .output()
        .unwrap());
    assert_eq!(lines(&pendulum.join("returns.csv")), 7);
}

/// Per sample `seq`: a numeric field of the JSON messages on `topic`.
fn field(msgs: &Messages, topic: &str, key: &str) -> BTreeMap<u64, f64> {
    msgs[topic]
        .iter()
        .map(|(_, _, data)| {
            let v: serde_json::Value = serde_json::from_slice(data).unwrap();
            (
                v["seq"].as_u64().unwrap(),
                v[key].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect()
}

/// A realtime run at 3 × real time (10 ms periods) into `dir` whose `role` process is
/// killed `after_ms` after the third trial started; asserts that `rig run` names it.
/// Returns the time of the death on the plant's clock.
fn realtime_run_killed(dir: &Path, role: &str, after_ms: u64) -> u64 {
    let sup = rig()
        .args([
            "run", "--timing", "realtime", "--speed", "3", "--trials", "400",
        ])
        .args(["--eval-every", "0", "--quiet", "--out"])
        .arg(dir)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_rows(dir, 3);
    std::thread::sleep(Duration::from_millis(after_ms));
    let dead_ns = kill_role(&sup, role);
    let died = sup.wait_with_output().unwrap();
    let err = stderr(&died);
    assert!(!died.status.success(), "{role}");
    assert!(
        err.contains(&format!("the {role} process exited (signal: 9")),
        "{err}"
    );
    dead_ns
}

/// The plant's own record says when the last action arrived (`t_action_ns`), so the
/// bound is exact: a watchdog that tripped one period later fails it (sample j + 3 still
/// holds the last action).
#[test]
fn a_process_killed_in_realtime_leaves_the_plant_in_the_safe_action_within_two_periods() {
    // 3 × real time: 10 ms periods.
    let period_ns = 10e6;
    for (i, role) in ["agent", "observer"].into_iter().enumerate() {
        let dir = tmp(&format!("realtime-{role}"));
        // Mid-trial, at a different moment for each role.
        let dead_ns = realtime_run_killed(&dir, role, 400 + 300 * i as u64);

        let msgs = recording(&dir.join("run.mcap"));
        let sampled = field(&msgs, "/timing/plant/measurement", "t_sample_ns");
        let applied = field(&msgs, "/plant/measurement", "u_applied_0");
        let interval_of = |t: f64| {
            *sampled
                .iter()
                .filter(|(_, t_k)| **t_k <= t)
                .map(|(k, _)| k)
                .max()
                .unwrap()
        };
        // The last action reached the plant within interval [t_j, t_{j+1}): sample j + 1
        // is the last whose `t_action_ns` is set.
        let arrived = field(&msgs, "/timing/plant/measurement", "t_action_ns");
        let j = arrived
            .iter()
            .filter(|(_, t)| **t > 0.0)
            .map(|(k, _)| k)
            .max()
            .unwrap()
            - 1;
        assert!(
            (sampled[&j]..sampled[&(j + 1)]).contains(&arrived[&(j + 1)]),
            "{role}: t_action_ns of sample {} is in the interval before it",
            j + 1
        );
        assert!(
            (j.saturating_sub(5)..=j + 1).any(|k| applied.get(&k).is_some_and(|u| *u != 0.0)),
            "{role}: actions were being applied before the kill"
        );
        // It came from a process alive then: no arrival after the interval of the
        // death, d, but the one the agent may have sent in it (if the observer died, the
        // agent answers its last estimate).
        let d = interval_of(dead_ns as f64);
        assert!(
            j <= d + 1,
            "{role}: an action arrived in interval {j}, after the death in {d}"
        );
        // Interval j + 1 has no action: from t_{j+2} on the plant applies zero, and
        // sample j + 3 reports it (applied over [t_{j+2}, t_{j+3})).
        let safe: Vec<u64> = applied.range(j + 3..).map(|(&k, _)| k).collect();
        assert!(
            !safe.is_empty(),
            "{role}: the recording must show the plant after the death (last action in interval {j}, last sample {:?})",
            applied.keys().max()
        );
        for k in safe {
            assert_eq!(
                applied[&k],
                0.0,
                "{role}: sample {k} (last action in interval {j}, death in {d}): applied {:?}",
                applied.range(j.saturating_sub(2)..=k).collect::<Vec<_>>()
            );
        }
        // On the plant's clock: zero from t_{j+2}, at most two periods after the last
        // action arrived (at or after t_j).
        let (t_j, t_safe) = (sampled[&j], sampled[&(j + 2)]);
        assert!(
            t_safe - t_j <= 2.5 * period_ns,
            "{role}: safe action {} ms after the start of the last action's interval",
            (t_safe - t_j) * 1e-6
        );
        resume_two_more(&dir);
    }
}

/// Resumes the run in `dir` for two more trials than it completed (lockstep), and checks
/// that the completed rows stayed as they were.
fn resume_two_more(dir: &Path) {
    let before = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    let done = before.lines().count() - 1;
    let out = rig()
        .args([
            "run",
            "--quiet",
            "--trials",
            &(done + 2).to_string(),
            "--resume",
        ])
        .arg(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let after = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    assert!(after.starts_with(&before), "{after}");
    assert_eq!(after.lines().count(), done + 3);
    let m = recording(&dir.join("run.mcap"));
    let rows = field(&m, "/plant/measurement", "trial");
    assert_eq!(
        rows.values().fold(0.0, |a: f64, &b| a.max(b)),
        (done + 2) as f64
    );
}

#[test]
fn a_plant_killed_in_realtime_is_named_and_the_run_resumes() {
    let dir = tmp("realtime-plant");
    realtime_run_killed(&dir, "plant", 500);
    assert!(!recording(&dir.join("run.mcap")).is_empty());
    resume_two_more(&dir);
}
