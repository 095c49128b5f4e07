//! Driver processes for the tests: the Python example (`examples/python_driver/`,
//! official iceoryx2 bindings) and `rig sim-driver`, one at a time.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use super::python as py;
use super::rig;

/// The Python interpreter with the bindings (and the source tree's rigkit), or `None`
/// (and why) if there is none.
pub fn python() -> Option<String> {
    let install = "pip install \"./python[driver]\"";
    let (python, version) = py::probe(
        "import importlib.metadata as m, iceoryx2, rigkit; print(m.version('iceoryx2'))",
        &format!("iceoryx2 0.10.0 and rigkit ({install})"),
    )?;
    if version != "0.10.0" {
        println!("skipped: {python} has iceoryx2 {version}, not 0.10.0 ({install})");
        return None;
    }
    Some(python)
}

/// The Python interpreter with the bindings, if it can also import `modules`
/// (comma-separated), or `None` (and why).
pub fn python_with(modules: &str) -> Option<String> {
    python()?;
    py::with(modules)
}

/// A driver process: the Python example (`examples/python_driver/driver.py`, official
/// iceoryx2 bindings) or `rig sim-driver` (Rust, the driver kit).
#[derive(Clone, Debug)]
pub enum Kind {
    /// The Python example, run by this interpreter.
    Python(String),
    /// `rig sim-driver`.
    Rust,
}

/// The drivers to test: `rig sim-driver`, and the Python example where the bindings are.
pub fn drivers() -> Vec<Kind> {
    let mut kinds = vec![Kind::Rust];
    kinds.extend(python().map(Kind::Python));
    kinds
}

/// A driver, stopped (SIGTERM, then killed) when dropped. One runs at a time: these
/// tests measure the driver's timing (sample rate, watchdog, the safe action after a
/// death), which two drivers and their rigs sharing a 2-core CI machine would disturb.
pub struct Driver {
    pub child: Child,
    pub id: String,
    _alone: std::sync::MutexGuard<'static, ()>,
}

/// Held by the test whose driver is running.
static ONE_DRIVER: std::sync::Mutex<()> = std::sync::Mutex::new(());

impl Driver {
    pub fn start(python: &str, name: &str, extra: &[&str]) -> Self {
        Self::launch(&Kind::Python(python.into()), name, extra)
    }

    /// Driver `kind` with id `<name>-rs<pid>` (Rust) or `<name>-py<pid>` (Python) and
    /// flags `extra` (both drivers take `--speed`; the Python one also
    /// `--inject-fault`).
    pub fn launch(kind: &Kind, name: &str, extra: &[&str]) -> Self {
        match kind {
            Kind::Python(python) => {
                Self::script(python, "examples/python_driver/driver.py", name, extra)
            }
            Kind::Rust => {
                let mut c = rig();
                c.arg("sim-driver");
                Self::spawn(c, &format!("{name}-rs"), extra)
            }
        }
    }

    /// The Python driver `script` (relative to the repository) with id `<name>-py<pid>`
    /// and flags `extra`.
    pub fn script(python: &str, script: &str, name: &str, extra: &[&str]) -> Self {
        Self::spawn(py::script(python, script), &format!("{name}-py"), extra)
    }

    /// `command --driver-id <prefix><pid> extra…`, once the other tests' drivers are done.
    fn spawn(mut command: Command, prefix: &str, extra: &[&str]) -> Self {
        // A failed test's poisoned lock is still a lock.
        let alone = ONE_DRIVER.lock().unwrap_or_else(|e| e.into_inner());
        let id = format!("{prefix}{}", std::process::id());
        let child = command
            .args(["--driver-id", &id])
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        Self {
            child,
            id,
            _alone: alone,
        }
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(3) {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
