//! `rig run` reproduces `rig learn`: three processes over iceoryx2 give the in-process
//! numbers byte for byte, in every timing, with delays, observers and finite horizons.

use std::path::{Path, PathBuf};

mod common;
use common::{field, messages, ok, pipelined, rig};

fn tmp(name: &str) -> PathBuf {
    common::tmp("run", name)
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

/// Where the processes run changes nothing in what they compute: every `--cpus` layout
/// gives `rig learn`'s bytes (on a machine of one CPU the layouts that set one apart are
/// refused with a one-line error instead).
#[test]
fn every_cpu_layout_reproduces_the_in_process_run() {
    let dir = tmp("cpus");
    let online = std::thread::available_parallelism().map_or(1, |n| n.get());
    for layout in ["shared", "plant-alone", "recorder-alone"] {
        let args = [
            "--cpus", layout, "--trials", "6", "--seed", "5", "--quiet", "--out",
        ];
        if online < 2 && layout != "shared" {
            run_error(&dir, &args[..2], "at least two CPUs");
            continue;
        }
        let ran = learn_and_run_as(&dir, &format!("-{layout}"), &args[2..], &args[..2]);
        assert_eq!(ran.lines().count(), 7, "{layout}");
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
        // Wall-clock stamps and the latency taken of them differ by nature.
        if topic.starts_with("/timing") || topic == "/latency" {
            assert_eq!(msgs.len(), b[topic].len(), "{topic}");
            continue;
        }
        assert_eq!(
            msgs, &b[topic],
            "{topic} differs between two identical runs"
        );
        compared += msgs.len();
    }
    // 6 learning + 2 greedy trials of 101 samples, plus the shutdown, on three topics;
    // a row of returns.csv per learning trial; a picture of the system per sample.
    assert_eq!(compared, 3 * (8 * 101 + 1) + 6 + 8 * 101);
    assert_eq!(a["/returns"].len(), 6);
    assert_eq!(a["/latency"].len(), 8 * 101 + 1);
    assert_ne!(
        a["/timing/plant/measurement"], b["/timing/plant/measurement"],
        "wall-clock stamps differ"
    );
}

/// Runs the experiment `args` (ending in `--out`) with `rig learn --runs 1` into
/// `dir/learn{tag}` and with `rig run` into `dir/run{tag}`, asserts that `runs.csv` and
/// `returns.csv` are byte-identical, and returns them.
fn learn_and_run(dir: &Path, tag: &str, args: &[&str]) -> String {
    learn_and_run_as(dir, tag, args, &[])
}

/// [`learn_and_run`], with `rig run` also given `run_only` (flags `rig learn` does not
/// take).
fn learn_and_run_as(dir: &Path, tag: &str, args: &[&str], run_only: &[&str]) -> String {
    ok(rig()
        .args(["learn", "--runs", "1"])
        .args(args)
        .arg(dir.join(format!("learn{tag}")))
        .output()
        .unwrap());
    ok(rig()
        .arg("run")
        .args(run_only)
        .args(args)
        .arg(dir.join(format!("run{tag}")))
        .output()
        .unwrap());
    let learned = std::fs::read_to_string(dir.join(format!("learn{tag}/runs.csv"))).unwrap();
    let ran = std::fs::read_to_string(dir.join(format!("run{tag}/returns.csv"))).unwrap();
    assert_eq!(learned, ran, "{args:?} {run_only:?}");
    ran
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

/// MLAC-FH with RBFs, 6 trials and 2 evaluations, quiet, and `--out` (its directory to
/// follow).
const MLAC_FH: [&str; 12] = [
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

#[test]
fn a_finite_horizon_run_is_the_same_in_both_drivers() {
    // τ_N(x_N) enters the returns of `rig run` as it does in `rig learn` (Eq. 4.1).
    let dir = tmp("fh");
    let ran = learn_and_run(&dir, "", &MLAC_FH);
    assert_eq!(ran.lines().count(), 7);
}

/// A task file (examples/tasks/pendulum-balance.toml: three start states, an operating
/// range, terminal weights of its own) runs the same in both drivers; the run's
/// config.toml carries it, so the processes and a resume need no other file.
#[test]
fn a_task_file_runs_the_same_in_both_drivers() {
    let dir = tmp("task");
    let task =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/tasks/pendulum-balance.toml");
    let task = task.to_str().unwrap();
    let args = [["--task", task].as_slice(), &MLAC_FH].concat();
    let ran = learn_and_run(&dir, "", &args);
    assert_eq!(ran.lines().count(), 7);
    let config = std::fs::read_to_string(dir.join("run/config.toml")).unwrap();
    assert!(
        config.contains("[task]\nname = \"pendulum-balance\""),
        "{config}"
    );
    // The same file without its terminal weights gives other returns: τ_N uses them.
    let text = std::fs::read_to_string(task).unwrap();
    let plain = dir.join("plain.toml");
    std::fs::write(&plain, text.replace("terminal_weights = [50.0, 1.0]\n", "")).unwrap();
    let mut args = args;
    args[1] = plain.to_str().unwrap();
    assert_ne!(learn_and_run(&dir, "-plain", &args), ran);
}

/// A task with reward terms beyond the quadratic form, a goal that ends trials and start
/// states drawn from the run seed (examples/tasks/pendulum-reach.toml, its goal moved to
/// where some drawn starts lie) runs the same in both drivers, for VGBP (whose action
/// solves Eq. 6.10 with the absolute action cost) and MLAC; trials end early at the goal;
/// another seed draws other starts.
#[test]
fn a_goal_task_with_drawn_starts_runs_the_same_in_both_drivers() {
    let dir = tmp("reach");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/tasks/pendulum-reach.toml"),
    )
    .unwrap();
    let near = "low = [-0.1, -0.5]\nhigh = [0.1, 0.5]";
    assert!(text.contains(near));
    let task = dir.join("reach.toml");
    std::fs::write(
        &task,
        text.replace(near, "low = [-inf, 0.3]\nhigh = [inf, inf]"),
    )
    .unwrap();
    let task = task.to_str().unwrap();
    for (tag, learner) in [("vgbp", ["vgbp", "lstd"]), ("mlac", ["mlac", "llr"])] {
        // MLAC_FH's 6 trials, 2 evaluations, quiet, `--out`.
        let args = [
            ["--task", task, "--algo", learner[0], "--approx", learner[1]].as_slice(),
            &MLAC_FH[6..],
        ]
        .concat();
        let ran = learn_and_run(&dir, tag, &args);
        let t: Vec<f64> = ran
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
            .collect();
        assert_eq!(t.len(), 6);
        let early = std::iter::once(0.0).chain(t.iter().copied()).zip(&t);
        assert!(
            early.filter(|(a, b)| *b - a < 4.0 - 1e-9).count() > 0,
            "{tag}: {ran}"
        );
        let mut seeded = args.clone();
        seeded.splice(0..0, ["--seed", "2"]);
        assert_ne!(
            learn_and_run(&dir, &format!("{tag}-seed2"), &seeded),
            ran,
            "{tag}"
        );
    }
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
