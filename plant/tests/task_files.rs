//! Task files: a new system from a file a test writes, the shipped files, and bad files
//! refused with one line naming the file, the key and what is allowed.

use std::f64::consts::PI;
use std::path::PathBuf;

mod common;

use plant::task::builtin;
use plant::{SystemName, Task, TaskFile};

/// A cart with a pole, which the rig has no simulation of: the states, their ranges, a
/// reference, terminal weights and an operating range on the cart's position.
const CART: &str = r#"
name = "cart-pole"
description = "a cart on a rail balancing a pole"
sampling_time = 0.02
trial_seconds = 5
start_states = [[0.0, "pi", 0.0, 0.0], [0.2, "-0.5pi", 0.0, 0.0]]

[[state]]
name = "x"
unit = "m"
range = [-0.5, 0.5]

[[state]]
name = "theta"
unit = "rad"
angle = true

[[state]]
name = "x_dot"
unit = "m/s"
range = [-2, 2]

[[state]]
name = "theta_dot"
unit = "rad/s"
range = ["-4pi", "4pi"]

[[action]]
name = "force"
unit = "N"
low = -10
high = 10

[reward]
state_weights = [1.0, 5.0, 0.1, 0.1]
action_weights = [0.01]
reference = [0.1, 0.0, 0.0, 0.0]
terminal_weights = [10.0, 50.0, 1.0, 1.0]

[operating_range]
low = [-0.5, -inf, -inf, -inf]
high = [0.5, inf, inf, inf]
penalty = -1000
"#;

fn write(name: &str, text: &str) -> PathBuf {
    common::write("task-files", name, text)
}

#[test]
fn a_new_system_is_a_task_file() {
    let path = write("cart.toml", CART);
    let task = Task::from_file(&path).unwrap();
    assert_eq!(task.name, "cart-pole");
    assert!(task.simulation.is_none(), "a driver serves it");
    assert_eq!((task.state_dim(), task.action_dim()), (4, 1));
    assert_eq!(task.ts, 0.02);
    assert_eq!(task.steps_per_trial(), 250);
    assert_eq!(task.angle_mask, [false, true, false, false]);
    assert_eq!(
        task.state_range,
        [(-0.5, 0.5), (-PI, PI), (-2.0, 2.0), (-4.0 * PI, 4.0 * PI)]
    );
    assert_eq!(
        task.initial_states,
        [vec![0.0, PI, 0.0, 0.0], vec![0.2, -0.5 * PI, 0.0, 0.0]]
    );
    assert_eq!(
        (task.action_low.clone(), task.action_high.clone()),
        (vec![-10.0], vec![10.0])
    );
    assert_eq!(task.state_names, ["x", "theta", "x_dot", "theta_dot"]);
    let range = task.operating_range.as_ref().unwrap();
    assert_eq!(range.penalty, -1000.0);
    assert!(range.excludes(&[0.6, 0.0, 0.0, 0.0]) && !range.excludes(&[0.4, 3.0, 9.0, 9.0]));

    // The reward: errors to the reference, the angle's modulo 2π.
    let r = &task.reward;
    let x = [0.3, 2.0 * PI - 0.1, 1.0, -2.0];
    let want = -(1.0 * 0.2f64.powi(2) + 5.0 * 0.1f64.powi(2) + 0.1 * 1.0 + 0.1 * 4.0);
    assert!((r.state_reward(&x) - want).abs() < 1e-12);
    assert!((r.reward(&x, &[2.0]) - (want - 0.04)).abs() < 1e-12);
    let terminal = -(10.0 * 0.2f64.powi(2) + 50.0 * 0.1f64.powi(2) + 1.0 + 4.0);
    assert!((r.terminal_reward(&x) - terminal).abs() < 1e-12);
    // Its gradients follow from the weights: against finite differences.
    let (mut gx, mut gu) = ([0.0; 4], [0.0]);
    r.grad_x(&x, &mut gx);
    r.grad_u(&[2.0], &mut gu);
    let h = 1e-6;
    for i in 0..4 {
        let (mut a, mut b) = (x, x);
        a[i] += h;
        b[i] -= h;
        let fd = (r.reward(&a, &[2.0]) - r.reward(&b, &[2.0])) / (2.0 * h);
        assert!((fd - gx[i]).abs() < 1e-5, "∂ρ/∂x{i}: {fd} vs {}", gx[i]);
    }
    let fd = (r.reward(&x, &[2.0 + h]) - r.reward(&x, &[2.0 - h])) / (2.0 * h);
    assert!((fd - gu[0]).abs() < 1e-5);
}

