//! The processes of `rig run` under faults and in real time: a dead or stalled peer,
//! signals, two runs at once, the plant's clock and its watchdog.

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{children_of, field, messages, ok, rig, wait_for_lines};

fn tmp(name: &str) -> PathBuf {
    common::tmp("proc", name)
}

#[test]
fn two_runs_at_once_do_not_see_each_other() {
    let dir = tmp("parallel");
    let spawn = |seed: &str, name: &str| {
        rig()
            .args([
                "run",
                "--trials",
                "20",
                "--eval-every",
                "10",
                "--quiet",
                "--seed",
                seed,
                "--out",
            ])
            .arg(dir.join(name))
            .spawn()
            .unwrap()
    };
    let (mut a, mut b) = (spawn("1", "a"), spawn("2", "b"));
    assert!(a.wait().unwrap().success() && b.wait().unwrap().success());
    for (seed, name) in [("1", "a"), ("2", "b")] {
        ok(rig()
            .args([
                "learn",
                "--runs",
                "1",
                "--trials",
                "20",
                "--eval-every",
                "10",
                "--quiet",
                "--seed",
                seed,
                "--out",
            ])
            .arg(dir.join(format!("learn-{name}")))
            .output()
            .unwrap());
        let want = std::fs::read_to_string(dir.join(format!("learn-{name}/runs.csv"))).unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join(format!("{name}/returns.csv"))).unwrap(),
            want,
            "run {name}"
        );
    }
}

#[test]
fn after_kill_9_of_all_three_processes_the_next_run_just_works() {
    let dir = tmp("kill");
    let mut sup = rig()
        .args(["run", "--trials", "400", "--quiet", "--out"])
        .arg(dir.join("killed"))
        .spawn()
        .unwrap();
    // Wait until learning is under way.
    wait_for_lines(&dir.join("killed/returns.csv"), 4);
    let kids = children_of(sup.id());
    assert_eq!(kids.len(), 3, "plant, observer and agent");
    for pid in &kids {
        Command::new("kill")
            .args(["-9", &pid.to_string()])
            .status()
            .unwrap();
    }
    let status = sup.wait().unwrap();
    assert!(
        !status.success(),
        "rig run must fail when its processes die"
    );
    // The recording was finished: the official reader's crate reads it.
    assert!(!messages(&dir.join("killed/run.mcap")).is_empty());
    // And the next run starts and finishes without manual cleanup.
    ok(rig()
        .args(["run", "--trials", "5", "--quiet", "--out"])
        .arg(dir.join("next"))
        .output()
        .unwrap());
    assert_eq!(
        std::fs::read_to_string(dir.join("next/returns.csv"))
            .unwrap()
            .lines()
            .count(),
        6
    );
}

#[test]
fn bench_loop_measures_the_loop_against_one_process_and_the_transport() {
    // A short measurement with every waiting strategy the loop may use: each run's
    // returns equal the in-process ones (the command fails otherwise), and every
    // measurement is in loop.csv.
    for wait in [
        &["--wait", "block"][..],
        &["--wait", "yield"],
        &["--wait", "spin", "--wait-us", "50"],
    ] {
        let dir = tmp(&format!("bench-loop-{}", wait[1]));
        let out = ok(rig()
            .args([
                "bench-loop",
                "--trials",
                "4",
                "--repetitions",
                "2",
                "--samples",
                "300",
                "--quiet",
                "--out",
            ])
            .arg(&dir)
            .args(wait)
            .output()
            .unwrap());
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("three processes / one process: "), "{text}");
        assert!(text.contains("three processes placed --cpus "), "{text}");
        assert!(
            text.contains("byte for byte") && !text.contains("DID NOT"),
            "{text}"
        );
        let csv = std::fs::read_to_string(dir.join("loop.csv")).unwrap();
        for kind in ["in_process", "three_processes", "unrecorded"] {
            let rows: Vec<Vec<f64>> = csv
                .lines()
                .filter(|l| l.starts_with(&format!("{kind},")))
                .map(|l| l.split(',').skip(2).map(|v| v.parse().unwrap()).collect())
                .collect();
            assert_eq!(rows.len(), 2, "{kind}: {csv}");
            assert!(
                rows.iter().all(|r| r[0] > 0.0 && r[1] > 0.0),
                "{kind}: {csv}"
            );
        }
        for kind in [
            "lockstep_step,",
            "raw_round_trip_waiting,300,",
            "raw_round_trip_block,300,",
            "raw_round_trip_poll,300,",
        ] {
            let row = csv
                .lines()
                .find(|l| l.starts_with(kind))
                .unwrap_or_else(|| panic!("{kind}: {csv}"));
            let p50: f64 = row.split(',').nth(2).unwrap().parse().unwrap();
            assert!(p50 > 0.0 && p50.is_finite(), "{row}");
        }
    }
}

