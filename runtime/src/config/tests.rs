//! Resolution, validation and the TOML form of whole experiments.

use std::path::Path;

use agent::config::{Algo, ApproxKind, Component, FitAt, HorizonKind, LstdPrior, PlanningMethod};
use observer::config::{ObserverMode, ObserverModel, SensorKind};
use plant::SystemName;
use plant::config::ConfigError;

use super::*;

fn resolve_str(text: &str) -> Result<ExperimentConfig, ConfigError> {
    resolve(Some((Path::new("exp.toml"), text)), &Overrides::default())
}

#[test]
fn default_is_pendulum_mlac_llr_with_table_3_2() {
    let c = resolve(None, &Overrides::default()).unwrap();
    assert_eq!(
        (c.system, c.agent().algo, c.agent().approx),
        (SystemName::Pendulum, Algo::Mlac, ApproxKind::Llr)
    );
    let Some(Component::Llr(actor)) = &c.agent().actor else {
        panic!()
    };
    assert_eq!(
        (actor.alpha, actor.memory, actor.neighbours),
        (0.05, 2000, 25)
    );
}

#[test]
fn file_overrides_and_round_trips() {
    let c = resolve_str("algo = \"sac\"\n[critic]\nneighbours = 12\n[run]\nruns = 3\n").unwrap();
    assert_eq!(c.agent().algo, Algo::Sac);
    assert_eq!(c.run().runs, 3);
    let Component::Llr(critic) = &c.agent().critic else {
        panic!()
    };
    assert_eq!(critic.neighbours, 12);
    let again: ExperimentConfig = toml::from_str(&c.to_toml()).unwrap();
    assert_eq!(again, c);
    // A resolved configuration fed back as a file resolves to itself.
    assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
}

#[test]
fn unknown_key_is_named() {
    let e = resolve_str("[actor]\nalpa = 0.1\n").unwrap_err();
    assert_eq!(e.key, "actor.alpa");
    assert!(
        e.to_string()
            .starts_with("exp.toml: `actor.alpa`: unknown key"),
        "{e}"
    );
    assert!(
        e.message
            .contains("alpha, clip_to_neighbours, eviction, memory, neighbours"),
        "{e}"
    );
}

#[test]
fn out_of_range_is_named_with_the_range() {
    let e = resolve_str("[learning]\ngamma = 1.5\n").unwrap_err();
    assert_eq!(e.key, "learning.gamma");
    assert!(e.message.contains("(0, 1)"), "{e}");
    let e = resolve_str("[critic]\nneighbours = 0\n").unwrap_err();
    assert_eq!(e.key, "critic.neighbours");
    assert!(e.message.contains("1..=128"), "{e}");
    let e = resolve_str("[actor]\nweights = [1.0]\n").unwrap_err();
    assert_eq!(e.key, "actor.weights");
    let e = resolve_str("[actor]\nmemory = \"big\"\n").unwrap_err();
    assert!(e.message.contains("wrong type"), "{e}");
    let e = resolve_str("system = \"cartpole\"\n").unwrap_err();
    assert!(e.message.contains("pendulum, arm-vertical"), "{e}");
}

#[test]
fn finite_horizon_adds_time_to_actor_and_critic() {
    let c = resolve_str("horizon = \"finite\"\nalgo = \"sac\"\napprox = \"rbf\"\n").unwrap();
    assert_eq!(c.agent().horizon, HorizonKind::Finite);
    assert_eq!(
        c.agent().learning.gamma,
        1.0,
        "Algorithms 4–6 do not discount"
    );
    assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
    let e = resolve_str("horizon = \"finit\"\n").unwrap_err();
    assert_eq!(e.key, "horizon");
    assert!(e.to_string().starts_with("exp.toml: `horizon`"), "{e}");
    assert!(e.message.contains("infinite, finite"), "{e}");
    let fh = "horizon = \"finite\"\nalgo = \"mlac\"\napprox = \"rbf\"\n";
    let e = resolve_str(&format!("{fh}[critic]\ncentres = [9, 9]\n")).unwrap_err();
    assert_eq!(e.key, "critic.centres");
    assert!(
        e.message
            .contains("must have 3, one per state component and time"),
        "{e}"
    );
    assert!(resolve_str(&format!("{fh}[learning]\ngamma = 1.01\n")).is_err());
    let e = resolve_str("[learning]\ngamma = 1.0\n").unwrap_err();
    assert_eq!(e.key, "learning.gamma", "an infinite horizon must discount");
    let e = resolve_str("horizon = \"finite\"\nalgo = \"vgbp\"\napprox = \"lstd\"\n").unwrap_err();
    assert_eq!(e.key, "horizon");
    let e = resolve_str("horizon = \"finite\"\nalgo = \"sac\"\napprox = \"llr\"\n").unwrap_err();
    assert_eq!(e.key, "approx");
    // Validation, for a configuration not made by `resolve`.
    let mut c = c;
    let before = c.clone();
    let e = c.change_agent(|a| a.algo = Algo::Sarsa).unwrap_err();
    assert_eq!(e.key, "horizon");
    assert_eq!(
        c, before,
        "a refused change leaves the configuration as it was"
    );
}

