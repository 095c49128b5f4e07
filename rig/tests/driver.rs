//! External drivers with real processes: the Python example driver
//! (`examples/python_driver/`, official iceoryx2 bindings) against `rig check-driver` and
//! `rig run --plant external`.
//!
//! The Python tests need `iceoryx2==0.10.0` importable by `$RIG_PYTHON` (default
//! `python3`); without it they print why and pass — CI installs it, so they run there.

use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::drivers::{Driver, Kind, drivers, python};
use common::rig;

fn tmp(name: &str) -> PathBuf {
    common::tmp("driver", name)
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `rig check-driver` against driver `id`, with a shortened rate measurement (3 s, about
/// 200 samples: the p99 is the second-worst lateness, so one stall of the shared machine
/// does not decide it) and a jitter bound for a shared CI machine (the default, 10 %, is
/// for hardware).
fn check_driver(id: &str) -> Output {
    rig()
        .args([
            "check-driver",
            "--driver",
            id,
            "--rate-seconds",
            "3",
            "--max-jitter",
            "0.5",
            "--driver-timeout",
            "20",
        ])
        .output()
        .unwrap()
}

/// `rig run --plant external --driver ID` with `extra` flags, writing to `dir`.
/// `rig run --plant external` against driver `id`. The drivers here run at 10 × real
/// time on a machine shared with other tests, where the loop cannot keep 3 ms periods:
/// the runs learn across gaps (`--gaps learn`, the behaviour these tests measure); the
/// gap rule is tested in `across_hosts.rs` and `faults.rs`.
fn run_external(id: &str, extra: &[&str], dir: &std::path::Path) -> Output {
    rig()
        .args([
            "run", "--plant", "external", "--driver", id, "--gaps", "learn",
        ])
        .args(extra)
        .arg("--out")
        .arg(dir)
        .output()
        .unwrap()
}

fn line<'a>(stdout: &'a str, check: &str) -> &'a str {
    stdout
        .lines()
        .find(|l| l[4..].trim_start().starts_with(check))
        .unwrap_or_else(|| panic!("no line for {check}:\n{stdout}"))
}

#[test]
fn the_rust_and_python_drivers_pass_check_driver() {
    for kind in drivers() {
        let d = Driver::launch(&kind, "pass", &["--speed", "2"]);
        passes_check_driver(&d);
    }
}

fn passes_check_driver(d: &Driver) {
    let out = check_driver(&d.id);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{}: {stdout}\n{stderr}", d.id);
    for check in [
        "payload types",
        "info",
        "reset",
        "samples",
        "sample rate",
        "step response",
        "watchdog",
        "out-of-range actions",
        "non-finite and malformed actions",
    ] {
        assert!(line(&stdout, check).starts_with("PASS"), "{stdout}");
    }
    assert!(stdout.contains("check-driver: PASS (9 checks)"), "{stdout}");
    assert!(line(&stdout, "info").contains("time scale 2"), "{stdout}");
}

/// `rig run --plant external` with MLAC/LLR on the pendulum, 6 trials at 10 × real time
/// against each driver: it learns, and the returns are those of the recorded samples.
/// Learning shows in the greedy returns after trials 3 and 6 — the better exceeds −4500,
/// where the untrained policy (zero action, the pendulum hanging) earns −4932 — or, where
/// a greedy policy still learning does worse than the untrained one (it happens: −7613
/// and −8115 once, with other tests running), in the exploring returns: the best of
/// trials 4 to 6 exceeds −4200. Measured over 30 runs of both drivers, some with two
/// busy loops on the two cores (up to 786 of 809 deadlines missed): the better greedy
/// return −2438 to −4287 but in that one run, the best exploring return −2790 to −3830
/// in every run. With the actor's update zeroed (MLAC's Eq. 3.14 step), the critic's
/// (`α_c δ z`) or both, both greedy returns are −4932 and the exploring ones −4493 at
/// best (12 runs): this test fails.
#[test]
fn rig_run_learns_against_the_rust_and_python_drivers_and_records_them() {
    for kind in drivers() {
        let d = Driver::launch(&kind, "run", &["--speed", "10"]);
        learns_and_records(&d, &tmp(&format!("run-{}", d.id)));
    }
}

