//! The optimal-control reference of the pendulum swing-up (`bench::optimal`): the DP's grid
//! value against the return its policy earns on the plant, grid and action refinement,
//! no learner beating it, and `rig optimal` on the command line.
//!
//! The grids here are coarse (201², 61 action levels: about 4 s with the test profile's
//! optimisation) so the file stays fast; `docs/results/optimal.md` has 401² and 801².

use std::sync::{Arc, OnceLock};

use agent::config::{Algo, ApproxKind};
use bench::optimal::{Optimum, OptimumOptions, pendulum_optimum};
use plant::{Plant, Task};
use runtime::config::{Overrides, resolve};
use runtime::learn::{LearnOptions, Progress, learn};

fn optimum(grid: usize, actions: usize) -> Optimum {
    pendulum_optimum(&OptimumOptions { grid, actions }).expect("valid options")
}

/// 201², 61 action levels, computed once for the whole file.
fn reference() -> &'static Optimum {
    static REF: OnceLock<Optimum> = OnceLock::new();
    REF.get_or_init(|| optimum(201, 61))
}

#[test]
fn the_grid_value_and_the_dp_policy_on_the_plant_agree_within_one_percent() {
    let o = reference();
    eprintln!(
        "201²×61: V_0 = {:.2}, simulated = {:.2}, gap {:.3} %, {:.1} s",
        o.value_grid,
        o.simulated_return,
        100.0 * o.relative_gap(),
        o.wall.as_secs_f64()
    );
    assert!(o.relative_gap() < 0.01, "gap {}", o.relative_gap());
    // A swing-up (never swinging up earns ≈ −4900) that stays well inside the grid's
    // velocity range, so clamping successors at ±8π never mattered.
    assert!(o.simulated_return > -800.0, "{}", o.simulated_return);
    assert!(
        o.max_speed < 0.75 * o.velocity_limit,
        "max |velocity| {} of {}",
        o.max_speed,
        o.velocity_limit
    );
    // The trajectory is one trial exactly as a learner's greedy trial is scored: 100
    // samples from [π, 0] (wrapped to −π), and replaying its actions on a fresh plant
    // gives the same states and rewards, summing to the simulated return.
    let task = Arc::new(Task::pendulum());
    assert_eq!(o.trajectory.len(), task.steps_per_trial());
    assert_eq!(o.trajectory[0].x, vec![-std::f64::consts::PI, 0.0]);
    let mut plant = Plant::new(task.clone());
    plant.reset(&task.initial_states[0]);
    let mut sum = 0.0;
    for s in &o.trajectory {
        assert_eq!(plant.state(), &s.x[..]);
        assert!(s.u[0].abs() <= 3.0);
        let r = plant.step(&s.u);
        assert_eq!(r, s.reward);
        assert_eq!(r, task.reward.reward(&s.x, &s.u), "Eq. 3.16, angle wrapped");
        sum += r;
    }
    assert_eq!(sum, o.simulated_return);
    // Not better than a policy can be: the last state is upright and nearly at rest.
    let last = o.trajectory.last().unwrap();
    assert!(
        last.x[0].abs() < 0.05 && last.x[1].abs() < 0.5,
        "{:?}",
        last.x
    );
}

#[test]
fn the_optimum_converges_with_the_grid_and_the_action_set() {
    let coarse = optimum(101, 61);
    let fine = reference();
    // Grid: the grid value moves towards the simulated return, which barely moves.
    let gap = |o: &Optimum| (o.value_grid - o.simulated_return).abs();
    eprintln!(
        "101²: V_0 = {:.2}, simulated = {:.2}; 201²: {:.2}, {:.2}",
        coarse.value_grid, coarse.simulated_return, fine.value_grid, fine.simulated_return
    );
    assert!(gap(fine) < 0.5 * gap(&coarse));
    assert!((coarse.simulated_return - fine.simulated_return).abs() < 0.005 * 750.0);
    // Actions: 121 levels contain the 61, so the grid value can only rise, and by < 0.1 %.
    let refined = optimum(201, 121);
    eprintln!(
        "201²×121: V_0 = {:.2}, simulated = {:.2}",
        refined.value_grid, refined.simulated_return
    );
    assert!(refined.value_grid >= fine.value_grid);
    let change = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(change(refined.value_grid, fine.value_grid) < 1e-3);
    assert!(change(refined.simulated_return, fine.simulated_return) < 1e-3);
}

