//! Checkpoints hold an agent's whole learned state: for every learner the thesis defines
//! (every preset: system × algorithm × approximator × horizon), an agent restored from a
//! checkpoint — through its file encoding — continues bit for bit as the agent that
//! wrote it.
//!
//! Left out, for test time only: the arms' RBF process models and finite-horizon RBF
//! grids (6-D and 5-D grids, about a minute per preset here). The same `Persist` code
//! serves them as the pendulum's RBF presets, which are included.

use agent::checkpoint::{Checkpoint, Snapshot};
use agent::config::{Algo, ApproxKind, HorizonKind};
use plant::SystemName;
use runtime::config::ExperimentConfig;
use runtime::experiment::Experiment;
use runtime::resumable::ResumeError;

fn presets() -> Vec<ExperimentConfig> {
    let mut out = Vec::new();
    for system in SystemName::ALL {
        for algo in Algo::ALL {
            for &approx in algo.approximators() {
                for horizon in HorizonKind::ALL {
                    let heavy = system != SystemName::Pendulum
                        && approx == ApproxKind::Rbf
                        && (matches!(algo, Algo::Mlac | Algo::Rmac)
                            || horizon == HorizonKind::Finite);
                    if heavy {
                        continue;
                    }
                    if let Ok(mut cfg) = ExperimentConfig::preset(system, algo, approx, horizon) {
                        cfg.change_run(|r| (r.trials, r.eval_every) = (6, 1))
                            .expect("six trials are allowed");
                        out.push(cfg);
                    }
                }
            }
        }
    }
    out
}

fn name(cfg: &ExperimentConfig) -> String {
    let a = cfg.agent();
    format!("{} {}/{}/{}", cfg.system(), a.algo, a.approx, a.horizon)
}

#[test]
fn every_learner_resumes_bit_for_bit() {
    let presets = presets();
    assert!(presets.len() >= 20, "only {} presets", presets.len());
    for cfg in &presets {
        let who = name(cfg);
        let t0 = std::time::Instant::now();
        let mut straight = Experiment::new(cfg, 1);
        let want: Vec<_> = std::iter::from_fn(|| straight.next_trial()).collect();
        assert_eq!(want.len(), 6, "{who}");

        let mut first = Experiment::new(cfg, 1);
        for _ in 0..3 {
            first.next_trial().unwrap();
        }
        let bytes = first.checkpoint().to_bytes();
        drop(first);
        let c = Checkpoint::from_bytes(&bytes).unwrap();
        assert_eq!(c.trial, 3, "{who}");
        assert_eq!(
            c.sim_time_s.to_bits(),
            want[2].sim_time_s.to_bits(),
            "{who}"
        );
        let mut resumed = Experiment::resume(cfg, 1, &c).unwrap_or_else(|e| panic!("{who}: {e}"));
        let got: Vec<_> = std::iter::from_fn(|| resumed.next_trial()).collect();
        assert_eq!(got.len(), 3, "{who}");
        for (g, w) in got.iter().zip(&want[3..]) {
            assert_eq!(g.trial, w.trial, "{who}");
            assert_eq!(g.ret.to_bits(), w.ret.to_bits(), "{who}: trial {}", w.trial);
            assert_eq!(g.sim_time_s.to_bits(), w.sim_time_s.to_bits(), "{who}");
            assert_eq!(
                g.greedy.map(f64::to_bits),
                w.greedy.map(f64::to_bits),
                "{who}: greedy after trial {}",
                w.trial
            );
        }
        // The learned state itself is the same after the same trials.
        let (mut a, mut b) = (Snapshot::default(), Snapshot::default());
        straight.agent().save(&mut a);
        resumed.agent().save(&mut b);
        assert!(a == b, "{who}: learned states differ after resuming");
        eprintln!(
            "{who}: resumed bit for bit ({:.2} s)",
            t0.elapsed().as_secs_f64()
        );
    }
}