fn learns_and_records(d: &Driver, dir: &std::path::Path) {
    let out = run_external(
        &d.id,
        &[
            "--trials",
            "6",
            "--eval-every",
            "3",
            "--driver-timeout",
            "20",
        ],
        dir,
    );
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{}: {stdout}\n{stderr}", d.id);
    assert!(stdout.contains("deadline misses:"), "{stdout}");
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    let rows: Vec<&str> = returns.lines().collect();
    assert_eq!(rows.len(), 7, "{returns}");
    let column = |row: &str, i: usize| -> f64 { row.split(',').nth(i).unwrap().parse().unwrap() };
    let greedy = column(rows[3], 4).max(column(rows[6], 4));
    let exploring = rows[4..]
        .iter()
        .map(|r| column(r, 3))
        .fold(f64::MIN, f64::max);
    assert!(
        greedy > -4500.0 || exploring > -4200.0,
        "{}: no learning\n{returns}",
        d.id
    );
    // The returns are the recorded rewards, each ρ(x_k, u_k) of the driver's samples.
    let task = plant::Task::new(plant::SystemName::Pendulum);
    let trials = recorded_trials(&dir.join("run.mcap"));
    let learning: Vec<_> = trials.iter().filter(|t| !t.greedy).collect();
    assert_eq!(learning.len(), 6);
    for (t, row) in learning.iter().zip(&rows[1..]) {
        let ret: f64 = row.split(',').nth(3).unwrap().parse().unwrap();
        assert!(
            same(t.ret(&task), ret),
            "{}: trial {}\n{returns}",
            d.id,
            t.trial
        );
    }
    // The recording has the driver's samples and commands: a RESET per trial (6 learning
    // and 2 greedy) and 100 actions each.
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let (mut samples, mut resets, mut actions) = (0, 0, 0);
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        match m.channel.topic.as_str() {
            "/driver/sample" => samples += 1,
            "/driver/command" => {
                let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
                match v["kind"].as_u64() {
                    Some(1) => actions += 1,
                    Some(2) => resets += 1,
                    k => panic!("command kind {k:?}"),
                }
            }
            _ => {}
        }
    }
    assert_eq!(resets, 8);
    assert_eq!(actions, 8 * 100);
    assert!(samples >= 8 * 101, "{samples} driver samples recorded");
}

/// A run against a driver resumes against a driver only: without `--plant external` the
/// hardware run would quietly finish in the simulator. Resumed against the driver, it
/// goes on, and the summary names the resumed directory.
#[test]
fn a_run_against_a_driver_resumes_only_against_a_driver() {
    let d = Driver::launch(&Kind::Rust, "resume", &["--speed", "10"]);
    let dir = tmp(&format!("resume-{}", d.id));
    let out = run_external(&d.id, &["--trials", "2", "--driver-timeout", "20"], &dir);
    assert!(out.status.success(), "{}", text(&out).1);

    let simulated = rig()
        .args(["run", "--trials", "3", "--quiet", "--resume"])
        .arg(&dir)
        .output()
        .unwrap();
    let (_, err) = text(&simulated);
    assert!(!simulated.status.success());
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("was run against an external driver") && err.contains("--plant external"),
        "{err}"
    );

    let resumed = rig()
        .args([
            "run", "--plant", "external", "--driver", &d.id, "--trials", "3", "--gaps", "learn",
        ])
        .args(["--driver-timeout", "20", "--resume"])
        .arg(&dir)
        .output()
        .unwrap();
    let (stdout, stderr) = text(&resumed);
    assert!(resumed.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains(&format!("wrote {}/{{returns.csv", dir.display())),
        "{stdout}"
    );
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    assert_eq!(returns.lines().count(), 4, "{returns}");
}

