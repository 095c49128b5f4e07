//! The rig's Python package, `rigkit` (python/), from `cargo test`: its pytest suite
//! (python/tests: the package's modules, every example script shortened, the bench
//! scripts that must end cleanly), given this rig as `RIG`, and its type check (mypy,
//! strict, python/pyproject.toml), and that of `rig tune`'s helpers (tune/rig_tune). The
//! package is the source tree's (`PYTHONPATH`, set by `common::python`), installed or
//! not. Needs pytest (and mypy) importable by
//! `$RIG_PYTHON` (default `python3`): `pip install "./python[test]"`; without them each
//! test prints why and passes — CI installs them.

mod common;

use common::python;

fn text(out: &std::process::Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn the_python_package_passes_its_tests() {
    let Some(py) = python::with("pytest") else {
        return;
    };
    let out = python::command(&py)
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "python/tests",
        ])
        .current_dir(python::root())
        .env("RIG", env!("CARGO_BIN_EXE_rig"))
        .output()
        .unwrap();
    let said = text(&out);
    println!("{said}");
    assert!(out.status.success(), "pytest python/tests failed:\n{said}");
    assert!(said.contains(" passed"), "{said}");
}

/// `python -m mypy --no-incremental ARGS` in the repository's folder `dir`, asserted to
/// find no issue.
fn type_checks(py: &str, dir: &str, args: &[&str]) {
    let out = python::command(py)
        .args(["-m", "mypy", "--no-incremental"])
        .args(args)
        .current_dir(python::root().join(dir))
        .output()
        .unwrap();
    let said = text(&out);
    assert!(out.status.success(), "mypy {args:?} in {dir}:\n{said}");
    assert!(said.starts_with("Success: no issues found"), "{said}");
}

/// The package, strictly (python/pyproject.toml).
#[test]
fn the_python_package_type_checks() {
    if let Some(py) = python::with("mypy") {
        type_checks(&py, "python", &["rigkit", "tests"]);
    }
}

/// `rig tune`'s Python side (tune/rig_tune) type-checks strictly too, against the
/// package it imports.
#[test]
fn the_tune_helpers_type_check() {
    if let Some(py) = python::with("mypy, optuna, matplotlib") {
        type_checks(&py, "tune", &["--strict", "rig_tune"]);
    }
}
