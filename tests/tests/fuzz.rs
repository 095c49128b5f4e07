//! Fuzz-style robustness, for a real motor driver swapped in: random, NaN and
//! extreme values through the action path and through configuration files must never
//! panic and never actuate outside the limits. Deterministic: every input derives from
//! a fixed seed, so a failure names a reproducible case.

use std::path::Path;
use std::sync::Arc;

use plant::{Plant, SystemName, Task};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use runtime::config::{Overrides, resolve};

/// A value a broken agent, a corrupted message or a hostile sender could produce.
fn wild_f64(rng: &mut ChaCha8Rng) -> f64 {
    match rng.random_range(0..8) {
        0 => f64::from_bits(rng.random()),
        1 => f64::NAN,
        2 => f64::INFINITY,
        3 => f64::NEG_INFINITY,
        4 => f64::MAX * if rng.random() { 1.0 } else { -1.0 },
        5 => f64::MIN_POSITIVE * 0.5,
        6 => rng.random_range(-1e6..1e6),
        _ => rng.random_range(-5.0..5.0),
    }
}

#[test]
fn random_actions_never_actuate_outside_the_limits() {
    let mut rng = ChaCha8Rng::seed_from_u64(0xF022);
    for system in SystemName::ALL {
        let task = Arc::new(Task::new(system));
        let mut plant = Plant::new(task.clone());
        let x0 = task.initial_states[0].clone();
        plant.reset(&x0);
        let mut u = vec![0.0; task.action_dim()];
        for step in 0..2000 {
            u.iter_mut().for_each(|v| *v = wild_f64(&mut rng));
            let r = plant.step(&u);
            for (j, a) in plant.applied_action().iter().enumerate() {
                assert!(
                    a.is_finite() && *a >= task.action_low[j] && *a <= task.action_high[j],
                    "{system} step {step}: action {u:?} applied as {a}"
                );
            }
            assert!(!r.is_nan(), "{system} step {step}: reward NaN");
            assert!(
                plant.state().iter().all(|x| x.is_finite()),
                "{system} step {step}: state {:?}",
                plant.state()
            );
            if plant.terminated() || step % 200 == 199 {
                plant.reset(&x0);
            }
        }
    }
}

/// Replaces the value of a random `key = value` line of `text` by a wild one, or, a
/// quarter of the time, by one of `forms`.
fn mutate(text: &str, rng: &mut ChaCha8Rng, forms: &[&str]) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let keyed: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains(" = "))
        .collect();
    for _ in 0..rng.random_range(1..3) {
        let i = keyed[rng.random_range(0..keyed.len())];
        let (key, old) = lines[i].split_once(" = ").unwrap();
        let (key, old) = (key.to_string(), old.trim().to_string());
        let value = if !forms.is_empty() && rng.random_range(0..4) == 0 {
            forms[rng.random_range(0..forms.len())].to_string()
        } else {
            wild_value(&old, rng)
        };
        lines[i] = format!("{key} = {value}");
    }
    lines.join("\n")
}

/// A wild replacement of the value `old`.
fn wild_value(old: &str, rng: &mut ChaCha8Rng) -> String {
    match rng.random_range(0..16) {
        // Plausible edits: the preset's number scaled, or a nearby integer.
        10..=15 => match (old.parse::<i64>(), old.parse::<f64>()) {
            (Ok(n), _) => format!("{}", n + rng.random_range(-2..=3)),
            (_, Ok(v)) => format!("{:?}", v * rng.random_range(0.3..3.0)),
            _ => old.to_string(),
        },
        0 => "nan".to_string(),
        1 => "inf".to_string(),
        2 => "-1".to_string(),
        3 => "0".to_string(),
        4 => "1e308".to_string(),
        5 => "18446744073709551615".to_string(),
        6 => "\"pendulum\"".to_string(),
        7 => "[]".to_string(),
        8 => format!("[{}, 0]", rng.random_range(-3..100_000)),
        _ => format!("{}", rng.random_range(-10.0..10.0)),
    }
}

