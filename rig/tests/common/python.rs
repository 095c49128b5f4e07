//! Python for the tests: `$RIG_PYTHON` (default `python3`), with the rig's Python
//! package, `rigkit`, taken from this source tree — `python/` first on `PYTHONPATH` — so
//! that the tests run the package beside them whether or not `pip install ./python` put
//! a copy in the interpreter's site-packages. This is the tests' one place of path setup.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The interpreter the tests run Python with.
pub fn interpreter() -> String {
    std::env::var("RIG_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// `PYTHONPATH` with the source tree's `python/` first.
pub fn path() -> OsString {
    let mut path = root().join("python").into_os_string();
    if let Some(old) = std::env::var_os("PYTHONPATH") {
        path.push(":");
        path.push(old);
    }
    path
}

/// `python` with the source tree's rigkit importable.
pub fn command(python: &str) -> Command {
    let mut c = Command::new(python);
    c.env("PYTHONPATH", path());
    c
}

/// `python SCRIPT` for `script` relative to the repository's root.
pub fn script(python: &str, script: &str) -> Command {
    let mut c = command(python);
    c.arg(root().join(script));
    c
}

/// The interpreter if it imports `modules` (comma-separated), or `None` with the reason
/// printed ("skipped: ..."), for a test that passes where they are not installed.
pub fn with(modules: &str) -> Option<String> {
    let (python, _) = probe(
        &format!("import {modules}"),
        &format!("{modules} (pip install \"./python[driver,gymnasium,recording,test]\")"),
    )?;
    Some(python)
}

/// The interpreter and what it printed running `code`, or `None` with the reason printed:
/// "skipped: PYTHON cannot import WHAT" where `code` fails (`what` saying what it needs
/// and how to install it), or where there is no interpreter.
pub fn probe(code: &str, what: &str) -> Option<(String, String)> {
    let python = interpreter();
    match command(&python).args(["-c", code]).output() {
        Ok(o) if o.status.success() => {
            let said = String::from_utf8_lossy(&o.stdout).trim().to_string();
            Some((python, said))
        }
        Ok(o) => {
            let why = String::from_utf8_lossy(&o.stderr);
            let why = why.lines().last().unwrap_or("");
            println!("skipped: {python} cannot import {what}, or set RIG_PYTHON: {why}");
            None
        }
        Err(e) => {
            println!("skipped: cannot run {python} ({e})");
            None
        }
    }
}