#[test]
fn realtime_runs_on_the_plants_clock_and_counts_misses() {
    let dir = tmp("realtime");
    // 3 trials of 101 samples at 20 × real time: 1.5 ms periods, ≈ 0.45 s (learning
    // across gaps: 1.5 ms is beyond a shared machine).
    let t0 = Instant::now();
    let out = ok(rig()
        .args([
            "run",
            "--timing",
            "realtime",
            "--gaps",
            "learn",
            "--speed",
            "20",
            "--trials",
            "3",
            "--eval-every",
            "0",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let wall = t0.elapsed();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("deadline misses:"), "{text}");
    assert!(
        wall >= Duration::from_millis(3 * 101 * 3 / 2),
        "the plant keeps real time: {wall:?}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("returns.csv"))
            .unwrap()
            .lines()
            .count(),
        4
    );
    let msgs = messages(&dir.join("run.mcap"));
    // Log time is the plant's monotonic sample time: increasing by about a period.
    let t: Vec<u64> = msgs["/plant/measurement"].iter().map(|m| m.0).collect();
    assert!(t.windows(2).all(|w| w[1] >= w[0]));
    let mean_gap = (t[t.len() - 2] - t[0]) as f64 / (t.len() - 2) as f64;
    assert!(
        (mean_gap - 1.5e6).abs() < 0.2e6,
        "mean sample period {mean_gap} ns"
    );
    let bad = rig()
        .args(["run", "--timing", "realtime", "--speed", "0"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    // Polling without end leaves no process woken: the realtime plant, which sleeps
    // until its sampling instant, would never see the action; refused in one line.
    let bad = rig()
        .args(["run", "--timing", "realtime", "--wait", "yield", "--out"])
        .arg(dir.join("yield"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("`--wait spin|yield` without `--wait-us`") && err.lines().count() == 1,
        "{err}"
    );
}

#[test]
fn processes_notice_a_dead_peer_and_say_which() {
    let dir = tmp("dead-peer");
    let config = dir.join("config.toml");
    let preset = ok(rig().args(["config", "--trials", "400"]).output().unwrap());
    std::fs::write(&config, &preset.stdout).unwrap();
    let run_id = format!("deadpeer{}", std::process::id());
    // Each node by hand: its settings name the run and its configuration.
    let settings = dir.join("node.toml");
    std::fs::write(
        &settings,
        format!("[node]\nrun_id = {run_id:?}\nconfig = {config:?}\n"),
    )
    .unwrap();
    let start = |exe: &str| {
        let log = std::fs::File::create(dir.join(format!("{exe}.log"))).unwrap();
        Command::new(env!("CARGO_BIN_EXE_rig").replace("/rig", &format!("/{exe}")))
            .arg("--node")
            .arg(&settings)
            .stderr(log)
            .spawn()
            .unwrap()
    };
    let (mut agent, mut observer, mut plant) = (start("agent"), start("observer"), start("plant"));
    std::thread::sleep(Duration::from_millis(300));
    assert!(plant.try_wait().unwrap().is_none(), "learning is under way");
    agent.kill().unwrap();
    agent.wait().unwrap();
    let t0 = Instant::now();
    for (name, child) in [("plant", &mut plant), ("observer", &mut observer)] {
        let status = child.wait().unwrap();
        assert!(!status.success(), "{name} must fail");
        let log = std::fs::read_to_string(dir.join(format!("{name}.log"))).unwrap();
        // The plant sees the agent die; the observer sees the agent or the plant stop.
        let who = if name == "plant" {
            "agent"
        } else {
            "of this run stopped"
        };
        assert!(
            log.contains(who) && log.contains("stopped"),
            "{name}: {log}"
        );
    }
    assert!(
        t0.elapsed() < Duration::from_secs(5),
        "noticed in {:?}",
        t0.elapsed()
    );
}

/// A node started by hand reads its settings file and holds the run's clock to the same
/// rules as `rig run`: an injected delay with an external driver is refused at once,
/// not after waiting for the driver; a key the file may not have is named.
#[test]
fn a_node_started_by_hand_checks_its_settings_as_rig_run_does() {
    let dir = tmp("by-hand");
    let config = dir.join("config.toml");
    let delayed = ok(rig().args(["config", "--delay-ms", "5"]).output().unwrap());
    std::fs::write(&config, &delayed.stdout).unwrap();
    let node = format!(
        "[node]\nrun_id = \"byhand{}\"\nconfig = {config:?}\n",
        std::process::id()
    );
    let plant = |settings: &str| {
        let file = dir.join("plant.toml");
        std::fs::write(&file, settings).unwrap();
        let t0 = Instant::now();
        let out = rig()
            .arg("plant")
            .arg("--node")
            .arg(&file)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{settings}");
        (
            String::from_utf8_lossy(&out.stderr).into_owned(),
            t0.elapsed(),
        )
    };
    let external = "[clock.external]\nid = \"pendulum\"\ntimeout = 20\nreset_timeout = 30\n";
    let (err, took) = plant(&format!("{node}{external}"));
    assert!(
        err.contains("apply in lockstep with the simulated plant only") && err.lines().count() == 1,
        "{err}"
    );
    assert!(took < Duration::from_secs(10), "refused after {took:?}");
    let (err, _) = plant(&format!("speed = 10\n{node}"));
    assert!(
        err.contains("plant.toml")
            && err.contains("unknown field `speed`")
            && err.lines().count() == 1,
        "{err}"
    );
}

#[test]
fn sigterm_stops_the_run_and_keeps_the_recording() {
    let dir = tmp("sigterm");
    let sup = rig()
        .args(["run", "--trials", "400", "--quiet", "--out"])
        .arg(&dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_lines(&dir.join("returns.csv"), 4);
    Command::new("kill")
        .args(["-TERM", &sup.id().to_string()])
        .status()
        .unwrap();
    let out = sup.wait_with_output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("interrupted"), "{err}");
    assert!(
        !messages(&dir.join("run.mcap")).is_empty(),
        "the recording was finished"
    );
    assert!(children_of(std::process::id()).iter().all(|&p| p != 0));
}

#[test]
fn a_stalled_agent_meets_the_watchdog_within_two_periods() {
    // Realtime at 5 × real time (6 ms periods); the agent is stopped (SIGSTOP) for about
    // 40 periods in the second trial, then continued.
    let dir = tmp("watchdog");
    let mut sup = rig()
        .args([
            "run",
            "--timing",
            "realtime",
            // The plant's watchdog is what is measured: the trial goes on through the
            // stall (the gap rule would cut it short, below).
            "--gaps",
            "learn",
            "--speed",
            "5",
            "--trials",
            "4",
            "--eval-every",
            "0",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .spawn()
        .unwrap();
    wait_for_lines(&dir.join("returns.csv"), 2);
    std::thread::sleep(Duration::from_millis(100));
    let agent = common::child_running(sup.id(), "agent");
    common::signal(agent, "-STOP");
    std::thread::sleep(Duration::from_millis(240));
    common::signal(agent, "-CONT");
    assert!(sup.wait().unwrap().success());
    let msgs = messages(&dir.join("run.mcap"));
    let sampled = field(&msgs, "/timing/plant/measurement", "t_sample_ns");
    let applied = field(&msgs, "/plant/measurement", "u_applied_0");
    let answered = field(&msgs, "/timing/agent/action", "t_publish_ns");
    // Sample k's action was on time if it was published before sample k + 1.
    let on_time = |k: u64| match (answered.get(&k), sampled.get(&(k + 1))) {
        (Some(a), Some(s)) => a < s,
        _ => false,
    };
    let seqs: Vec<u64> = sampled.keys().copied().collect();
    // The stall: the longest run of samples without a timely answer.
    let (mut best, mut start, mut len) = ((0, 0), 0, 0);
    for &k in &seqs {
        if on_time(k) {
            len = 0;
        } else {
            if len == 0 {
                start = k;
            }
            len += 1;
            if len > best.1 {
                best = (start, len);
            }
        }
    }
    let (first_late, late) = best;
    assert!(
        late >= 20,
        "the stall shows as {late} late samples from {first_late}"
    );
    // The last action arrived in the interval after sample L = first_late − 1; the next
    // interval had none, so from sample L + 2 on the plant applies zero: sample L + 3
    // reports it as applied over the interval before it.
    let l = first_late - 1;
    assert_ne!(applied[&(l + 1)], 0.0, "the last action was in effect");
    for k in l + 3..l + 15 {
        assert_eq!(
            applied[&k], 0.0,
            "sample {k}: the safe action (stall after sample {l})"
        );
    }
}

#[test]
fn a_plant_held_up_in_real_time_cuts_the_trial_short_and_runs_it_again() {
    // Realtime at real time (30 ms periods); the plant is stopped (SIGSTOP) for about
    // four periods in the second trial: the sample it then takes is late, a gap.
    let dir = tmp("held-plant");
    let sup = rig()
        .args([
            "run",
            "--timing",
            "realtime",
            "--trials",
            "3",
            "--eval-every",
            "0",
        ])
        .arg("--out")
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_lines(&dir.join("returns.csv"), 2);
    std::thread::sleep(Duration::from_millis(1000));
    let plant = common::child_running(sup.id(), "plant");
    common::signal(plant, "-STOP");
    std::thread::sleep(Duration::from_millis(120));
    common::signal(plant, "-CONT");
    let out = sup.wait_with_output().unwrap();
    assert!(out.status.success());
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    assert_eq!(returns.lines().count(), 4, "{returns}");
    let flagged = common::gaps::flagged_and_never_learned(&dir.join("run.mcap"), 30_000_000);
    common::gaps::counted(&String::from_utf8_lossy(&out.stdout), &dir, flagged);
}

#[test]
fn a_second_run_with_the_same_run_id_is_refused_and_the_first_goes_on() {
    let dir = tmp("same-id");
    let id = format!("same-{}", std::process::id());
    let mut first = rig()
        .args([
            "run", "--run-id", &id, "--trials", "150", "--quiet", "--out",
        ])
        .arg(dir.join("first"))
        .spawn()
        .unwrap();
    wait_for_lines(&dir.join("first/returns.csv"), 3);
    let second = rig()
        .args(["run", "--run-id", &id, "--trials", "5", "--quiet", "--out"])
        .arg(dir.join("second"))
        .output()
        .unwrap();
    assert!(!second.status.success());
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(
        err.contains("is in use") && err.trim().lines().count() == 1,
        "one line: {err}"
    );
    assert!(!dir.join("second/config.toml").exists(), "nothing written");
    assert!(
        first.wait().unwrap().success(),
        "the first run is undisturbed"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("first/returns.csv"))
            .unwrap()
            .lines()
            .count(),
        151
    );
}
