//! The systems benchmark's held-out systems (bench/python/systems.toml, `held_out = true`)
//! are served as a user would serve them: the cart-pole (examples/cartpole/) by its Python
//! driver — its model keeps its energy and is Gymnasium CartPole-v1's, the driver passes
//! `rig check-driver` for both tasks, and a few trials repeat their returns — and
//! Gymnasium's MuJoCo InvertedPendulum-v5 by the adapter with its mapping module, the
//! environment's reward and endings reaching the rig. The known controllers of
//! bench/python/known_controllers.py meet every held-out success rule. What learners
//! reach on them is the benchmark's (docs/results/systems.md).
//!
//! Needs iceoryx2 0.10.0 importable by `$RIG_PYTHON` (default `python3`), and gymnasium
//! with MuJoCo for the environment; without them a test prints why and passes — CI
//! installs them.

use std::path::Path;
use std::process::Output;

mod common;
use common::drivers::{Driver, python, python_with};
use common::python::root;
use common::{ok, rig};

/// `rig check-driver --driver ID --task TASK`, asserted to pass.
fn check_driver(id: &str, task: &str) {
    ok(rig()
        .args(["check-driver", "--driver", id, "--driver-timeout", "20"])
        .args(["--task", task])
        .output()
        .unwrap());
}

/// `rig run --plant external` of `task` against driver `id`, `trials` trials, MLAC/LLR,
/// a greedy evaluation every second: its returns.csv.
fn run(id: &str, task: &str, trials: &str, dir: &Path) -> String {
    ok(rig()
        .arg("run")
        .args(common::external(id))
        .args(["--quiet", "--task", task, "--trials", trials])
        .args([
            "--algo",
            "mlac",
            "--approx",
            "llr",
            "--eval-every",
            "2",
            "--out",
        ])
        .arg(dir)
        .output()
        .unwrap());
    std::fs::read_to_string(dir.join("returns.csv")).unwrap()
}

/// `python SCRIPT`, `script` relative to the repository's root.
fn script(python: &str, path: &str) -> Output {
    common::python::script(python, path).output().unwrap()
}

/// The cart-pole: its model check passes, and for each task its driver passes `rig
/// check-driver` and a few trials repeat their returns on a second run.
#[test]
fn the_cartpole_is_a_task_file_and_a_python_driver() {
    let Some(python) = python() else {
        return;
    };
    let model = script(&python, "examples/cartpole/check_model.py");
    assert!(
        model.status.success(),
        "{}",
        String::from_utf8_lossy(&model.stdout)
    );
    let dir = common::tmp("held-out", "cartpole");
    for (name, trials) in [("cartpole-balance", "4"), ("cartpole-swing-balance", "2")] {
        let task = root().join(format!("examples/cartpole/{name}.toml"));
        let task = task.to_str().unwrap();
        let d = Driver::script(
            &python,
            "examples/cartpole/driver.py",
            name,
            &["--task", task],
        );
        check_driver(&d.id, task);
        let a = run(&d.id, task, trials, &dir.join(format!("{name}-a")));
        let b = run(&d.id, task, trials, &dir.join(format!("{name}-b")));
        assert_eq!(a, b, "{name}");
        assert_eq!(
            a.lines().count(),
            trials.parse::<usize>().unwrap() + 1,
            "{a}"
        );
    }
}

/// InvertedPendulum-v5 through the adapter: `rig check-driver` passes, and a run learns
/// the environment's own reward (+1 a step while the pole is up: every learning trial's
/// return is its number of steps, at least one, at most 1000).
#[test]
fn gymnasium_inverted_pendulum_v5_is_served_by_the_adapter() {
    let Some(python) = python_with("gymnasium, mujoco") else {
        return;
    };
    let task = root().join("examples/gymnasium/inverted-pendulum-v5.toml");
    let task = task.to_str().unwrap();
    let mapping = root().join("examples/gymnasium/inverted_pendulum_v5.py");
    let d = Driver::script(
        &python,
        "examples/gymnasium/adapter.py",
        "inverted-pendulum",
        &["--mapping", mapping.to_str().unwrap()],
    );
    check_driver(&d.id, task);
    let dir = common::tmp("held-out", "inverted-pendulum-v5");
    let returns = run(&d.id, task, "4", &dir);
    for row in returns.lines().skip(1) {
        let r: f64 = row.split(',').nth(3).unwrap().parse().unwrap();
        assert!(r.fract() == 0.0 && (1.0..=1000.0).contains(&r), "{returns}");
    }
}

/// A controller that knows each held-out system's model meets its success rule: every
/// line of known_controllers.py's table says "yes".
#[test]
fn every_held_out_success_rule_is_reachable() {
    let Some(python) = python_with("numpy, gymnasium, mujoco") else {
        return;
    };
    let out = ok(script(&python, "bench/python/known_controllers.py"));
    let table = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<&str> = table.lines().skip(2).collect();
    assert_eq!(rows.len(), 3, "{table}");
    assert!(rows.iter().all(|r| r.ends_with("| yes |")), "{table}");
}