/// The §6.4.2 manipulator (two joints, ±0.1 N m, a ±1.2 rad operating range, four start
/// states) behind `rig sim-driver`: it passes `rig check-driver --system arm-6.4`, and
/// VGBP-LSTD runs against it — trials that leave the range end early with the penalty,
/// and the driver brakes back to each start state. Two trials are too few to learn
/// reliably (the greedy return after trial 2 ranges from −40 500 to −54 100, a critic
/// that never learns gives −49 600), so the returns are checked instead: each is the
/// recorded rewards, each reward recomputed from the driver's state and applied action
/// (or the penalty), and the greedy return is the mean over the four start states'
/// trials. With the plant computing `ρ(x_{k+1}, u_k)` instead of `ρ(x_k, u_k)` the test
/// fails at the first sample whose state has changed.
#[test]
fn the_rust_driver_of_the_manipulator_passes_check_driver_and_runs_a_learner() {
    let d = Driver::launch(&Kind::Rust, "arm", &["--system", "arm-6.4", "--speed", "2"]);
    let out = rig()
        .args(["check-driver", "--driver", &d.id, "--system", "arm-6.4"])
        .args(["--rate-seconds", "3", "--max-jitter", "0.5"])
        .output()
        .unwrap();
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("check-driver: PASS (9 checks)"), "{stdout}");
    drop(d);
    let d = Driver::launch(
        &Kind::Rust,
        "armrun",
        &["--system", "arm-6.4", "--speed", "20"],
    );
    let dir = tmp("armrun");
    let out = run_external(
        &d.id,
        &[
            common::ARM64_VGBP_LSTD.as_slice(),
            &["--trials", "2", "--eval-every", "2", "--quiet"],
        ]
        .concat(),
        &dir,
    );
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    let rows: Vec<Vec<&str>> = returns
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 2, "{returns}");
    // The returns are those of the recorded samples, each reward recomputed from the
    // driver's state and applied action, and the greedy return after trial 2 is the mean
    // over the four start states.
    let task = plant::Task::new(plant::SystemName::Arm64);
    let trials = recorded_trials(&dir.join("run.mcap"));
    let (learning, greedy): (Vec<_>, Vec<_>) = trials.iter().partition(|t| !t.greedy);
    assert_eq!((learning.len(), greedy.len()), (2, 4), "{returns}");
    for (t, row) in learning.iter().zip(&rows) {
        assert_eq!(t.trial.to_string(), row[1]);
        assert!(same(t.ret(&task), row[3].parse().unwrap()), "{returns}");
    }
    let mean = greedy.iter().map(|t| t.ret(&task)).sum::<f64>() / 4.0;
    assert!(same(mean, rows[1][4].parse().unwrap()), "{returns}");
    assert!(greedy.iter().all(|t| t.trial == 2));
    // A RESET per trial: 2 learning and 4 greedy.
    let (_, commands) = driver_traffic(&dir.join("run.mcap"));
    let resets = commands.iter().filter(|c| c["kind"] == 2).count();
    assert_eq!(resets, 6, "{returns}");
}

/// `a = b` to 1e-12 relative: a number read back from a recording's JSON may be off in
/// its last bit (the rig writes the shortest exact decimal; `serde_json` reads it fast,
/// not always correctly rounded).
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs()
}

/// One trial of a recording: its `/plant/measurement` messages from the start sample on.
struct RecordedTrial {
    /// A greedy evaluation trial (after learning trial `trial`).
    greedy: bool,
    /// The learning trial it is or follows.
    trial: u64,
    /// `(y, u_applied, reward)` per sample, the start sample's reward unused.
    samples: Vec<(Vec<f64>, Vec<f64>, f64)>,
}

impl RecordedTrial {
    /// The return: the recorded rewards summed in order, after checking each against
    /// `ρ(y_{k−1}, u_k)` recomputed from the recorded state and the action applied over
    /// the interval — or the operating range's penalty, for the sample that left it,
    /// which must be the trial's last.
    fn ret(&self, task: &plant::Task) -> f64 {
        let range = task.operating_range.as_ref();
        let mut sum = 0.0;
        for (k, w) in self.samples.windows(2).enumerate() {
            let ((y, _, _), (y_next, u, r)) = (&w[0], &w[1]);
            let left = range.is_some_and(|range| range.excludes(y_next));
            let want = match range {
                Some(range) if left => range.penalty,
                _ => task.reward.reward(y, u),
            };
            assert!(
                same(*r, want),
                "trial {} sample {}: reward {r}, recomputed {want}",
                self.trial,
                k + 1
            );
            assert!(
                !left || k + 2 == self.samples.len(),
                "a trial goes on after leaving"
            );
            sum += r;
        }
        sum
    }
}