#[test]
fn tile_coding_is_for_sac_only() {
    let o = Overrides {
        algo: Some(Algo::Mlac),
        approx: Some(ApproxKind::Tiles),
        ..Default::default()
    };
    let e = resolve(None, &o).unwrap_err();
    assert_eq!(e.key, "approx");
}

#[test]
fn the_default_observer_section_is_not_written() {
    let c = resolve(None, &Overrides::default()).unwrap();
    assert!(c.observer().is_default());
    assert!(!c.to_toml().contains("[observer]"));
}

#[test]
fn observer_keys_resolve_and_round_trip() {
    let text = "[observer]\nsensor = \"angle\"\ncounts_per_rev = 1024\nobserver = \"predictive\"\nmodel = \"known\"\n";
    let c = resolve(Some((Path::new("o.toml"), text)), &Overrides::default()).unwrap();
    assert_eq!(c.observer().sensor, SensorKind::Angle);
    assert_eq!(c.observer().counts_per_rev, 1024);
    assert_eq!(c.observer().model, ObserverModel::Known);
    let again = resolve(
        Some((Path::new("c.toml"), &c.to_toml())),
        &Overrides::default(),
    )
    .unwrap();
    assert_eq!(again, c);
}

#[test]
fn lstd_prior_choices_and_errors() {
    let vgbp = "algo = \"vgbp\"\napprox = \"lstd\"\n";
    let none = Overrides::default();
    let file = |text: String| resolve(Some((Path::new("v.toml"), &text)), &none);
    let prior = |c: &ExperimentConfig| match &c.agent().critic {
        Component::Lstd(l) => l.prior,
        other => panic!("not LSTD: {other:?}"),
    };
    assert_eq!(prior(&file(vgbp.to_string()).unwrap()), LstdPrior::Zero);
    let c = file(format!("{vgbp}[critic]\nprior = \"reward\"\n")).unwrap();
    assert_eq!(prior(&c), LstdPrior::Reward);
    // The default is not written; the other choice is, and reads back.
    assert!(!file(vgbp.to_string()).unwrap().to_toml().contains("prior"));
    let again = file(c.to_toml()).unwrap();
    assert_eq!(prior(&again), LstdPrior::Reward);
    let e = file(format!("{vgbp}[critic]\nprior = \"pessimistic\"\n"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "v.toml: `critic.prior`: \"pessimistic\" is not one of: zero, reward"
    );
}

#[test]
fn observer_errors_name_file_key_and_range() {
    let bad = |text: &str, o: &Overrides| {
        resolve(Some((Path::new("o.toml"), text)), o)
            .unwrap_err()
            .to_string()
    };
    let none = Overrides::default();
    let e = bad("[observer]\nsensor = \"camera\"\n", &none);
    assert_eq!(
        e,
        "o.toml: `observer.sensor`: \"camera\" is not one of: full, angle"
    );
    let e = bad("[observer]\ncounts_per_rev = 2\n", &none);
    assert!(
        e.starts_with("o.toml: `observer.counts_per_rev`: 2 is out of range"),
        "{e}"
    );
    let e = bad("[observer]\ngain = 2.5\n", &none);
    assert!(e.contains("`observer.gain`") && e.contains("[0, 2)"), "{e}");
    let e = bad("[observer]\nnoise_std = -1.0\n", &none);
    assert!(e.contains("`observer.noise_std`"), "{e}");
    let angle = Overrides {
        sensor: Some(SensorKind::Angle),
        ..Default::default()
    };
    let e = bad("", &angle);
    assert!(
        e.contains("`observer.observer`") && e.contains("pass-through"),
        "{e}"
    );
    let e = bad("[observer]\nfilter = 1.0\n", &none);
    assert!(e.contains("`observer.filter`"), "{e}");
}

#[test]
fn timing_and_delay_keys_resolve_round_trip_and_are_checked() {
    let text = "[observer]\nsensor = \"angle\"\nobserver = \"predictive\"\nmode = \"predictive\"\n";
    let c = resolve(Some((Path::new("t.toml"), text)), &Overrides::default()).unwrap();
    assert_eq!(c.observer().mode, ObserverMode::Predictive);
    let again = resolve(
        Some((Path::new("c.toml"), &c.to_toml())),
        &Overrides::default(),
    );
    assert_eq!(again.unwrap(), c);
    let bad = |text: &str| {
        resolve(Some((Path::new("t.toml"), text)), &Overrides::default())
            .unwrap_err()
            .to_string()
    };
    let e = bad("[observer]\nmode = \"predictive\"\n");
    assert!(
        e.contains("`observer.mode`") && e.contains("predictive"),
        "{e}"
    );
    let e = bad("[observer]\nmode = \"late\"\n");
    assert!(
        e.contains("`observer.mode`") && e.contains("direct, predictive"),
        "{e}"
    );
    let csv = std::env::temp_dir().join(format!("cfg-delays-{}.csv", std::process::id()));
    std::fs::write(&csv, "delay_ms\n1\n2\n").unwrap();
    let from = format!("[run]\ndelay_from = {:?}\n", csv.display().to_string());
    let c = resolve(Some((Path::new("t.toml"), &from)), &Overrides::default()).unwrap();
    assert!(c.to_toml().contains("delay_from"));
    let e = bad(&format!("{from}delay_ms = 3.0\n"));
    assert!(
        e.contains("`run.delay_from`") && e.contains("exclusive"),
        "{e}"
    );
    let e = bad("[run]\ndelay_column = \"x_ms\"\n");
    assert!(e.contains("`run.delay_column`"), "{e}");
    // The default configuration does not mention the optional keys.
    let plain = resolve(None, &Overrides::default()).unwrap().to_toml();
    assert!(!plain.contains("delay_from") && !plain.contains("\nmode ="));
}

#[test]
fn a_checkpoint_origin_fingerprints_the_learning_parameters() {
    let cfg = resolve(None, &Overrides::default()).unwrap();
    let origin = cfg.origin(0);
    // The fingerprints of checkpoints already written: they must not change.
    assert_eq!(origin.fingerprint, 15377454252297950925);
    let vgbp = Overrides {
        algo: Some(Algo::Vgbp),
        approx: Some(ApproxKind::Lstd),
        ..Default::default()
    };
    let vgbp = resolve(None, &vgbp).unwrap().origin(3);
    assert_eq!(vgbp.fingerprint, 7102850041982682030);
    assert_eq!((vgbp.learner.as_str(), vgbp.run), ("vgbp/lstd/infinite", 3));
    assert_eq!((origin.system.as_str(), origin.seed), ("pendulum", 1));
    let mut longer = cfg.clone();
    longer
        .change_run(|r| {
            r.trials += 10;
            r.runs += 1;
            r.eval_every = 0;
        })
        .unwrap();
    assert_eq!(longer.origin(0), origin, "more trials is the same learner");
    let mut tuned = cfg.clone();
    tuned.change_agent(|a| a.learning.gamma = 0.5).unwrap();
    assert_ne!(tuned.origin(0).fingerprint, origin.fingerprint);
    let mut reseeded = cfg;
    reseeded.change_run(|r| r.seed = 2).unwrap();
    assert_ne!(reseeded.origin(0).fingerprint, origin.fingerprint);
}

#[test]
fn the_learner_is_resolved_once_and_again_on_each_change() {
    let mut c = resolve(None, &Overrides::default()).unwrap();
    assert!(
        std::ptr::eq(c.learner(), c.clone().learner()),
        "copies share it"
    );
    assert_eq!(c.learner(), &c.agent().resolve(&c.task()).unwrap());
    c.change_agent(|a| a.learning.gamma = 0.9).unwrap();
    assert_eq!(c.learner().learning.gamma, 0.9);
    assert_eq!(c.learner(), &c.agent().resolve(&c.task()).unwrap());
}

#[test]
fn a_change_that_breaks_a_rule_is_refused_and_changes_nothing() {
    let fh = Overrides {
        algo: Some(Algo::Sac),
        approx: Some(ApproxKind::Rbf),
        horizon: Some(HorizonKind::Finite),
        ..Default::default()
    };
    let mut c = resolve(None, &fh).unwrap();
    let before = c.clone();
    // Across sections: predictive timing needs an infinite horizon.
    let e = c
        .change_observer(|o| {
            o.sensor = SensorKind::Angle;
            o.observer = observer::config::ObserverKind::Predictive;
            o.mode = ObserverMode::Predictive;
        })
        .unwrap_err();
    assert_eq!(e.key, "observer.mode");
    // Against the task: a delay of a whole sample period.
    let ts_ms = c.task().ts * 1e3;
    let e = c.change_run(|r| r.delay_ms = ts_ms).unwrap_err();
    assert_eq!(e.key, "run.delay_ms");
    // Within the learner: SAC needs an actor.
    let e = c.change_agent(|a| a.actor = None).unwrap_err();
    assert_eq!(e.key, "actor");
    let e = c.change_run(|r| r.runs = 0).unwrap_err();
    assert_eq!(e.key, "run.runs");
    assert_eq!(c, before);
    assert_eq!(c.learner(), before.learner());
    assert_eq!(c.to_toml(), before.to_toml());
}

#[test]
fn one_run_changes_the_run_count_only() {
    let c = resolve(None, &Overrides::default()).unwrap();
    let one = c.one_run();
    assert_eq!(one.run().runs, 1);
    let mut back = one.clone();
    back.change_run(|r| r.runs = c.run().runs).unwrap();
    assert_eq!(back.to_toml(), c.to_toml());
}

#[test]
fn the_task_is_read_once_and_shared_by_copies() {
    let c = resolve(None, &Overrides::default()).unwrap();
    assert!(std::sync::Arc::ptr_eq(&c.task(), &c.task()));
    assert!(std::sync::Arc::ptr_eq(&c.task(), &c.clone().task()));
    assert_eq!(c.task().name, "pendulum");
}

#[test]
fn an_unknown_eviction_rule_is_named_with_the_rules() {
    let e = resolve_str("[actor]\neviction = \"newest\"\n").unwrap_err();
    assert_eq!(
        e.to_string(),
        "exp.toml: `actor.eviction`: \"newest\" is not one of: oldest, redundant"
    );
}

#[test]
fn the_learner_is_the_algorithm_with_its_components() {
    use agent::learner::{Algorithm, Plain, Smooth};
    let o = |algo, approx| Overrides {
        algo: Some(algo),
        approx: Some(approx),
        ..Default::default()
    };
    let c = resolve(None, &o(Algo::Sac, ApproxKind::Tiles)).unwrap();
    let Algorithm::Sac(sac) = &c.learner().algorithm else {
        panic!("not SAC")
    };
    assert!(matches!(sac.critic, Plain::Tiles(_)), "{sac:?}");
    let c = resolve(None, &o(Algo::Rmac, ApproxKind::Rbf)).unwrap();
    let Algorithm::Rmac(rmac) = &c.learner().algorithm else {
        panic!("not RMAC")
    };
    assert!(matches!(rmac.model, Smooth::Rbf(_)), "{rmac:?}");
    // A component the algorithm cannot use is an error of the learner, naming its key.
    let mut bad = c.clone();
    let e = bad.change_agent(|a| a.model = None).unwrap_err();
    assert_eq!(
        (e.key.as_str(), e.message.as_str()),
        (
            "model",
            "rmac learns a process model: a [model] section is required"
        )
    );
}

/// The command line's flags: with the feature `cli` (on in `rig`'s build).
#[cfg(feature = "cli")]
#[test]
fn help_lists_the_choices() {
    use clap::{CommandFactory, Parser};
    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        o: Overrides,
    }
    let help = Cli::command().render_long_help().to_string();
    // Each value with its doc comment as its help.
    for value in [
        "- sac:   Standard actor-critic (Algorithm 1).",
        "- sarsa: SARSA(λ) with ε-greedy discrete actions (§6.2), critic-only.",
        "- llr:",
        "- lstd:",
        "- pendulum:",
        "- arm-6.4:",
        "- double-integrator:",
        "- pass-through:",
        "- predictive:",
    ] {
        assert!(help.contains(value), "{value} not in\n{help}");
    }
    let cli = Cli::try_parse_from(["rig", "--algo", "vgbp", "--system", "arm-6.4"]).unwrap();
    assert_eq!(
        (cli.o.algo, cli.o.system),
        (Some(Algo::Vgbp), Some(SystemName::Arm64))
    );
    assert!(Cli::try_parse_from(["rig", "--algo", "ddpg"]).is_err());
}

