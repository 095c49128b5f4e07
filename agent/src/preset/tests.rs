//! Every preset validates; Chapter 4's are those of §4.4.

use super::*;
use crate::config::Component;

#[test]
fn every_supported_preset_validates() {
    for system in SystemName::ALL {
        for algo in Algo::ALL {
            for approx in ApproxKind::ALL {
                for horizon in HorizonKind::ALL {
                    let supported = algo.approximators().contains(&approx)
                        && (horizon == HorizonKind::Infinite
                            || (algo.has_actor() && approx == ApproxKind::Rbf));
                    let task = Task::new(system);
                    match preset(system, algo, approx, horizon) {
                        Ok(p) => p
                            .agent
                            .validate(&task)
                            .and_then(|()| p.run.validate(&task))
                            .unwrap_or_else(|e| panic!("{system}/{algo}/{approx}/{horizon}: {e}")),
                        Err(e) => assert!(!supported, "{e}"),
                    }
                }
            }
        }
    }
}

#[test]
fn finite_horizon_presets_are_those_of_section_4_4() {
    let rates = |algo| {
        let Preset { agent: c, run } = preset(
            SystemName::Pendulum,
            algo,
            ApproxKind::Rbf,
            HorizonKind::Finite,
        )
        .unwrap();
        assert_eq!((run.trials, run.runs, c.learning.gamma), (600, 20, 1.0));
        let Some(Component::Rbf(a)) = c.actor else {
            panic!()
        };
        let Component::Rbf(v) = c.critic else {
            panic!()
        };
        assert_eq!((&a.centres, &v.centres), (&vec![9; 3], &vec![9; 3]));
        let p = c.model.map(|m| m.alpha());
        (a.alpha, v.alpha, p, a.intersection, v.intersection)
    };
    assert_eq!(rates(Algo::Sac), (0.05, 0.2, None, 0.55, 0.55));
    assert_eq!(rates(Algo::Mlac), (0.15, 0.4, Some(0.8), 0.55, 0.65));
    assert_eq!(rates(Algo::Rmac), (0.6, 0.2, Some(0.6), 0.7, 0.7));
}

/// Every supported (algorithm, approximator, horizon), with `f` on each preset's result.
fn each_supported(mut f: impl FnMut(Algo, ApproxKind, HorizonKind)) {
    for algo in Algo::ALL {
        for &approx in algo.approximators() {
            f(algo, approx, HorizonKind::Infinite);
            if algo.has_actor() && approx == ApproxKind::Rbf {
                f(algo, approx, HorizonKind::Finite);
            }
        }
    }
}

/// The task of `text` with its `[simulation]` table removed: one only a driver serves.
fn driven(text: &str) -> Task {
    let text = text.split("[simulation]").next().unwrap();
    plant::TaskFile::parse(text, None)
        .and_then(|f| f.task(None))
        .unwrap()
}

#[test]
fn the_rules_carry_the_pendulum_preset_over_to_the_pendulum_itself() {
    let task = driven(plant::task::builtin::text(SystemName::Pendulum));
    each_supported(|algo, approx, horizon| {
        assert_eq!(
            for_task(&task, algo, approx, horizon).unwrap(),
            preset(SystemName::Pendulum, algo, approx, horizon).unwrap(),
            "{algo}/{approx}/{horizon}"
        );
    });
}

