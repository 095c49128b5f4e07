//! The systems benchmark (`bench/python/systems.py`) in a short version: one experiment of
//! the shipped matrix (the acrobot's balance, one learner, a few trials) runs, its table,
//! table.csv (with the agent's step per sample, from the recordings) and curve are
//! written, a second call with one seed more keeps the first seed's run and adds the
//! second, and a bad matrix file is refused in one line naming the file and the keys;
//! the Pendulum-v1 comparison keeps its finished runs. What the learners reach in full
//! runs is the benchmark's (docs/results/systems.md).
//!
//! Needs iceoryx2 0.10.0, mcap and matplotlib importable by `$RIG_PYTHON` (default
//! `python3`); without them it prints why and passes — CI installs them.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::drivers::python;

/// The interpreter, if it has the benchmark's modules.
fn interpreter() -> Option<String> {
    interpreter_with("mcap, matplotlib")
}

/// The interpreter, if it can import `modules` (comma-separated).
fn interpreter_with(modules: &str) -> Option<String> {
    python()?;
    common::python::with(modules)
}

/// `systems.py OUT` with `args`, the rig under test.
fn systems(python: &str, out: &Path, args: &[&str]) -> Output {
    common::python::script(python, "bench/python/systems.py")
        .arg(out)
        .arg("--rig")
        .arg(env!("CARGO_BIN_EXE_rig"))
        .args(["--python", python])
        .args(args)
        .output()
        .unwrap()
}

/// A matrix of the shipped one's acrobot balance with its first learner only.
fn one_learner(dir: &Path) -> PathBuf {
    let matrix = dir.join("matrix.toml");
    std::fs::write(
        &matrix,
        r#"[[experiment]]
name = "acrobot-balance"
system = "acrobot, balance from small deflections"
task = "examples/acrobot/acrobot-balance.toml"
driver = ["examples/acrobot/driver.py"]
trials = 400
success = { upright = 0.3, hold = 1.5 }
learners = [{ label = "MLAC/LLR", flags = ["--algo", "mlac", "--approx", "llr", "--eval-every", "5"] }]
"#,
    )
    .unwrap();
    matrix
}

