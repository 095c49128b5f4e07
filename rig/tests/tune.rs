//! `rig tune` end to end, with Optuna: a small study in the embedded storage, continued
//! by the same command; Ctrl-C and a killed worker; two machines sharing one study
//! through a real PostgreSQL server (`RIG_TEST_POSTGRES`, a URL; `.ci/run` starts one);
//! bad space files.

mod common;

use std::collections::BTreeSet;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{ok, rig, tmp};

/// A Python with Optuna and the study's other packages (`tune/requirements.txt`), or
/// `None` (and why).
fn python() -> Option<String> {
    common::python::with("rigkit, optuna, matplotlib, tomli_w")
}

/// `rig tune ARGS` in `dir`.
fn tune(python: &str, dir: &Path, args: &[&str]) -> Command {
    let mut cmd = rig();
    cmd.arg("tune")
        .args(args)
        .current_dir(dir)
        .env("RIG_PYTHON", python)
        .env("PYTHONPATH", common::python::path());
    cmd
}

const SPACE: &str = r#"
[param."actor.alpha"]
low = 0.01
high = 0.2
log = true

[param."learning.gamma"]
choices = [0.95, 0.97]
"#;

/// Short runs: 30 learning trials (3 greedy evaluations) on one seed.
const SHORT: [&str; 6] = ["--space", "space.toml", "--trials", "30", "--seeds", "1"];

fn text(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The trials of a report's table: number and state.
fn states(out: &Path) -> Vec<(u32, String)> {
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    let table = report.split("## Trials").nth(1).expect("a table of trials");
    table
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            Some((cells.get(1)?.parse().ok()?, cells.get(2)?.to_string()))
        })
        .collect()
}

/// The trials this machine ran: one folder each.
fn folders(out: &Path) -> BTreeSet<u32> {
    std::fs::read_dir(out.join("trials"))
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_str().unwrap().parse().unwrap())
                .collect()
        })
        .unwrap_or_default()
}

fn finished(states: &[(u32, String)]) -> usize {
    states
        .iter()
        .filter(|(_, s)| s == "complete" || s == "pruned")
        .count()
}

#[test]
fn a_small_study_writes_the_best_configuration_and_the_same_command_continues_it() {
    let Some(py) = python() else { return };
    let dir = tmp("tune", "small");
    std::fs::write(dir.join("space.toml"), SPACE).unwrap();
    let args = [
        &SHORT[..],
        &["--n-trials", "4", "--workers", "2", "--check-seeds", "2"],
    ]
    .concat();
    let out = ok(tune(&py, &dir, &args).output().unwrap());
    let stdout = text(&out);
    assert!(stdout.contains("best: trial"), "{stdout}");
    assert!(stdout.contains("On the check's 2 fresh seeds"), "{stdout}");
    let study = dir.join("out/tune");
    let trials = states(&study);
    assert!(finished(&trials) >= 4, "{trials:?}");
    let numbers: BTreeSet<u32> = trials.iter().map(|t| t.0).collect();
    assert_eq!(numbers.len(), trials.len(), "a trial listed twice");
    assert_eq!(
        folders(&study),
        numbers,
        "each trial ran once, in a folder of its own"
    );
    let report = std::fs::read_to_string(study.join("report.md")).unwrap();
    for part in [
        "## Check on fresh seeds",
        "| best |",
        "| preset |",
        "plots/check.png",
    ] {
        assert!(report.contains(part), "{part} missing from the report");
    }
    assert!(study.join("plots/check.png").is_file());

    // The best configuration is one `rig learn --config` takes, with values in the space.
    let best = std::fs::read_to_string(study.join("best.toml")).unwrap();
    let alpha: f64 = best
        .split("[actor]")
        .nth(1)
        .and_then(|s| s.lines().find(|l| l.starts_with("alpha = ")))
        .and_then(|l| l["alpha = ".len()..].parse().ok())
        .unwrap();
    assert!((0.01..=0.2).contains(&alpha), "actor.alpha {alpha}");
    let learn = dir.join("learn");
    ok(rig()
        .args(["learn", "--config"])
        .arg(study.join("best.toml"))
        .args(["--runs", "1", "--trials", "10", "--quiet", "--out"])
        .arg(&learn)
        .output()
        .unwrap());

    // The same command again: nothing new to run. More trials: the same study goes on.
    let again = text(&ok(tune(&py, &dir, &args).output().unwrap()));
    assert!(
        again.contains(&format!("{} of 4 trials finished", finished(&trials))),
        "{again}"
    );
    assert_eq!(folders(&study), numbers, "no trial ran again");
    let more = [&SHORT[..], &["--n-trials", "6", "--check-seeds", "0"]].concat();
    ok(tune(&py, &dir, &more).output().unwrap());
    let trials = states(&study);
    assert!(finished(&trials) >= 6, "{trials:?}");
    assert!(folders(&study).is_superset(&numbers));

    // Another study (another space) into the same folder would number its trials from 0
    // again, over the first's: refused, naming the study the folder holds.
    let ran = folders(&study);
    std::fs::write(
        dir.join("other.toml"),
        SPACE.replace("0.95, 0.97", "0.9, 0.99"),
    )
    .unwrap();
    let other = [
        &["--space", "other.toml"],
        &SHORT[2..],
        &["--n-trials", "2"],
    ]
    .concat();
    let out = tune(&py, &dir, &other).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("holds the trials of study rig-tune-")
            && stderr.contains("--study rig-tune-"),
        "{stderr}"
    );
    assert_eq!(folders(&study), ran, "no trial of the other study ran");
}