/// The discount of a task without a thesis preset comes from its time scale in seconds:
/// the pendulum's 0.97 for the pendulum's 30 ms and 3 s trials; the same horizon (1 s,
/// a third of the trial) for other sampling times and trial lengths; a finite horizon
/// keeps `γ = 1`.
#[test]
fn the_discount_of_a_task_is_a_third_of_its_trial_in_seconds() {
    let pendulum = plant::task::builtin::text(SystemName::Pendulum);
    let task = |ts: &str, seconds: &str| {
        let text = pendulum
            .replace("sampling_time = 0.03", &format!("sampling_time = {ts}"))
            .replace("trial_seconds = 3.0", &format!("trial_seconds = {seconds}"));
        assert_eq!(text != pendulum, ts != "0.03" || seconds != "3.0", "{text}");
        driven(&text)
    };
    let gamma = |t: &Task, horizon| {
        for_task(t, Algo::Mlac, ApproxKind::Rbf, horizon)
            .unwrap()
            .agent
            .learning
            .gamma
    };
    let infinite = HorizonKind::Infinite;
    assert_eq!(gamma(&task("0.03", "3.0"), infinite), 0.97);
    assert_eq!(rules::discount(&task("0.03", "3.0")), 0.97);
    let cases = [
        ("0.01", "3.0", 0.99),
        ("0.03", "4.0", 0.9775),
        ("0.01", "4.0", 0.9925),
    ];
    for (ts, seconds, want) in cases {
        let g = gamma(&task(ts, seconds), infinite);
        assert!((g - want).abs() < 1e-12, "Ts {ts}, trial {seconds}: {g}");
    }
    // 999 samples of a trial (a Gymnasium time limit): 1 − 3/999.
    let long = gamma(&task("0.01", "9.99"), infinite);
    assert!((long - (1.0 - 3.0 / 999.0)).abs() < 1e-12, "{long}");
    assert_eq!(gamma(&task("0.03", "0.06"), infinite), rules::MIN_DISCOUNT);
    assert_eq!(gamma(&task("0.01", "4.0"), HorizonKind::Finite), 1.0);
}

/// A rotary pendulum's shape: four states (arm and pendulum angles, their velocities) and
/// one action of ±10 V.
const ROTARY: &str = r#"
name = "rotary"
sampling_time = 0.01
trial_seconds = 4
start_states = [[0.0, "pi", 0.0, 0.0]]
[[state]]
name = "theta"
angle = true
[[state]]
name = "alpha"
angle = true
[[state]]
name = "theta_dot"
range = ["-10pi", "10pi"]
[[state]]
name = "alpha_dot"
range = ["-20pi", "20pi"]
[[action]]
name = "v"
low = -10
high = 10
[reward]
state_weights = [1, 5, 0.1, 0.1]
action_weights = [0.1]
"#;

#[test]
fn the_rules_fit_a_task_of_other_dimensions_and_ranges() {
    let task = driven(ROTARY);
    each_supported(|algo, approx, horizon| {
        let p = for_task(&task, algo, approx, horizon).unwrap();
        p.agent
            .validate(&task)
            .unwrap_or_else(|e| panic!("{algo}/{approx}/{horizon}: {e}"));
        let pendulum = preset(SystemName::Pendulum, algo, approx, horizon).unwrap();
        // σ scaled to the ±10 V bounds.
        assert_eq!(
            p.agent.learning.sigma,
            pendulum.agent.learning.sigma * 10.0 / 3.0
        );
        for c in [
            p.agent.actor.as_ref(),
            Some(&p.agent.critic),
            p.agent.model.as_ref(),
        ]
        .into_iter()
        .flatten()
        {
            match c {
                Component::Rbf(r) => {
                    assert!(r.centres.iter().product::<usize>() <= rules::MAX_GRID)
                }
                Component::Lstd(l) => {
                    assert!(
                        l.centres.iter().product::<usize>() <= 400,
                        "the pendulum's LSTD grid at most"
                    )
                }
                Component::Tiles(t) => {
                    assert!(t.tiles.iter().product::<usize>() <= rules::MAX_GRID)
                }
                Component::Llr(l) => assert!(l.neighbours >= 2 * (l.weights.len() + 1)),
            }
        }
    });
    // MLAC/LLR by hand: angles weigh as the pendulum's angle, the velocities by their
    // ranges (the pendulum's 0.1 at ±8π), the voltage by its bounds.
    let p = for_task(&task, Algo::Mlac, ApproxKind::Llr, HorizonKind::Infinite).unwrap();
    let Some(Component::Llr(actor)) = &p.agent.actor else {
        panic!()
    };
    assert_eq!(
        actor.weights,
        [1.0, 1.0, 0.1 * 8.0 / 10.0, 0.1 * 8.0 / 20.0]
    );
    assert_eq!((actor.memory, actor.neighbours), (4000, 25));
    let Some(Component::Llr(model)) = &p.agent.model else {
        panic!()
    };
    assert_eq!(model.weights[4], 1.0 * 3.0 / 10.0);
    assert_eq!((model.memory, model.neighbours), (200, 12));
}