#[test]
fn the_shipped_files_are_the_built_in_systems() {
    for system in SystemName::ALL {
        let file = TaskFile::parse(builtin::text(system), None).unwrap();
        assert_eq!(file.name, system.as_str());
        let sim = file
            .simulation
            .as_ref()
            .expect("a built-in system is simulated");
        assert_eq!(sim.system, system);
        // Written out and read back, the file is the same.
        assert_eq!(TaskFile::parse(&file.to_toml(), None).unwrap(), file);
        let task = Task::new(system);
        assert_eq!(task.file, file);
        assert_eq!(task.reward.terminal, task.reward.q, "§4.4: τ_N = −xᵀQx");
    }
    // The values the thesis gives, spot-checked.
    let p = Task::pendulum();
    assert_eq!(p.initial_states, [vec![PI, 0.0]]);
    assert_eq!(p.state_range, [(-PI, PI), (-8.0 * PI, 8.0 * PI)]);
    assert_eq!(p.simulation().substeps, 20);
    let m = Task::new(SystemName::Arm64);
    assert_eq!(m.initial_states.len(), 4);
    assert_eq!(m.operating_range.unwrap().penalty, -4e4);
}

/// `CART` with `from` replaced by `to` (which must occur).
fn edited(from: &str, to: &str) -> String {
    assert!(CART.contains(from), "{from:?}");
    CART.replacen(from, to, 1)
}

#[test]
fn bad_task_files_are_one_line_errors_naming_file_key_and_what_is_allowed() {
    let cases: &[(&str, String, &str)] = &[
        (
            "missing key",
            edited("sampling_time = 0.02\n", ""),
            "missing field `sampling_time`",
        ),
        (
            "unknown key",
            edited("trial_seconds = 5", "trial_seconds = 5\ntrial_secs = 5"),
            "unknown field `trial_secs`, expected one of `name`, `description`, `sampling_time`",
        ),
        (
            "negative sampling time",
            edited("sampling_time = 0.02", "sampling_time = -0.02"),
            "`sampling_time`: -0.02 is out of range: must be a finite number in (0, 60)",
        ),
        (
            "trial shorter than a sample",
            edited("trial_seconds = 5", "trial_seconds = 0.01"),
            "`trial_seconds`: 0.01 is out of range: must be a finite number in [0.02, 200000]",
        ),
        (
            "bound order",
            edited("low = -10\nhigh = 10", "low = 10\nhigh = -10"),
            "`action[0].low`: [10, -10]: the lower bound must be below the upper",
        ),
        (
            "range order",
            edited("range = [-2, 2]", "range = [2, -2]"),
            "`state[2].range`: [2, -2]: the lower bound must be below the upper",
        ),
        (
            "range missing",
            edited("range = [-2, 2]\n", ""),
            "`state[2].range`: is missing: a state that is not an angle needs [low, high]",
        ),
        (
            "wrong dimension of a start state",
            edited("[0.0, \"pi\", 0.0, 0.0]", "[0.0, \"pi\", 0.0]"),
            "`start_states[0]`: has 3 entries; must have 4, one per state",
        ),
        (
            "reward weights of the wrong size",
            edited("action_weights = [0.01]", "action_weights = [0.01, 0.01]"),
            "`reward.action_weights`: has 2 entries; must have 1, one per action",
        ),
        (
            "a negative weight",
            edited("state_weights = [1.0, 5.0", "state_weights = [1.0, -5.0"),
            "`reward.state_weights[1]`: -5 must be a finite number ≥ 0",
        ),
        (
            "a start state outside the operating range",
            edited("[0.2, \"-0.5pi\"", "[0.7, \"-0.5pi\""),
            "`start_states[1][0]`: 0.7 lies outside the operating range [-0.5, 0.5]",
        ),
        (
            "not a multiple of pi",
            edited("\"-4pi\"", "\"-4tau\""),
            "invalid value: string \"-4tau\", expected a number, or a multiple of pi",
        ),
        (
            "a NaN",
            edited("sampling_time = 0.02", "sampling_time = nan"),
            "`sampling_time`: NaN is out of range",
        ),
        (
            "a name the driver contract cannot carry",
            edited("name = \"cart-pole\"", "name = \"cart pole\""),
            "`name`: \"cart pole\" must be 1 to 31 ASCII letters, digits, '-', '_' or '.'",
        ),
        (
            "two states of one name",
            edited("name = \"x_dot\"", "name = \"x\""),
            "`state[2].name`: \"x\" names two states: names must differ",
        ),
        (
            "no actions",
            CART.split("[[action]]").next().unwrap().to_string()
                + CART.split("high = 10\n").nth(1).unwrap(),
            "missing field `action`",
        ),
        (
            "a simulation of other dimensions",
            format!("{CART}\n[simulation]\nsystem = \"pendulum\"\nsubsteps = 20\n"),
            "`simulation.system`: \"pendulum\" has 2 states and 1 actions; the task has 4 and 1",
        ),
        (
            "an unknown simulation",
            format!("{CART}\n[simulation]\nsystem = \"cart\"\nsubsteps = 20\n"),
            "unknown variant `cart`, expected one of `pendulum`, `arm-vertical`",
        ),
        (
            "not TOML",
            edited("[reward]", "[reward"),
            "not a valid task file: line ",
        ),
    ];
    common::assert_refused("task-files", cases);
    let e = Task::from_file(&write("missing", "").with_extension("absent"))
        .err()
        .unwrap();
    assert!(e.to_string().contains("cannot read"), "{e}");
}