/// The trials recorded in `path`, in order.
fn recorded_trials(path: &std::path::Path) -> Vec<RecordedTrial> {
    let msgs = common::messages(path);
    let mut trials: Vec<RecordedTrial> = Vec::new();
    for (_, data) in &msgs["/plant/measurement"] {
        let v: serde_json::Value = serde_json::from_slice(data).unwrap();
        let flags = v["flags"].as_u64().unwrap();
        if flags & 8 != 0 {
            continue; // shutdown
        }
        if flags & 1 != 0 {
            trials.push(RecordedTrial {
                greedy: flags & 4 != 0,
                trial: v["trial"].as_u64().unwrap(),
                samples: Vec::new(),
            });
        }
        let nums = |key: &str| -> Vec<f64> {
            (0..)
                .map_while(|i| v.get(format!("{key}_{i}")).map(|x| x.as_f64().unwrap()))
                .collect()
        };
        let r = v["reward"].as_f64().unwrap_or(f64::NAN);
        let t = trials.last_mut().expect("a trial starts first");
        t.samples.push((nums("y"), nums("u_applied"), r));
    }
    trials
}

/// A driver that measures positions only (`--sensor angle` of `rig sim-driver` and of the
/// Python driver: an encoder, as on the physical pendulum of §6.4.1; NaN velocities). Without `--sensor angle` the rig
/// refuses it, naming the flags. With an observer the velocities are estimated, the
/// measurements carry no reward (null, flag ESTIMATED_REWARD), each estimate carries
/// `ρ(x̂_k, u_k)` of the previous estimate and the action applied over the interval,
/// and returns.csv sums those.
#[test]
fn a_driver_measuring_positions_only_is_estimated_and_its_rewards_computed_from_the_estimates() {
    for kind in drivers() {
        let d = Driver::launch(&kind, "encoder", &["--sensor", "angle", "--speed", "10"]);
        estimated_rewards(&d);
    }
}

fn estimated_rewards(d: &Driver) {
    let timeout = ["--driver-timeout", "20"];
    let out = run_external(
        &d.id,
        &[&timeout[..], &["--trials", "1"]].concat(),
        &tmp(&format!("encoder-refused-{}", d.id)),
    );
    let (stdout, stderr) = text(&out);
    assert!(!out.status.success(), "{stdout}");
    assert!(
        stderr.contains("measures positions only") && stderr.contains("`--sensor angle`"),
        "{stderr}"
    );
    let dir = tmp(&format!("encoder-run-{}", d.id));
    let flags = ["--sensor", "angle", "--observer", "predictive"];
    let more = ["--trials", "3", "--eval-every", "3"];
    let out = run_external(&d.id, &[&timeout[..], &flags, &more].concat(), &dir);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let task = plant::Task::new(plant::SystemName::Pendulum);
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let num = |v: &serde_json::Value, k: &str| v[k].as_f64();
    let (mut measured, mut estimated) = (0, 0);
    let mut prev: Option<serde_json::Value> = None;
    // Per learning trial, the sum of the estimates' rewards.
    let mut sums = [0.0; 4];
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let topic = m.channel.topic.as_str();
        if !["/plant/measurement", "/observer/estimate"].contains(&topic) {
            continue;
        }
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        let f = v["flags"].as_u64().unwrap();
        assert_ne!(f & 256, 0, "{topic} without ESTIMATED_REWARD: {v}");
        let (start, greedy, shutdown) = (f & 1 != 0, f & 4 != 0, f & 8 != 0);
        match topic {
            "/plant/measurement" if !start && !shutdown => {
                assert!(v["reward"].is_null() && v["y_1"].is_null(), "{v}");
                assert!(num(&v, "y_0").is_some(), "{v}");
                measured += 1;
            }
            "/observer/estimate" if !shutdown => {
                if !start {
                    let p = prev.as_ref().unwrap();
                    let x = [num(p, "x_0").unwrap(), num(p, "x_1").unwrap()];
                    let u = [num(&v, "u_applied_0").unwrap()];
                    let r = num(&v, "reward").unwrap();
                    let expected = task.reward.reward(&x, &u);
                    assert!((r - expected).abs() <= 1e-12 * r.abs(), "{v} after {p}");
                    if !greedy {
                        sums[v["trial"].as_u64().unwrap() as usize] += r;
                    }
                    estimated += 1;
                }
                prev = Some(v);
            }
            _ => {}
        }
    }
    // 3 learning trials and one greedy of 100 samples each.
    assert_eq!((measured, estimated), (400, 400));
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    for row in returns.lines().skip(1) {
        let c: Vec<&str> = row.split(',').collect();
        let (trial, ret): (usize, f64) = (c[1].parse().unwrap(), c[3].parse().unwrap());
        assert!((ret - sums[trial]).abs() <= 1e-9 * ret.abs(), "{returns}");
        assert!(ret < -1000.0, "{returns}");
    }
    assert!(
        returns
            .lines()
            .last()
            .unwrap()
            .split(',')
            .nth(4)
            .unwrap()
            .parse::<f64>()
            .is_ok()
    );
}