/// `[planning]`, which no preset has: a file adds it whole, it round-trips, and a wrong
/// key, value or algorithm is named.
#[test]
fn a_planning_section_is_added_checked_and_round_trips() {
    let plan = "[planning]\nhorizon = 15\nsamples = 64\nelites = 8\niterations = 3\n";
    let c = resolve_str(plan).unwrap();
    let p = c.agent().planning.as_ref().unwrap();
    assert_eq!(
        (p.horizon, p.samples, p.elites, p.iterations),
        (15, Some(64), Some(8), 3)
    );
    assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
    assert!(
        !c.to_toml().contains("method"),
        "the default method is not written"
    );
    assert!(
        resolve(None, &Overrides::default())
            .unwrap()
            .agent
            .planning
            .is_none()
    );
    let e = resolve_str(&plan.replace("elites = 8", "elites = 80")).unwrap_err();
    assert_eq!(e.key, "planning.elites", "{e}");
    assert!(
        e.message.contains("2..=64") || e.message.contains("1..=64"),
        "{e}"
    );
    let e = resolve_str(&plan.replace("horizon", "horizn")).unwrap_err();
    assert!(e.to_string().contains("horizn"), "{e}");
    let e = resolve_str(&format!("algo = \"sac\"\n{plan}")).unwrap_err();
    assert_eq!(e.key, "planning", "{e}");
    assert!(e.message.contains("remove the [planning] section"), "{e}");
}