#[test]
fn a_short_benchmark_writes_its_table_and_resumes_with_more_seeds() {
    let Some(python) = interpreter() else {
        return;
    };
    let dir = common::tmp("systems", "short");
    let matrix = one_learner(&dir);
    let m = matrix.to_str().unwrap();
    let out = dir.join("out");
    let short = ["--matrix", m, "--trials", "10"];
    let first = common::ok(systems(
        &python,
        &out,
        &[&short[..], &["--seeds", "1"]].concat(),
    ));
    let table = String::from_utf8_lossy(&first.stdout);
    assert!(
        table.contains("| MLAC/LLR | 0 of 1 |") || table.contains("| MLAC/LLR | 1 of 1 |"),
        "{table}"
    );
    assert!(table.contains("PILCO"), "{table}");
    assert!(out.join("acrobot-balance.png").metadata().unwrap().len() > 0);
    let runs = out.join("acrobot-balance/mlac-llr");
    let modified = || {
        std::fs::metadata(runs.join("seed-1/run.mcap"))
            .unwrap()
            .modified()
            .unwrap()
    };
    let seed1 = modified();

    let again = common::ok(systems(
        &python,
        &out,
        &[&short[..], &["--seeds", "2"]].concat(),
    ));
    let table = String::from_utf8_lossy(&again.stdout);
    assert!(table.contains(" of 2 |"), "{table}");
    assert_eq!(modified(), seed1, "seed 1 kept, not run again");
    let wall = std::fs::read_to_string(runs.join("wall.csv")).unwrap();
    assert_eq!(wall.lines().count(), 3, "{wall}");
    let csv = std::fs::read_to_string(out.join("table.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
    // The agent's step per sample, read from the seeds' recordings: the last two columns
    // (the system's name before them may hold a quoted comma).
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with(",agent_ms_median,agent_ms_p99"),
        "{csv}"
    );
    let last: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .rsplit(',')
        .take(2)
        .map(|v| v.parse().unwrap_or_else(|e| panic!("{v}: {e}: {csv}")))
        .collect();
    let (median, p99) = (last[1], last[0]);
    assert!(0.0 < median && median <= p99 && p99 < 1000.0, "{csv}");
}

#[test]
fn a_bad_matrix_is_refused_in_one_line() {
    let Some(python) = interpreter() else {
        return;
    };
    let err = refused(&python, "[[experiment]]\nname = \"x\"\nsytem = \"typo\"\n");
    assert!(
        err.contains("bad.toml") && err.contains("sytem") && err.contains("system"),
        "{err}"
    );
    let learner = "learners = [{ label = \"a\", flags = [], trials = 0 }]";
    let err = refused(
        &python,
        &format!(
            "[[experiment]]\nname = \"x\"\nsystem = \"s\"\ntask = \"t\"\ndriver = []\ntrials = 5\nsuccess = {{ return_at_least = 0.0 }}\n{learner}\n"
        ),
    );
    assert!(err.contains("trials must be a whole number"), "{err}");
}

/// The one-line error of `systems.py --matrix` on a matrix file `bad.toml` holding `text`.
fn refused(python: &str, text: &str) -> String {
    let dir = common::tmp("systems", "bad");
    let matrix = dir.join("bad.toml");
    std::fs::write(&matrix, text).unwrap();
    let out = systems(
        python,
        &dir.join("out"),
        &["--matrix", matrix.to_str().unwrap()],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    err
}

/// `sb3_pendulum.py OUT --seeds 1 --steps 2000` with `args`, the rig under test.
fn comparison(python: &str, out: &Path, args: &[&str]) -> Output {
    common::python::script(python, "bench/python/sb3_pendulum.py")
        .arg(out)
        .args(["--seeds", "1", "--steps", "2000", "--python", python])
        .args(args)
        .output()
        .unwrap()
}

/// The Pendulum-v1 comparison keeps what an earlier call finished: here Stable-Baselines3's
/// seed (CI does not install it; its evaluation is written as an earlier call would have),
/// and on a second call the rig's runs too. Runs of another length, or a rig that is not
/// there, are refused in one line.
#[test]
fn the_pendulum_comparison_keeps_the_runs_an_earlier_call_finished() {
    let Some(python) = interpreter_with("mcap, matplotlib, gymnasium") else {
        return;
    };
    let out = common::tmp("systems", "sb3").join("out");
    std::fs::create_dir_all(&out).unwrap();
    let kept = "learner,seed,steps,wall_s,greedy_return\nSB3 SAC,1,2000,61.500,-150.25\n";
    std::fs::write(out.join("curves.csv"), kept).unwrap();
    let rig = ["--rig", env!("CARGO_BIN_EXE_rig")];

    let first = common::ok(comparison(&python, &out, &rig));
    let text = String::from_utf8_lossy(&first.stdout);
    assert!(text.contains("SB3 SAC seed 1: kept"), "{text}");
    assert!(
        text.contains("| SB3 SAC | 1 of 1 | 2000 | 61.5 s | -150.2 | 61.5 s |"),
        "{text}"
    );
    for learner in ["rig MLAC/LLR", "rig SAC/LLR"] {
        assert!(text.contains(&format!("| {learner} | ")), "{text}");
    }
    let curves = std::fs::read_to_string(out.join("curves.csv")).unwrap();
    assert!(curves.starts_with(kept), "{curves}");
    assert_eq!(curves.lines().count(), 4, "{curves}");
    let returns = out.join("rig-mlac-1/returns.csv");
    let modified = || std::fs::metadata(&returns).unwrap().modified().unwrap();
    let ran = modified();

    let again = common::ok(comparison(&python, &out, &rig));
    let text = String::from_utf8_lossy(&again.stdout);
    assert_eq!(text.matches(": kept from ").count(), 3, "{text}");
    assert_eq!(modified(), ran, "the rig's run kept, not run again");
    assert_eq!(
        std::fs::read_to_string(out.join("curves.csv")).unwrap(),
        curves
    );

    let longer = comparison(&python, &out, &[&rig[..], &["--steps", "4000"]].concat());
    let err = String::from_utf8_lossy(&longer.stderr);
    assert!(!longer.status.success());
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("holds runs of 2000 steps"), "{err}");
    let absent = comparison(&python, &out, &["--rig", "/nonexistent/rig"]);
    let err = String::from_utf8_lossy(&absent.stderr);
    assert!(!absent.status.success());
    assert!(
        err.contains("/nonexistent/rig: no such rig binary"),
        "{err}"
    );
}