/// One driver per id: a second `rig sim-driver` with the same id is a one-line error
/// naming the id and the service, and the first goes on.
#[test]
fn a_second_driver_with_the_same_id_is_refused() {
    let first = Driver::launch(&Kind::Rust, "twice", &[]);
    std::thread::sleep(Duration::from_millis(500));
    let out = rig()
        .args(["sim-driver", "--driver-id", &first.id])
        .output()
        .unwrap();
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let error: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(
        error,
        [format!(
            "error: another driver {:?} is running: rig/driver/{}/info has its one publisher already",
            first.id, first.id
        )],
        "{stderr}"
    );
    let out = check_driver(&first.id);
    assert!(out.status.success(), "{}", text(&out).0);
}

/// A driver that times each sample from the previous one, its wait off by up to ±2 ms,
/// fails the sample-rate check, and the line says that its clock drifts (or, on a
/// machine that stalls it besides, that it is irregular) instead of reporting only an
/// accumulated lateness. With `--inject-fault clock` removed the driver passes.
#[test]
fn check_driver_says_when_a_drivers_clock_drifts() {
    let Some(py) = python() else { return };
    let d = Driver::start(&py, "clock", &["--inject-fault", "clock"]);
    let out = rig()
        .args(["check-driver", "--driver", &d.id, "--rate-seconds", "3"])
        .args(["--driver-timeout", "20"])
        .output()
        .unwrap();
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    let rate = line(&stdout, "sample rate");
    assert!(rate.starts_with("FAIL"), "{stdout}");
    assert!(
        rate.contains("intervals off the period by p99")
            && (rate.contains("the driver's clock drifts")
                || rate.contains("the driver's clock is irregular")),
        "{rate}"
    );
}

/// A driver whose commands take effect a period late (as across a slow link, or on a
/// loaded host) fails the sample-rate check, which times them, and passes the checks of
/// what it does with a command once it has it: the step response, the watchdog (two
/// periods from when the last action was taken), clamping, rejecting.
#[test]
fn check_driver_tells_late_actions_from_unsafe_ones() {
    let Some(py) = python() else { return };
    let d = Driver::start(&py, "late", &["--speed", "5", "--inject-fault", "late"]);
    let out = check_driver(&d.id);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(line(&stdout, "sample rate").starts_with("FAIL"), "{stdout}");
    for check in [
        "step response",
        "watchdog",
        "out-of-range actions",
        "non-finite and malformed actions",
    ] {
        assert!(line(&stdout, check).starts_with("PASS"), "{stdout}");
    }
    assert!(
        line(&stdout, "step response").contains("1 taken before their action arrived (late)"),
        "{stdout}"
    );
}