#[test]
fn a_checkpoint_does_not_restore_into_another_learner() {
    let all = presets();
    let first = &all[0];
    assert_eq!(
        (first.system(), first.agent().algo),
        (SystemName::Pendulum, Algo::Sac),
        "{}",
        name(first)
    );
    let mut sac = Experiment::new(first, 0);
    sac.next_trial().unwrap();
    let c = sac.checkpoint();
    let mut checked = 0;
    for other in &all[1..] {
        let e = Experiment::resume(other, 0, &c).err().expect("refused");
        assert!(
            e.to_string().contains("checkpoint is from")
                || e.to_string().contains("different learning parameters"),
            "{}: {e}",
            name(other)
        );
        checked += 1;
    }
    assert!(checked > 10);
    // Past the origin check (a forged origin), the sections' names and shapes still do
    // not fit another learner: an error, never a panic. Only the same learner on a system
    // of the same state and action dimensions (SAC/LLR on the double integrator) has the
    // same sections and shapes; the origin, checked above, is what refuses it there.
    let learner = |cfg: &ExperimentConfig| {
        let task = cfg.task();
        let a = cfg.agent();
        (
            a.algo,
            a.approx,
            a.horizon,
            task.state_dim(),
            task.action_dim(),
        )
    };
    let (mut refused, mut alike) = (0, 0);
    for other in &all[1..] {
        let mut forged = c.clone();
        forged.origin = other.origin(0);
        let resumed = Experiment::resume(other, 0, &forged);
        if learner(other) == learner(first) {
            assert!(resumed.is_ok(), "{}", name(other));
            alike += 1;
            continue;
        }
        let Err(e) = resumed else {
            panic!(
                "{}: resumed from a checkpoint of {}",
                name(other),
                name(first)
            );
        };
        assert!(
            matches!(&e, ResumeError::Checkpoint(c) if c.to_string().contains("differently configured")),
            "{}: {e}",
            name(other)
        );
        refused += 1;
    }
    assert_eq!((refused, alike), (all.len() - 2, 1));
}

/// A learning rate on a schedule (`[actor]`/`[critic]` `decay_trials`, `decay_power`)
/// resumes where it left off: the checkpoint holds each schedule's trial count, and the
/// resumed run's returns are the uninterrupted run's, bit for bit. The schedules change
/// what is learned (the same learners at constant rates return otherwise), so a
/// schedule that started over on resuming would show.
#[test]
fn a_learning_rate_schedule_resumes_where_it_left_off() {
    let learners = [
        "algo = \"mlac\"\napprox = \"llr\"\n",
        "algo = \"sac\"\napprox = \"tiles\"\n",
        "algo = \"rmac\"\napprox = \"rbf\"\n",
        "algo = \"sarsa\"\napprox = \"rbf\"\n",
    ];
    let run = "[run]\ntrials = 6\neval_every = 1\n";
    let resolve = |text: &str| {
        runtime::config::resolve(
            Some((std::path::Path::new("schedule.toml"), text)),
            &runtime::config::Overrides::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let returns = |e: &mut Experiment| {
        std::iter::from_fn(|| e.next_trial())
            .map(|t| (t.ret.to_bits(), t.greedy.map(f64::to_bits)))
            .collect::<Vec<_>>()
    };
    for learner in learners {
        // SARSA has no actor.
        let (actor, schedules) = match learner.contains("sarsa") {
            true => ("", 1),
            false => ("[actor]\ndecay_trials = 1\n", 2),
        };
        let critic = "[critic]\ndecay_trials = 2\ndecay_power = 0.6\n";
        let cfg = resolve(&format!("{learner}{actor}{critic}{run}"));
        let who = name(&cfg);
        let want = returns(&mut Experiment::new(&cfg, 1));
        let constant = returns(&mut Experiment::new(
            &resolve(&format!("{learner}{run}")),
            1,
        ));
        assert_eq!(want[0], constant[0], "{who}: the first trial learns at α_0");
        assert_ne!(
            want[3..],
            constant[3..],
            "{who}: the schedule changes nothing"
        );

        let mut first = Experiment::new(&cfg, 1);
        for _ in 0..3 {
            first.next_trial().unwrap();
        }
        let c = Checkpoint::from_bytes(&first.checkpoint().to_bytes()).unwrap();
        let saved = format!("{:?}", c.state).matches("schedule.trials").count();
        assert_eq!(saved, schedules, "{who}: {:?}", c.state);
        let mut resumed = Experiment::resume(&cfg, 1, &c).unwrap();
        assert_eq!(returns(&mut resumed), want[3..], "{who}");
    }
}