/// Starts `rig tune` in a process group of its own (as a shell starts a command).
fn start(py: &str, dir: &Path, args: &[&str]) -> std::process::Child {
    tune(py, dir, args)
        .process_group(0)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until trial `n`'s first run has written a row.
fn running(study: &Path, n: u32) {
    let rows = study.join(format!("trials/{n:05}/seed-1/runs.csv"));
    let t0 = Instant::now();
    while std::fs::read_to_string(&rows)
        .unwrap_or_default()
        .lines()
        .count()
        < 2
    {
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "trial {n} did not start"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn signal_group(pid: u32, signal: &str) {
    Command::new("kill")
        .args([signal, "--", &format!("-{pid}")])
        .status()
        .unwrap();
}

#[test]
fn ctrl_c_stops_cleanly_a_killed_worker_s_trial_fails_and_the_study_goes_on() {
    let Some(py) = python() else { return };
    let dir = tmp("tune", "interrupted");
    std::fs::write(dir.join("space.toml"), SPACE).unwrap();
    // Long runs, so that each is caught under way.
    let args = [
        "--space",
        "space.toml",
        "--trials",
        "4000",
        "--seeds",
        "1",
        "--n-trials",
        "2",
        "--check-seeds",
        "0",
        "--heartbeat",
        "1",
        "--pruner",
        "none",
    ];
    let study = dir.join("out/tune");

    let child = start(&py, &dir, &args);
    running(&study, 0);
    signal_group(child.id(), "-INT");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("the same command continues the study"),
        "{stderr}"
    );

    let child = start(&py, &dir, &args);
    running(&study, 1);
    signal_group(child.id(), "-KILL");
    let _ = child.wait_with_output();
    // The killed worker's heartbeat is 1 s; its trial is stale after 2 s.
    std::thread::sleep(Duration::from_secs(3));

    ok(tune(&py, &dir, &args).output().unwrap());
    let trials = states(&study);
    assert_eq!(
        trials[0],
        (0, "fail".to_string()),
        "the interrupted trial: {trials:?}"
    );
    assert_eq!(
        trials[1],
        (1, "fail".to_string()),
        "the killed worker's trial: {trials:?}"
    );
    assert!(finished(&trials) >= 2, "{trials:?}");
}

#[test]
fn two_machines_finish_one_study_in_postgresql_with_no_trial_run_twice() {
    let Some(py) = python() else { return };
    let Ok(url) = std::env::var("RIG_TEST_POSTGRES") else {
        println!(
            "skipped: RIG_TEST_POSTGRES is not set (a postgresql:// URL; .ci/run starts a server)"
        );
        return;
    };
    let dir = tmp("tune", "postgres");
    std::fs::write(dir.join("space.toml"), SPACE).unwrap();
    let name = format!("rig-test-{}-{}", std::process::id(), wire::now_ns());
    let machine = |out: &str| {
        let args = [
            &SHORT[..],
            &[
                "--n-trials",
                "6",
                "--check-seeds",
                "0",
                "--storage",
                &url,
                "--study",
                &name,
                "--out",
                out,
            ],
        ]
        .concat();
        tune(&py, &dir, &args).spawn().unwrap()
    };
    let (a, b) = (machine("a"), machine("b"));
    for child in [a, b] {
        ok(child.wait_with_output().unwrap());
    }
    let trials = states(&dir.join("a"));
    assert!(finished(&trials) >= 6, "{trials:?}");
    let (on_a, on_b) = (folders(&dir.join("a")), folders(&dir.join("b")));
    assert!(
        !on_a.is_empty() && !on_b.is_empty(),
        "both machines ran trials: {on_a:?} {on_b:?}"
    );
    assert!(
        on_a.is_disjoint(&on_b),
        "a trial ran on both: {on_a:?} {on_b:?}"
    );
    let all: BTreeSet<u32> = trials.iter().map(|t| t.0).collect();
    assert_eq!(
        &on_a | &on_b,
        all,
        "every trial of the study ran on one machine"
    );
    let configs: BTreeSet<String> = all
        .iter()
        .map(|n| {
            let on = if on_a.contains(n) { "a" } else { "b" };
            std::fs::read_to_string(dir.join(format!("{on}/trials/{n:05}/config.toml"))).unwrap()
        })
        .collect();
    assert_eq!(
        configs.len(),
        all.len(),
        "two trials ran the same configuration"
    );
}

#[test]
fn a_study_against_lockstep_drivers_starts_one_per_worker_and_keeps_the_returns_only() {
    let Some(py) = python() else { return };
    let dir = tmp("tune", "external");
    std::fs::write(dir.join("space.toml"), SPACE).unwrap();
    let driver = format!(
        "{} sim-driver --clock lockstep --driver-id {{id}}",
        env!("CARGO_BIN_EXE_rig")
    );
    let args = [
        &SHORT[..],
        &[
            "--n-trials",
            "2",
            "--check-seeds",
            "1",
            "--driver-cmd",
            &driver,
        ],
    ]
    .concat();
    let stdout = text(&ok(tune(&py, &dir, &args).output().unwrap()));
    assert!(stdout.contains("On the check's 1 fresh seeds"), "{stdout}");
    let study = dir.join("out/tune");
    let trials = states(&study);
    assert!(finished(&trials) >= 2, "{trials:?}");
    for n in folders(&study) {
        let run = study.join(format!("trials/{n:05}/seed-1"));
        let rows = std::fs::read_to_string(run.join("returns.csv")).unwrap();
        assert_eq!(
            rows.lines().count(),
            31,
            "trial {n}: a row per learning trial"
        );
        assert!(
            !run.join("run.mcap").exists(),
            "trial {n}: the recording is not kept"
        );
    }
    let logs = std::fs::read_dir(study.join("drivers")).unwrap().count();
    assert_eq!(logs, 1, "one driver for the one worker");
    let left = Command::new("pgrep")
        .args(["-f", "sim-driver --clock lockstep --driver-id tune-"])
        .output()
        .unwrap();
    assert!(
        left.stdout.is_empty(),
        "drivers left running: {}",
        String::from_utf8_lossy(&left.stdout)
    );
}

/// A driver command that exits (a misspelt flag) fails its trial at once with the
/// driver's own last words, not after the rig's wait for a driver; the worker stops
/// after `--max-failures` such trials.
#[test]
fn a_driver_that_exits_fails_its_trial_at_once_naming_why() {
    let Some(py) = python() else { return };
    let dir = tmp("tune", "driver-exits");
    std::fs::write(dir.join("space.toml"), SPACE).unwrap();
    let driver = format!("{py} -c \"import sys; sys.exit('no simulator for {{id}}')\"");
    let args = [
        &SHORT[..],
        &[
            "--n-trials",
            "3",
            "--max-failures",
            "2",
            "--driver-cmd",
            &driver,
        ],
    ]
    .concat();
    let started = Instant::now();
    let out = tune(&py, &dir, &args).output().unwrap();
    let (stdout, stderr) = (text(&out), String::from_utf8_lossy(&out.stderr));
    assert!(
        started.elapsed() < Duration::from_secs(30),
        "the trials waited for a driver that had exited: {:?}",
        started.elapsed()
    );
    let failed = stdout
        .lines()
        .filter(|l| l.contains(": failed: the driver"))
        .count();
    assert_eq!(failed, 2, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("exited with 1: no simulator for tune-"),
        "{stdout}"
    );
}

#[test]
fn bad_space_files_are_one_line_errors_naming_file_and_key() {
    let Some(py) = python() else { return };
    let dir = tmp("tune", "bad");
    let cases: [(&str, &str); 10] = [
        (
            "[param.\"actor.alfa\"]\nlow = 0.1\nhigh = 1.0\n",
            "param \"actor.alfa\": not a configuration key of this learner (did you mean \"actor.alpha\"?)",
        ),
        (
            "[param.\"actor.alpha\"]\nlow = 0.5\nhigh = 0.1\n",
            "param \"actor.alpha\": low (0.5) must be below high (0.1)",
        ),
        (
            "[param.\"actor.alpha\"]\nlow = 0.0\nhigh = 0.1\nlog = true\n",
            "param \"actor.alpha\": a log scale needs low > 0",
        ),
        (
            "[param.\"actor.alpha\"]\nlow = 0.1\nhigh = 0.2\nscale = \"log\"\n",
            "param \"actor.alpha\": unknown field \"scale\"",
        ),
        (
            "[param.\"learning.gamma\"]\nchoices = []\n",
            "param \"learning.gamma\": choices must be a non-empty list",
        ),
        (
            "[param.\"actor.memory\"]\nlow = 10.5\nhigh = 100\n",
            "param \"actor.memory\": an integer key needs integer bounds",
        ),
        (
            "[param.\"actor.eviction\"]\nlow = 1\nhigh = 2\n",
            "param \"actor.eviction\": the preset's value 'redundant' is not a number",
        ),
        (
            "[param.\"actor.alpha\"]\nlow = 1.0\nhigh = 1000.0\n",
            "param \"actor.alpha\": the rig refuses 1000.0",
        ),
        ("[param\n", "not TOML"),
        ("", "no [param.\"KEY\"] table"),
    ];
    for (i, (space, fragment)) in cases.iter().enumerate() {
        let file = format!("space-{i}.toml");
        std::fs::write(dir.join(&file), space).unwrap();
        let out = tune(&py, &dir, &["--space", &file, "--trials", "30"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{file}: {stderr}");
        assert_eq!(
            stderr.trim().lines().count(),
            1,
            "{file}: one line: {stderr}"
        );
        assert!(stderr.starts_with(&format!("error: {file}: ")), "{stderr}");
        assert!(
            stderr.contains(fragment),
            "{file}: {fragment} not in: {stderr}"
        );
    }
    assert!(!dir.join("out/tune/trials").exists(), "nothing ran");
    let out = tune(&py, &dir, &["--trials", "30"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--space FILE is needed"));
}

#[test]
fn every_learner_s_preset_gives_a_starting_space_the_rig_accepts() {
    let Some(py) = python() else { return };
    let dir = tmp("tune", "space-for");
    for (algo, approx) in [
        ("sac", "tiles"),
        ("mlac", "llr"),
        ("rmac", "rbf"),
        ("vgbp", "lstd"),
        ("sarsa", "rbf"),
    ] {
        let out = ok(tune(&py, &dir, &["--space-for", algo, "--approx", approx])
            .output()
            .unwrap());
        let space = text(&out);
        assert!(
            space.contains("[param.\"learning.gamma\"]"),
            "{algo}: {space}"
        );
        assert!(space.contains("# preset: "), "{algo}: {space}");
    }
}