/// No learner's greedy return may exceed the optimum. Which bound is strict: the
/// simulated return is a real return, so the true optimum `J*` is at least that; the grid
/// value is an estimate of `J*` of either sign of error, whose size the grid-vs-plant gap
/// measures (it shrinks with the grid: 1.1 %, 0.24 %, 0.10 %, 0.02 % at 101², 201², 401²,
/// 801²). A learner acts on continuous actions, so it may legitimately beat the DP's
/// policy — by at most `J* − simulated` — but not the estimate plus its error:
/// `greedy ≤ max(V_0, simulated) + |V_0 − simulated|`. A learner above that means a bug
/// in the learner's scoring or in the DP.
#[test]
fn no_learner_beats_the_optimum() {
    let o = reference();
    let bound = o.value_grid.max(o.simulated_return) + (o.value_grid - o.simulated_return).abs();
    for algo in [Algo::Mlac, Algo::Sac] {
        let cfg = resolve(
            None,
            &Overrides {
                algo: Some(algo),
                approx: Some(ApproxKind::Llr),
                runs: Some(3),
                ..Default::default()
            },
        )
        .expect("preset");
        let out = std::env::temp_dir().join(format!(
            "rig-optimal-{}-{}",
            std::process::id(),
            cfg.agent().algo
        ));
        let s = learn(
            &cfg,
            &LearnOptions {
                out: out.clone(),
                threads: None,
                progress: Progress::Hidden,
            },
        )
        .expect("learn");
        let greedy: Vec<f64> = s.records.iter().filter_map(|r| r.greedy).collect();
        let best = greedy.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        eprintln!(
            "{}/llr: {} greedy returns ({} runs × {} trials), best {best:.2}; bound {bound:.2}",
            cfg.agent().algo,
            greedy.len(),
            cfg.run().runs,
            cfg.run().trials
        );
        assert_eq!(
            greedy.len() as u32,
            3 * cfg.run().trials / cfg.run().eval_every
        );
        assert!(best <= bound, "{}: {best} > {bound}", cfg.agent().algo);
        // And they do swing up: the best is within 20 % of the optimum.
        assert!(
            best > 1.2 * o.simulated_return,
            "{}: {best}",
            cfg.agent().algo
        );
        let _ = std::fs::remove_dir_all(out);
    }
}

fn rig() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_rig"))
}

#[test]
fn rig_optimal_prints_the_optimum_writes_the_trajectory_and_rejects_bad_sizes() {
    let dir = std::env::temp_dir().join(format!("rig-optimal-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = rig()
        .args(["optimal", "--grid", "41", "--actions", "11", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for text in ["grid value V_0", "DP policy on the plant", "wall time"] {
        assert!(stdout.contains(text), "{stdout}");
    }
    let csv = std::fs::read_to_string(dir.join("optimal.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "t,angle,velocity,u,reward");
    assert_eq!(lines.len(), 101);
    assert!(lines[1].starts_with("0,-3.14159"), "{}", lines[1]);

    for (args, needle) in [
        (
            vec!["--grid", "5"],
            "`--grid` 5 is out of range: must be an integer in [21, 4001]",
        ),
        (
            vec!["--actions", "1"],
            "`--actions` 1 is out of range: must be an integer in [2, 1001]",
        ),
        (
            vec!["--grid", "4001", "--actions", "1001"],
            "`--grid` 4001 with `--actions` 1001",
        ),
        (vec!["--grid", "many"], "--grid"),
    ] {
        let out = rig().arg("optimal").args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
    let help = rig().args(["optimal", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for flag in ["--grid", "--actions", "--out", "[21, 4001]", "[2, 1001]"] {
        assert!(help.contains(flag), "{help}");
    }
    let _ = std::fs::remove_dir_all(dir);
}
