//! The learner a task chooses when none is named (`agent::preset::by_task`): said in one
//! line by `rig config`, `rig learn` and `rig run`; a balance learned without a
//! configuration file; a task whose reward the chosen learner cannot use refused in one
//! line that says what to add; a named learner and the thesis's own tasks untouched.
//!
//! The run against the Furuta pendulum's Python driver needs `iceoryx2==0.10.0`
//! importable by `$RIG_PYTHON` (default `python3`); without it that test prints why and
//! passes — CI installs it, so it runs there.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::drivers::{Driver, python};
use common::{ok, rig};

/// A file of the repository.
fn root(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
}

/// `rig config` with `args`.
fn config(args: &[&str]) -> Output {
    rig().arg("config").args(args).output().unwrap()
}

/// The lines of stderr that say which learner was chosen.
fn choice_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| l.starts_with("learner: "))
        .map(str::to_owned)
        .collect()
}

/// Each kind of task gets its learner, said in one line, and written into the resolved
/// configuration, so that a run's `config.toml` names it.
#[test]
fn each_kind_of_task_gets_its_learner_said_in_one_line() {
    let cases = [
        (
            "examples/furuta/furuta-balance.toml",
            "with the LQR of its learned model",
            "\n[lqr]\n",
        ),
        (
            "examples/acrobot/acrobot.toml",
            "planning by the iterative LQR",
            "method = \"ilqr\"",
        ),
        (
            "examples/gymnasium/mountain-car-continuous.toml",
            "MLAC/LLR — task",
            "algo = \"mlac\"",
        ),
    ];
    for (task, said, written) in cases {
        let out = ok(config(&["--task", root(task).to_str().unwrap()]));
        let lines = choice_lines(&out);
        assert_eq!(lines.len(), 1, "{task}: {lines:?}");
        assert!(lines[0].contains(said), "{task}: {}", lines[0]);
        assert!(
            lines[0].contains("--algo or a configuration file"),
            "{}",
            lines[0]
        );
        let toml = String::from_utf8_lossy(&out.stdout);
        assert!(toml.contains(written), "{task}: {toml}");
    }
}

/// A learner named by a flag or a file is the one used, silently; the thesis's own tasks
/// keep their presets.
#[test]
fn a_named_learner_and_the_thesis_tasks_choose_nothing() {
    let task = root("examples/furuta/furuta-balance.toml");
    let task = task.to_str().unwrap();
    let named = ok(config(&["--task", task, "--algo", "mlac"]));
    assert!(choice_lines(&named).is_empty());
    assert!(!String::from_utf8_lossy(&named.stdout).contains("[lqr]"));
    let dir = common::tmp("default-learner", "named");
    let file = dir.join("sac.toml");
    std::fs::write(&file, "algo = \"sac\"\n").unwrap();
    let from_file = ok(config(&[
        "--task",
        task,
        "--config",
        file.to_str().unwrap(),
    ]));
    assert!(choice_lines(&from_file).is_empty());
    let thesis = ok(config(&[
        "--task",
        root("plant/tasks/pendulum.toml").to_str().unwrap(),
    ]));
    assert!(choice_lines(&thesis).is_empty());
    let toml = String::from_utf8_lossy(&thesis.stdout);
    assert!(
        !toml.contains("[lqr]") && !toml.contains("[planning]"),
        "{toml}"
    );
}

/// A balance task whose reward has no action cost: the regulator cannot be designed, and
/// the error says so in one line, with the key and a value to add.
#[test]
fn a_task_without_an_action_cost_is_refused_with_what_to_add() {
    let dir = common::tmp("default-learner", "no-action-cost");
    let text = std::fs::read_to_string(root("examples/furuta/furuta-balance.toml")).unwrap();
    let zero = text.replace("action_weights = [0.1]", "action_weights = [0.0]");
    assert_ne!(zero, text);
    let task = dir.join("free.toml");
    std::fs::write(&task, zero).unwrap();
    let out = config(&["--task", task.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(e.contains("free.toml"), "{e}");
    assert!(e.contains("reward.action_weights"), "{e}");
    assert!(
        e.contains("add one to its [reward], e.g. action_weights = ["),
        "{e}"
    );
}

/// The README's path for a system of one's own — a task file, a driver, `rig run --plant
/// external --task` — with no configuration: the Furuta pendulum's balance from ±0.15 rad
/// is learned by the tenth trial (greedy return −30 or more on average over the three
/// start states; −7.09 measured with seed 1; a pendulum that falls ends with −10⁴).
#[test]
fn a_balance_is_learned_without_a_configuration() {
    let Some(python) = python() else {
        return;
    };
    let dir = common::tmp("default-learner", "furuta-balance");
    let task = root("examples/furuta/furuta-balance.toml");
    let task = task.to_str().unwrap();
    let d = Driver::script(
        &python,
        "examples/furuta/driver.py",
        "default",
        &["--task", task],
    );
    let out = ok(rig()
        .args([
            "run", "--plant", "external", "--driver", &d.id, "--task", task,
        ])
        .args(["--trials", "10", "--quiet", "--out"])
        .arg(&dir)
        .output()
        .unwrap());
    assert_eq!(choice_lines(&out).len(), 1, "{out:?}");
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    let last = returns.lines().last().unwrap();
    let greedy: f64 = last.rsplit(',').next().unwrap().parse().unwrap();
    assert!(greedy >= -30.0, "{returns}");
}
