//! `rig run` with real processes: plant, observer and agent over iceoryx2.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{children_of, ok, rig, wait_for_lines};

fn tmp(name: &str) -> PathBuf {
    common::tmp("run", name)
}

/// Predictive timing, from a recording: the action the plant announces at sample k
/// (`u_next`, not all zero) is the one it applies over the interval after it (as the
/// plant saturates it, to the pendulum's ±3 V). Returns how many consecutive sample pairs
/// were checked.
fn pipelined(mcap_path: &Path) -> usize {
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

/// Messages per topic: (log time, data) in order.
fn messages(mcap_path: &Path) -> BTreeMap<String, Vec<(u64, Vec<u8>)>> {
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

/// `rig run --quiet --out DIR/bad EXTRA…` fails with an error that names `says`; its
/// stderr.
fn run_error(dir: &std::path::Path, extra: &[&str], says: &str) -> String {
    let out = rig()
        .args(["run", "--quiet", "--out"])
        .arg(dir.join("bad"))
        .args(extra)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(err.contains(says), "{err}");
    err
}

#[test]
fn three_processes_reproduce_the_in_process_run_byte_for_byte() {
    let dir = tmp("ident");
    for (algo, approx) in [("mlac", "llr"), ("sac", "rbf")] {
        let args = [
            "--algo",
            algo,
            "--approx",
            approx,
            "--trials",
            "25",
            "--eval-every",
            "5",
            "--seed",
            "3",
            "--quiet",
            "--out",
        ];
        let ran = learn_and_run(&dir, &format!("-{algo}"), &args);
        assert_eq!(ran.lines().count(), 26);
    }
}

/// A sample-to-actuation delay (the delay studies') is deterministic in lockstep:
/// both drivers give the same bytes, and the delay changes what is learned.
#[test]
fn a_delay_is_the_same_in_both_drivers_and_changes_the_run() {
    let dir = tmp("delay");
    let args = |delay: &'static str| {
        [
            "--trials",
            "12",
            "--eval-every",
            "4",
            "--seed",
            "2",
            "--delay-ms",
            delay,
            "--quiet",
            "--out",
        ]
    };
    let delayed = learn_and_run(&dir, "-10ms", &args("10"));
    let none = learn_and_run(&dir, "-0ms", &args("0"));
    assert_ne!(delayed, none);
    let config = std::fs::read_to_string(dir.join("run-10ms/config.toml")).unwrap();
    assert!(config.contains("delay_ms = 10"), "{config}");
    // Out of range, and realtime: one-line errors.
    for (extra, says) in [
        (&["--delay-ms", "30"][..], "run.delay_ms"),
        (&["--delay-ms", "5", "--timing", "realtime"][..], "lockstep"),
    ] {
        assert_eq!(run_error(&dir, extra, says).trim().lines().count(), 1);
    }
}

#[test]
fn predictive_timing_and_recorded_delays_over_the_wire_reproduce_rig_learn() {
    // Predictive timing (`observer.mode`): the agent acts on the observer's prediction and
    // its action is applied at the next sample instant; `rig run` gives the numbers of
    // `rig learn`, byte for byte — with the learned and the known model, with a recorded
    // delay distribution, and in direct timing with that distribution.
    let dir = tmp("timing");
    let delays = dir.join("delays.csv");
    std::fs::write(&delays, "seq,delay_ms\n0,2.5\n1,\n2,11\n3,19.5\n").unwrap();
    let delays = delays.to_str().unwrap();
    let known = dir.join("known.toml");
    std::fs::write(&known, "[observer]\nmodel = \"known\"\n").unwrap();
    let known = known.to_str().unwrap();
    let base = [
        "--sensor",
        "angle",
        "--observer",
        "predictive",
        "--seed",
        "3",
        "--trials",
        "8",
        "--eval-every",
        "4",
    ];
    fn join<'b>(base: &[&'b str], extra: &[&'b str]) -> Vec<&'b str> {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a.extend(["--quiet", "--out"]);
        a
    }
    let with = |extra: &[&str]| -> Vec<String> {
        join(&base, extra).into_iter().map(String::from).collect()
    };
    let learn_and_run = |tag: &str, args: Vec<String>| {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        learn_and_run(&dir, tag, &args)
    };
    let p = &["--observer-mode", "predictive"][..];
    let pred = learn_and_run("-pred", with(p));
    let mut p10 = p.to_vec();
    p10.extend(["--delay-ms", "10"]);
    // A delay below Ts does not reach the plant in predictive timing.
    assert_eq!(learn_and_run("-pred-10ms", with(&p10)), pred);
    let mut pk = p.to_vec();
    pk.extend(["--config", known]);
    assert_ne!(learn_and_run("-pred-known", with(&pk)), pred);
    let direct = learn_and_run("-direct", with(&[]));
    assert_ne!(direct, pred);
    let recorded = learn_and_run("-from", with(&["--delay-from", delays]));
    assert_ne!(recorded, direct);
    let mut pf = p.to_vec();
    pf.extend(["--delay-from", delays]);
    assert_eq!(learn_and_run("-pred-from", with(&pf)), pred);
    // The recording says what was applied when: the delay of every interval (one of the
    // recorded values) and, in predictive timing, the action applied from each sample on.
    let msgs = messages(&dir.join("run-from/run.mcap"));
    let values =
        |topic: &str, key: &str| -> Vec<f64> { field(&msgs, topic, key).into_values().collect() };
    let drawn = values("/plant/measurement", "delay_s");
    assert!(
        drawn
            .iter()
            .all(|d| [0.0, 0.0025, 0.011, 0.0195].contains(d))
    );
    assert!(drawn.iter().filter(|d| **d > 0.0).count() > drawn.len() / 2);
    assert!(pipelined(&dir.join("run-pred/run.mcap")) > 0);
    // Exclusive flags and a bad file: one-line errors naming the key.
    for (extra, says) in [
        (
            &["--delay-from", delays, "--delay-ms", "3"][..],
            "--delay-ms",
        ),
        (&["--observer-mode", "predictive"][..], "observer.mode"),
        (&["--delay-from", "/nonexistent.csv"][..], "run.delay_from"),
    ] {
        run_error(&dir, extra, says);
    }
}

#[test]
fn a_second_run_records_the_same_messages_except_timing() {
    let dir = tmp("rerun");
    let args = ["--trials", "6", "--eval-every", "3", "--quiet", "--out"];
    ok(rig()
        .arg("run")
        .args(args)
        .arg(dir.join("a"))
        .output()
        .unwrap());
    ok(rig()
        .arg("run")
        .args(args)
        .arg(dir.join("b"))
        .output()
        .unwrap());
    let (a, b) = (
        messages(&dir.join("a/run.mcap")),
        messages(&dir.join("b/run.mcap")),
    );
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    let mut compared = 0;
    for (topic, msgs) in &a {
        if topic.starts_with("/timing") {
            assert_eq!(msgs.len(), b[topic].len(), "{topic}");
            continue;
        }
        assert_eq!(
            msgs, &b[topic],
            "{topic} differs between two identical runs"
        );
        compared += msgs.len();
    }
    // 6 learning + 2 greedy trials of 101 samples, plus the shutdown, on three topics.
    assert_eq!(compared, 3 * (8 * 101 + 1));
    assert_ne!(
        a["/timing/plant/measurement"], b["/timing/plant/measurement"],
        "wall-clock stamps differ"
    );
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

/// Runs the experiment `args` (ending in `--out`) with `rig learn --runs 1` into
/// `dir/learn{tag}` and with `rig run` into `dir/run{tag}`, asserts that `runs.csv` and
/// `returns.csv` are byte-identical, and returns them.
fn learn_and_run(dir: &Path, tag: &str, args: &[&str]) -> String {
    ok(rig()
        .args(["learn", "--runs", "1"])
        .args(args)
        .arg(dir.join(format!("learn{tag}")))
        .output()
        .unwrap());
    ok(rig()
        .arg("run")
        .args(args)
        .arg(dir.join(format!("run{tag}")))
        .output()
        .unwrap());
    let learned = std::fs::read_to_string(dir.join(format!("learn{tag}/runs.csv"))).unwrap();
    let ran = std::fs::read_to_string(dir.join(format!("run{tag}/returns.csv"))).unwrap();
    assert_eq!(learned, ran, "{args:?}");
    ran
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
fn bench_loop_measures_both_loops() {
    let dir = tmp("bench-loop");
    let out = ok(rig()
        .args(["bench-loop", "--samples", "1500", "--out"])
        .arg(&dir)
        .output()
        .unwrap());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("raw iceoryx2 round trip") && text.contains("lockstep step"),
        "{text}"
    );
    let csv = std::fs::read_to_string(dir.join("loop.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows[0], "measurement,n,p50_us,p90_us,p99_us,p999_us,max_us");
    assert!(
        rows[1].starts_with("raw_round_trip,1500,") && rows[2].starts_with("lockstep_step,"),
        "{csv}"
    );
    let p50: f64 = rows[2].split(',').nth(2).unwrap().parse().unwrap();
    assert!(p50 > 0.0 && p50.is_finite());
}

#[test]
fn realtime_runs_on_the_plants_clock_and_counts_misses() {
    let dir = tmp("realtime");
    // 3 trials of 101 samples at 20 × real time: 1.5 ms periods, ≈ 0.45 s.
    let t0 = Instant::now();
    let out = ok(rig()
        .args([
            "run",
            "--timing",
            "realtime",
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
}

#[test]
fn processes_notice_a_dead_peer_and_say_which() {
    let dir = tmp("dead-peer");
    let config = dir.join("config.toml");
    let preset = ok(rig().args(["config", "--trials", "400"]).output().unwrap());
    std::fs::write(&config, &preset.stdout).unwrap();
    let run_id = format!("deadpeer{}", std::process::id());
    let start = |exe: &str| {
        let log = std::fs::File::create(dir.join(format!("{exe}.log"))).unwrap();
        Command::new(env!("CARGO_BIN_EXE_rig").replace("/rig", &format!("/{exe}")))
            .args(["--run-id", &run_id, "--config"])
            .arg(&config)
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
fn trials_that_leave_the_operating_range_end_early_in_both_drivers() {
    // VGBP on the §6.4.2 manipulator leaves the ±1.2 rad range in its first trials.
    let dir = tmp("arm64");
    let args = [
        common::ARM64_VGBP_LSTD.as_slice(),
        &["--trials", "8", "--eval-every", "4", "--quiet", "--out"],
    ]
    .concat();
    let ran = learn_and_run(&dir, "", &args);
    let rows: Vec<Vec<f64>> = ran
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 8);
    // A terminated trial carries the −4·10⁴ penalty and lasts less than 10 s.
    let terminated = rows
        .iter()
        .zip(std::iter::once(0.0).chain(rows.iter().map(|r| r[2])))
        .filter(|(r, t_before)| r[3] < -4e4 && r[2] - t_before < 10.0 - 1e-9)
        .count();
    assert!(terminated > 0, "no trial left the range:\n{ran}");
    assert!(rows[7][2] < 80.0 - 1e-9, "{ran}");
    // Greedy evaluations (mean over the four start states) after trials 4 and 8.
    assert!(rows[3][4].is_finite() && rows[7][4].is_finite(), "{ran}");
}

/// Per sample `seq`: a field of a recorded JSON message on `topic`.
fn field(
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
fn a_finite_horizon_run_is_the_same_in_both_drivers() {
    // τ_N(x_N) enters the returns of `rig run` as it does in `rig learn` (Eq. 4.1).
    let dir = tmp("fh");
    let args = [
        "--horizon",
        "finite",
        "--algo",
        "mlac",
        "--approx",
        "rbf",
        "--trials",
        "6",
        "--eval-every",
        "3",
        "--quiet",
        "--out",
    ];
    let ran = learn_and_run(&dir, "", &args);
    assert_eq!(ran.lines().count(), 7);
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

#[test]
fn angle_sensing_and_observers_over_the_wire_reproduce_rig_learn() {
    // The plant process measures with the encoder (noise from the run seed's stream 2, as
    // in process), the observer process estimates the velocities: the returns are those
    // of `rig learn`, byte for byte — with and without sensor noise, in predictive timing
    // (whose repeated start sample is known, not measured), and with a finite horizon,
    // whose τ_N(x_N) is taken of the ground truth.
    let dir = tmp("angle");
    let noisy = dir.join("noisy.toml");
    std::fs::write(&noisy, "[observer]\nnoise_std = 0.003\n").unwrap();
    let known = dir.join("known.toml");
    std::fs::write(&known, "[observer]\nmodel = \"known\"\nnoise_std = 0.002\n").unwrap();
    let noisy = noisy.to_str().unwrap();
    let known = known.to_str().unwrap();
    let cases: [(&str, &[&str]); 6] = [
        ("fd", &["--observer", "finite-difference"]),
        ("pred", &["--observer", "predictive"]),
        (
            "fd-noise",
            &["--observer", "finite-difference", "--config", noisy],
        ),
        (
            "pred-noise",
            &["--observer", "predictive", "--config", noisy],
        ),
        (
            "pred-noise-timing",
            &[
                "--observer",
                "predictive",
                "--observer-mode",
                "predictive",
                "--config",
                noisy,
            ],
        ),
        (
            "known-fh",
            &[
                "--observer",
                "predictive",
                "--config",
                known,
                "--horizon",
                "finite",
                "--approx",
                "rbf",
            ],
        ),
    ];
    for (tag, observer) in cases {
        let mut args = vec!["--sensor", "angle", "--algo", "mlac", "--seed", "5"];
        args.extend_from_slice(observer);
        args.extend(["--trials", "8", "--eval-every", "4", "--quiet", "--out"]);
        let ran = learn_and_run(&dir, &format!("-{tag}"), &args);
        assert_eq!(ran.lines().count(), 9, "{tag}");
    }
    // Noise changes the numbers (the stream is used), and the recording shows what
    // crossed the wire: encoder angles with unmeasured (null) velocities, the observer's
    // finite estimates, and the ground truth on its own channel.
    let csv = |tag: &str| std::fs::read_to_string(dir.join(format!("run-{tag}/returns.csv")));
    assert_ne!(csv("pred").unwrap(), csv("pred-noise").unwrap());
    let msgs = messages(&dir.join("run-pred/run.mcap"));
    let json = |topic: &str| -> Vec<serde_json::Value> {
        msgs[topic]
            .iter()
            .map(|(_, d)| serde_json::from_slice(d).unwrap())
            .collect()
    };
    let (ys, xs, truth) = (
        json("/plant/measurement"),
        json("/observer/estimate"),
        json("/plant/truth"),
    );
    // Every sample but the shutdown has its truth, with the measurement's header.
    assert_eq!(truth.len() + 1, ys.len());
    let q = std::f64::consts::TAU / 4096.0;
    let mut differs = 0;
    for ((y, x), t) in ys.iter().zip(&xs).zip(&truth) {
        assert_eq!(y["seq"], t["seq"]);
        assert!(t["x_1"].as_f64().is_some_and(f64::is_finite), "{t}");
        assert!(x["x_1"].as_f64().is_some_and(f64::is_finite), "{x}");
        if y["flags"].as_u64().unwrap() & 1 != 0 {
            // A trial start: the state is known.
            assert_eq!(y["y_1"], t["x_1"]);
            continue;
        }
        assert!(
            y["y_1"].is_null(),
            "an encoder does not measure velocity: {y}"
        );
        let (angle, true_angle) = (y["y_0"].as_f64().unwrap(), t["x_0"].as_f64().unwrap());
        assert!(((angle / q) - (angle / q).round()).abs() < 1e-6, "{y}");
        assert!(plant::angle::wrap(angle - true_angle).abs() <= q / 2.0 + 1e-12);
        differs += usize::from(angle != true_angle);
    }
    assert!(differs > 100, "quantised angles differ from the true ones");
    // With full-state sensing there is no truth channel: the measurement is the truth.
    let full = messages(&dir.join("run-known-fh/run.mcap"));
    assert!(full.contains_key("/plant/truth"));
    let default = dir.join("full");
    ok(rig()
        .args(["run", "--trials", "1", "--quiet", "--out"])
        .arg(&default)
        .output()
        .unwrap());
    assert!(!messages(&default.join("run.mcap")).contains_key("/plant/truth"));
}

#[test]
fn a_run_with_an_observer_is_not_resumed() {
    let dir = tmp("resume-observer");
    ok(rig()
        .args([
            "run",
            "--sensor",
            "angle",
            "--observer",
            "predictive",
            "--trials",
            "2",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let out = rig()
        .args(["run", "--trials", "4", "--quiet", "--resume"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot resume")
            && err.contains("observer predictive")
            && err.lines().count() == 1,
        "{err}"
    );
    // Nothing was touched.
    assert_eq!(
        std::fs::read_to_string(dir.join("returns.csv"))
            .unwrap()
            .lines()
            .count(),
        3
    );
}

#[test]
fn latency_times_every_stage_of_every_cycle() {
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
    for stage in [
        "plant_to_observer",
        "observer_to_agent",
        "agent_to_plant",
        "slack",
    ] {
        assert!(summary.contains(stage), "{summary}");
    }
    assert!(summary.contains("deadline misses") && summary.contains("raw iceoryx2"));
    let csv = std::fs::read_to_string(dir.join("latency.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), 1 + 9 + 9 + 1, "{header:?}");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // Two whole trials (101 samples each), every sample a row.
    assert_eq!(rows.len(), 202);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let mut met = 0;
    for r in &rows {
        assert_eq!(r.len(), header.len());
        if r[col("deadline_miss")] == "1" {
            continue;
        }
        met += 1;
        let v = |name: &str| r[col(name)].parse::<u64>().unwrap();
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