/// `[planning]` with `method = "ilqr"`: horizon, iterations and whether to start from the
/// regulator's rollout; it round-trips, and the cross-entropy method's keys (or
/// `start_from_regulator` given to it) or a wrong method are named.
#[test]
fn an_ilqr_planning_section_resolves_and_round_trips() {
    let ilqr = "[planning]\nmethod = \"ilqr\"\nhorizon = 40\niterations = 3\n";
    let c = resolve_str(ilqr).unwrap();
    let p = c.agent().planning.as_ref().unwrap();
    assert_eq!(
        (p.method, p.horizon, p.iterations),
        (PlanningMethod::Ilqr, 40, 3)
    );
    assert!(c.to_toml().contains("method = \"ilqr\""), "{}", c.to_toml());
    assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
    let e = resolve_str(&format!("{ilqr}elites = 8\n")).unwrap_err();
    assert_eq!(e.key, "planning.elites", "{e}");
    let e = resolve_str(&ilqr.replace("ilqr", "ilq")).unwrap_err();
    assert!(e.to_string().contains("ilq"), "{e}");
    assert!(e.to_string().contains("cem"), "names the methods: {e}");
    let e = resolve_str(&ilqr.replace("horizon = 40", "horizon = 0")).unwrap_err();
    assert_eq!(e.key, "planning.horizon", "{e}");
    assert!(!p.start_from_regulator);
    assert!(
        !c.to_toml().contains("start_from_regulator"),
        "{}",
        c.to_toml()
    );
    let regulated = resolve_str(&format!("{ilqr}start_from_regulator = true\n")).unwrap();
    assert!(
        regulated
            .agent()
            .planning
            .as_ref()
            .unwrap()
            .start_from_regulator
    );
    assert_eq!(resolve_str(&regulated.to_toml()).unwrap(), regulated);
    let e = resolve_str("[planning]\nhorizon = 10\niterations = 2\nstart_from_regulator = true\n")
        .unwrap_err();
    assert_eq!(e.key, "planning.start_from_regulator", "{e}");
}