#[test]
fn a_driver_with_an_incompatible_payload_is_a_one_line_error() {
    let Some(py) = python() else { return };
    let d = Driver::start(&py, "layout", &["--inject-fault", "layout"]);
    // Let the driver create its services first.
    std::thread::sleep(Duration::from_millis(1500));
    let out = check_driver(&d.id);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    for part in [
        "error: ",
        &format!("rig/driver/{}/sample", d.id),
        "IncompatibleTypes",
        "rig.DriverSample.v2 (200 bytes",
        "rig.DriverSample.v2 (160 bytes",
    ] {
        assert!(stderr.contains(part), "{part:?} in {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// A driver that never engages its watchdog, or a period late, fails the watchdog check
/// (the two periods count from when it took the last action, which it took on time); one
/// that neither clamps nor rejects fails those two checks.
#[test]
fn check_driver_fails_a_driver_without_watchdog_or_limits() {
    let Some(py) = python() else { return };
    for (fault, failing) in [
        ("watchdog", &["watchdog"][..]),
        ("slow-watchdog", &["watchdog"][..]),
        (
            "limits",
            &["out-of-range actions", "non-finite and malformed actions"][..],
        ),
    ] {
        let d = Driver::start(&py, fault, &["--speed", "5", "--inject-fault", fault]);
        let out = check_driver(&d.id);
        let (stdout, stderr) = text(&out);
        assert_eq!(out.status.code(), Some(1), "{fault}: {stdout}\n{stderr}");
        for check in failing {
            assert!(
                line(&stdout, check).starts_with("FAIL"),
                "{fault}: {stdout}"
            );
        }
        assert!(
            line(&stdout, "step response").starts_with("PASS"),
            "{fault}: {stdout}"
        );
        assert!(stdout.contains("check-driver: FAIL"), "{stdout}");
    }
}

#[test]
fn no_driver_is_a_clear_error_after_the_timeout() {
    let id = format!("nobody{}", std::process::id());
    let out = rig()
        .args(["check-driver", "--driver", &id, "--driver-timeout", "1"])
        .output()
        .unwrap();
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("no driver {id:?}"))
            && stderr.contains(&format!("rig/driver/{id}/info"))
            && stderr.contains("examples/python_driver/driver.py"),
        "{stderr}"
    );
    let dir = tmp("nobody");
    let t0 = Instant::now();
    let out = run_external(&id, &["--driver-timeout", "1", "--quiet"], &dir);
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&format!("no driver {id:?}")), "{stderr}");
    assert!(t0.elapsed() < Duration::from_secs(10));
    // Flags that do not go together are usage errors.
    for args in [
        &["run", "--plant", "external", "--timing", "realtime"][..],
        &["run", "--driver", "x"][..],
        &["check-driver", "--max-jitter", "2"][..],
        &["check-driver", "--driver", "a/b"][..],
    ] {
        let out = rig().args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
}

/// Waiting for a driver that is not there, `rig check-driver` says that it waits, as
/// `rig run` does; the error then names a command that serves the task checked — or none,
/// for a task without a simulation; and a refused `rig run` leaves no output folder.
#[test]
fn waiting_for_no_driver_is_said_and_the_hint_fits_the_task() {
    let id = format!("absent{}", std::process::id());
    let dir = tmp("absent");
    let check = |extra: &[&str]| {
        let out = rig()
            .args(["check-driver", "--driver", &id, "--driver-timeout", "2"])
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        text(&out).1
    };
    let stderr = check(&[]);
    assert!(
        stderr.contains(&format!("waiting up to 2 s for driver {id:?}")),
        "{stderr}"
    );
    let arm = check(&["--system", "arm-6.4"]);
    assert!(
        arm.contains(&format!(
            "`rig sim-driver --system arm-6.4 --driver-id {id}`"
        )) && !arm.contains("python_driver"),
        "{arm}"
    );
    let balance = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/tasks/pendulum-balance.toml"),
    )
    .unwrap();
    let driven = dir.join("driven.toml");
    std::fs::write(&driven, balance.split("[simulation]").next().unwrap()).unwrap();
    let none = check(&["--task", driven.to_str().unwrap()]);
    assert!(
        none.contains(
            "the rig has no driver for task \"pendulum-balance\", which has no [simulation]"
        ) && !none.contains("e.g."),
        "{none}"
    );
    let out_dir = dir.join("refused");
    let out = run_external(&id, &["--driver-timeout", "1", "--quiet"], &out_dir);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        !out_dir.exists(),
        "a refused run left {}",
        out_dir.display()
    );
}