/// An agent of `learner` learns 20 samples on `task`'s plant, every action applied within
/// the bounds.
fn learns_within_the_limits(task: Arc<Task>, learner: &agent::config::AgentConfig) {
    let learner = learner
        .resolve(&task)
        .expect("a configuration that resolved has a learner");
    let mut agent = agent::build(&task, &learner, 1);
    let mut plant = Plant::new(task.clone());
    let mut u = vec![0.0; task.action_dim()];
    plant.reset(&task.initial_states[0]);
    agent.start_trial(plant.state(), &mut u);
    for _ in 0..20 {
        let r = plant.step(&u);
        for (j, a) in plant.applied_action().iter().enumerate() {
            assert!(*a >= task.action_low[j] && *a <= task.action_high[j]);
        }
        let x = plant.state().to_vec();
        agent.learn(r, &x, Some(&mut u));
    }
}

#[test]
fn mutated_configuration_files_are_errors_or_run_but_never_panic() {
    let mut rng = ChaCha8Rng::seed_from_u64(0xC0F1);
    let path = Path::new("fuzz.toml");
    let (mut accepted, mut rejected) = (0, 0);
    for case in 0..300 {
        let system = SystemName::ALL[rng.random_range(0..SystemName::ALL.len())];
        let algos = agent::config::Algo::ALL;
        let algo = algos[rng.random_range(0..algos.len())];
        let approx = algo.approximators()[rng.random_range(0..algo.approximators().len())];
        let o = Overrides {
            system: Some(system),
            algo: Some(algo),
            approx: Some(approx),
            ..Default::default()
        };
        let base = resolve(None, &o).unwrap().to_toml();
        let text = mutate(&base, &mut rng, &[]);
        let outcome = std::panic::catch_unwind(|| match resolve(Some((path, &text)), &o) {
            Err(e) => {
                let msg = e.to_string();
                assert!(!msg.contains('\n'), "a one-line error: {msg}");
                false
            }
            Ok(cfg) => {
                // Accepted: it must build and learn a few samples within the limits.
                learns_within_the_limits(cfg.task(), cfg.agent());
                true
            }
        });
        match outcome {
            Ok(true) => accepted += 1,
            Ok(false) => rejected += 1,
            Err(_) => panic!("case {case} ({system}/{algo}/{approx}) panicked on:\n{text}"),
        }
    }
    eprintln!("mutated configurations: {accepted} accepted and run, {rejected} rejected");
    // Both branches were exercised.
    assert!(
        accepted > 10 && rejected > 10,
        "{accepted} accepted, {rejected} rejected"
    );
}

#[test]
fn mutated_task_files_are_errors_or_run_but_never_panic() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x7A5C);
    let path = Path::new("task.toml");
    let (mut accepted, mut rejected) = (0, 0);
    for case in 0..400 {
        let system = SystemName::ALL[rng.random_range(0..SystemName::ALL.len())];
        // Besides wild values, the forms of task files: multiples of π, ranges, infinite
        // bounds, start states.
        let forms = [
            "\"-2pi\"",
            "\"pi\"",
            "[1, -1]",
            "[\"pi\", 0]",
            "-inf",
            "[[0.0, 0.0]]",
        ];
        let text = mutate(plant::task::builtin::text(system), &mut rng, &forms);
        let outcome = std::panic::catch_unwind(|| {
            let task =
                match plant::TaskFile::parse(&text, Some(path)).and_then(|f| f.task(Some(path))) {
                    Err(e) => {
                        let msg = e.to_string();
                        assert!(!msg.contains('\n'), "a one-line error: {msg}");
                        assert!(msg.starts_with("task.toml: "), "names the file: {msg}");
                        return false;
                    }
                    Ok(task) => Arc::new(task),
                };
            // Accepted: the system's preset learns on it within the limits.
            let sim = task.simulation().system;
            let o = Overrides {
                system: Some(sim),
                ..Default::default()
            };
            learns_within_the_limits(task, resolve(None, &o).unwrap().agent());
            true
        });
        match outcome {
            Ok(true) => accepted += 1,
            Ok(false) => rejected += 1,
            Err(_) => panic!("case {case} ({system}) panicked on:\n{text}"),
        }
    }
    eprintln!("mutated task files: {accepted} accepted and run, {rejected} rejected");
    assert!(
        accepted > 10 && rejected > 10,
        "{accepted} accepted, {rejected} rejected"
    );
}