/// `[lqr]`, which no preset has: a file adds it (empty, or with a region), it round-trips,
/// and a wrong region, algorithm or a `[planning]` beside it is named.
#[test]
fn an_lqr_section_is_added_checked_and_round_trips() {
    let c = resolve_str("[lqr]\n").unwrap();
    assert_eq!(c.agent().lqr.as_ref().unwrap().region, None);
    let lqr = "[lqr]\nregion = [0.5, inf]\n";
    let c = resolve_str(lqr).unwrap();
    assert_eq!(
        c.agent().lqr.as_ref().unwrap().region,
        Some(vec![0.5, f64::INFINITY])
    );
    assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
    let state = resolve_str("[lqr]\nfit_at = \"state\"\n").unwrap();
    assert_eq!(state.agent().lqr.as_ref().unwrap().fit_at, FitAt::State);
    assert_eq!(resolve_str(&state.to_toml()).unwrap(), state);
    let e = resolve_str("[lqr]\nfit_at = \"sate\"\n").unwrap_err();
    assert!(e.to_string().contains("sate"), "{e}");
    let e = resolve_str("[lqr]\nregion = [0.5]\n").unwrap_err();
    assert_eq!(e.key, "lqr.region", "{e}");
    let e = resolve_str("[lqr]\nregion = [0.5, -1.0]\n").unwrap_err();
    assert_eq!(e.key, "lqr.region", "{e}");
    let e = resolve_str("[lqr]\nregoin = [0.5, 1.0]\n").unwrap_err();
    assert!(e.to_string().contains("regoin"), "{e}");
    let e = resolve_str(&format!("algo = \"sac\"\n{lqr}")).unwrap_err();
    assert!(e.message.contains("remove the [lqr] section"), "{e}");
    let plan = "[planning]\nhorizon = 15\nsamples = 64\nelites = 8\niterations = 3\n";
    let e = resolve_str(&format!("{lqr}{plan}")).unwrap_err();
    assert_eq!(e.key, "lqr", "{e}");
}