/// Per driver sample `seq`: field `key` of the recorded `/driver/sample` messages, and
/// the recorded `/driver/command` messages as JSON.
fn driver_traffic(
    path: &std::path::Path,
) -> (
    std::collections::BTreeMap<u64, serde_json::Value>,
    Vec<serde_json::Value>,
) {
    let bytes = std::fs::read(path).unwrap();
    let (mut samples, mut commands) = (std::collections::BTreeMap::new(), Vec::new());
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let json = || -> serde_json::Value { serde_json::from_slice(&m.data).unwrap() };
        match m.channel.topic.as_str() {
            "/driver/sample" => {
                let v = json();
                samples.insert(v["seq"].as_u64().unwrap(), v);
            }
            "/driver/command" => commands.push(json()),
            _ => {}
        }
    }
    (samples, commands)
}

/// The plant process (the go-between) or the agent killed while a real driver runs: the
/// driver's own watchdog applies the safe action within two periods of the last action,
/// on the driver's clock; `rig run` names the dead process and keeps the recording,
/// which holds the driver's samples after the death.
#[test]
fn a_process_killed_during_an_external_run_leaves_the_driver_safe_within_two_periods() {
    for (kind, role) in drivers()
        .into_iter()
        .flat_map(|k| [(k.clone(), "plant"), (k, "agent")])
    {
        // 3 × real time: 10 ms periods.
        let d = Driver::launch(&kind, &format!("kill{role}"), &["--speed", "3"]);
        let who = format!("{role} ({})", d.id);
        let dir = tmp(&format!("kill-{}", d.id));
        let sup = rig()
            .args([
                "run", "--plant", "external", "--driver", &d.id, "--gaps", "learn",
            ])
            .args(["--trials", "50", "--eval-every", "0", "--quiet", "--out"])
            .arg(&dir)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // A row is written when the next trial starts: kill 30 samples into trial 4.
        let t0 = Instant::now();
        while std::fs::read_to_string(dir.join("returns.csv"))
            .unwrap_or_default()
            .lines()
            .count()
            < 4
        {
            assert!(t0.elapsed() < Duration::from_secs(60), "no learning");
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(Duration::from_millis(300));
        common::signal(common::child_running(sup.id(), role), "-9");
        let out = sup.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{who}");
        assert!(
            err.contains(&format!("the {role} process exited (signal: 9")),
            "{who}: {err}"
        );
        let (samples, commands) = driver_traffic(&dir.join("run.mcap"));
        let last = commands.last().expect("commands were recorded");
        assert_eq!(
            last["kind"], 1,
            "{who}: killed mid-trial, the last command is an action"
        );
        assert_ne!(last["u_0"].as_f64(), Some(0.0), "{who}: a non-zero action");
        // The driver applied the last command during the period before the first sample
        // that names it as `last_command` (under load that can be later than the sample
        // it answered); the next sample instant had none, so zero applies from the one
        // after. Under load the driver can miss periods: it then skips their sequence
        // numbers ("missed N period(s)" in its log), so sample instants are taken in
        // recorded order and periods counted by `seq`, the driver's clock.
        let seq = last["seq"].as_u64().unwrap();
        let keys: Vec<u64> = samples.keys().copied().collect();
        let i_a = keys
            .iter()
            .position(|k| samples[k]["last_command"].as_u64() == Some(seq))
            .expect("the driver reports applying the last command");
        assert!(i_a > 0, "{who}: a sample before the last command's");
        let (k_prev, k_a) = (keys[i_a - 1], keys[i_a]);
        let period = 10e6;
        let t = |k: u64| samples[&k]["t_sample_ns"].as_f64().unwrap();
        let after = &keys[i_a + 1..];
        assert!(
            after.len() >= 3,
            "{who}: the recording must show the driver after the death (last command applied by sample {k_a})"
        );
        for &k in &after[1..] {
            let v = &samples[&k];
            assert_eq!(
                v["u_applied_0"].as_f64(),
                Some(0.0),
                "{who}: sample {k}: {v} (last command applied by sample {k_a})"
            );
            assert_ne!(
                v["status"].as_u64().unwrap() & 4,
                0,
                "{who}: WATCHDOG at {k}"
            );
        }
        // Applied within [t(k_prev), t(k_a)); safe from the next sample instant: two
        // periods at most (plus those the driver itself missed, if any).
        let k_next = after[0];
        let periods = (k_next - k_prev) as f64;
        assert!(
            t(k_next) - t(k_prev) <= (periods + 0.5) * period,
            "{who}: the safe action {} ms after the period the last action arrived in began ({periods} periods by seq: {k_prev} to {k_next})",
            (t(k_next) - t(k_prev)) * 1e-6
        );
    }
}

/// `--cpu-wakeup-us 17` of `rig sim-driver` and of the Python example: while the driver
/// runs, the machine's CPU wake-up latency limit is at most 17 µs — or, where the limit
/// cannot be set, the driver stops at once with an error naming the device and the flag.
#[test]
fn a_driver_holds_the_cpu_wakeup_limit_while_it_runs() {
    let id = format!("wakeup-{}", std::process::id());
    let mut rust = rig();
    rust.args(["sim-driver", "--driver-id", &id]);
    holds_the_limit(rust);
    let Some(py) = python() else { return };
    let mut python = common::python::script(&py, "examples/python_driver/driver.py");
    python.args(["--driver-id", &format!("{id}-py")]);
    holds_the_limit(python);
}

fn holds_the_limit(mut driver: std::process::Command) {
    let mut child = driver
        .args(["--cpu-wakeup-us", "17"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Until the driver holds the limit (it starts up first), stops, or 20 s have passed.
    let t0 = Instant::now();
    let mut limit = runtime::process::wakeup::current();
    while child.try_wait().unwrap().is_none()
        && limit.is_some_and(|us| us > 17)
        && t0.elapsed() < Duration::from_secs(20)
    {
        std::thread::sleep(Duration::from_millis(20));
        limit = runtime::process::wakeup::current();
    }
    if child.try_wait().unwrap().is_some() {
        let out = child.wait_with_output().unwrap();
        let (_, stderr) = text(&out);
        assert!(!out.status.success(), "{stderr}");
        assert!(
            stderr.contains("--cpu-wakeup-us") && stderr.contains("/dev/cpu_dma_latency"),
            "{stderr}"
        );
        return;
    }
    child.kill().unwrap();
    child.wait().unwrap();
    // Unreadable (not root): the driver could not have set it either, and stopped above.
    if let Some(us) = limit {
        assert!(
            us <= 17,
            "the limit in force is {us} µs while the driver holds 17"
        );
    }
}

/// The gap rule on one host: the agent stopped (SIGSTOP) for about seven periods of a
/// driver at real time, mid-trial. The plant waits for its answer meanwhile; the driver's
/// clock goes on, so the next sample comes after missing ones: a gap. The attempt is cut
/// short unlearned, the trial run again, and the run completes.
#[test]
fn a_stalled_agent_against_a_driver_cuts_the_trial_short_and_it_is_run_again() {
    let d = Driver::launch(&Kind::Rust, "stall", &[]);
    let dir = tmp(&format!("stall-{}", d.id));
    let sup = rig()
        .arg("run")
        .args(common::external(&d.id))
        .args(["--trials", "3", "--eval-every", "0"])
        .arg("--out")
        .arg(&dir)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_for_lines(&dir.join("returns.csv"), 2);
    std::thread::sleep(Duration::from_millis(1000));
    let agent = common::child_running(sup.id(), "agent");
    common::signal(agent, "-STOP");
    std::thread::sleep(Duration::from_millis(200));
    common::signal(agent, "-CONT");
    let out = sup.wait_with_output().unwrap();
    assert!(out.status.success());
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    assert_eq!(returns.lines().count(), 4, "{returns}");
    let flagged = common::gaps::flagged_and_never_learned(&dir.join("run.mcap"), 30_000_000);
    common::gaps::counted(&String::from_utf8_lossy(&out.stdout), &dir, flagged);
}
