//! The systems benchmark (`bench/python/systems.py`) in a short version: one experiment of
//! the shipped matrix (the acrobot's balance, one learner, a few trials) runs, its table,
//! table.csv and curve are written, a second call with one seed more keeps the first
//! seed's run and adds the second, and a bad matrix file is refused in one line naming
//! the file and the keys. What the learners reach in full runs is the benchmark's
//! (docs/results/systems.md).
//!
//! Needs iceoryx2 0.10.0, mcap and matplotlib importable by `$RIG_PYTHON` (default
//! `python3`); without them it prints why and passes — CI installs them.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::drivers::python;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The interpreter, if it has the benchmark's modules.
fn interpreter() -> Option<String> {
    let python = python()?;
    let has = Command::new(&python)
        .args(["-c", "import mcap, matplotlib"])
        .status()
        .is_ok_and(|s| s.success());
    if !has {
        println!("skipped: {python} cannot import mcap and matplotlib");
    }
    has.then_some(python)
}

/// `systems.py OUT` with `args`, the rig under test.
fn systems(python: &str, out: &Path, args: &[&str]) -> Output {
    Command::new(python)
        .arg(root().join("bench/python/systems.py"))
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