#[test]
fn a_learning_rate_schedule_resolves_round_trips_and_is_fingerprinted() {
    let plain = resolve(None, &Overrides::default()).unwrap();
    assert!(
        !plain.to_toml().contains("decay"),
        "off by default, not written"
    );
    let c = resolve_str(
        "[actor]\ndecay_trials = 200\n[critic]\ndecay_trials = 400.0\ndecay_power = 0.6\n",
    )
    .unwrap();
    let (Some(Component::Llr(actor)), Component::Llr(critic)) = (&c.agent.actor, &c.agent.critic)
    else {
        panic!()
    };
    assert_eq!((actor.decay_trials, actor.decay_power), (Some(200.0), None));
    assert_eq!(
        (critic.decay_trials, critic.decay_power),
        (Some(400.0), Some(0.6))
    );
    assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
    assert_ne!(c.origin(0).fingerprint, plain.origin(0).fingerprint);
    // SAC's tile coding and SARSA's grid have a learning rate too.
    for algo in [
        "algo = \"sac\"\napprox = \"tiles\"\n",
        "algo = \"sarsa\"\napprox = \"rbf\"\n",
    ] {
        resolve_str(&format!("{algo}[critic]\ndecay_trials = 50\n")).unwrap();
    }
}

#[test]
fn learning_rate_schedule_errors_name_the_key_and_what_is_allowed() {
    let err = |text: &str| resolve_str(text).unwrap_err().to_string();
    assert_eq!(
        err("[actor]\ndecay_trials = -5\n"),
        "exp.toml: `actor.decay_trials`: -5 is out of range: must be a finite number in (0, 1000000000)"
    );
    assert_eq!(
        err("[critic]\ndecay_trials = nan\n"),
        "exp.toml: `critic.decay_trials`: NaN is out of range: must be a finite number in (0, 1000000000)"
    );
    assert_eq!(
        err("[actor]\ndecay_trials = 100\ndecay_power = 0.5\n"),
        "exp.toml: `actor.decay_power`: 0.5 is out of range: must be a finite number in (0.5, 1] (Σα_k = ∞ needs p ≤ 1, Σα_k² < ∞ needs p > 1/2, Eq. 2.21–2.22)"
    );
    assert_eq!(
        err("[critic]\ndecay_power = 1\n"),
        "exp.toml: `critic.decay_power`: is the power of a decay: give `critic.decay_trials` too"
    );
    assert_eq!(
        err("[actor]\ndecay_trials = \"slow\"\n"),
        "exp.toml: `actor.decay_trials`: \"slow\" has the wrong type: expected a number"
    );
    // No learning rate, no schedule: the process model, an LSTD critic.
    let e = err("[model]\ndecay_trials = 100\n");
    assert!(
        e.starts_with("exp.toml: `model.decay_trials`: unknown key"),
        "{e}"
    );
    let e = err("algo = \"vgbp\"\napprox = \"lstd\"\n[critic]\ndecay_trials = 100\n");
    assert!(
        e.starts_with("exp.toml: `critic.decay_trials`: unknown key"),
        "{e}"
    );
    assert!(!e.contains("schedule"), "{e}");
    // A misspelt key in a section with a learning rate lists the schedule's keys too.
    let e = err("[actor]\ndecay_trails = 100\n");
    assert!(
        e.ends_with("; and the learning rate's schedule: decay_trials, decay_power"),
        "{e}"
    );
}
