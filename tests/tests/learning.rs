//! Whole experiments through `rig learn`'s library: determinism, every supported
//! (algorithm, approximator) pair, that MLAC/LLR actually learns the swing-up, and the
//! finite-horizon learners of Chapter 4.

use std::path::PathBuf;

use agent::config::{Algo, ApproxKind, HorizonKind};
use runtime::config::{ExperimentConfig, Overrides, resolve};
use runtime::learn::{LearnOptions, Progress, learn};

fn config(algo: Algo, approx: ApproxKind, runs: u32, trials: u32, seed: u64) -> ExperimentConfig {
    config_with(HorizonKind::Infinite, algo, approx, runs, trials, seed)
}

fn config_with(
    horizon: HorizonKind,
    algo: Algo,
    approx: ApproxKind,
    runs: u32,
    trials: u32,
    seed: u64,
) -> ExperimentConfig {
    let o = Overrides {
        algo: Some(algo),
        approx: Some(approx),
        horizon: Some(horizon),
        runs: Some(runs),
        trials: Some(trials),
        seed: Some(seed),
        eval_every: Some(trials.min(5)),
        ..Default::default()
    };
    resolve(None, &o).expect("preset resolves")
}

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rig-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn run(cfg: &ExperimentConfig, name: &str, threads: usize) -> (PathBuf, String) {
    let out = out_dir(name);
    learn(
        cfg,
        &LearnOptions {
            out: out.clone(),
            threads: Some(threads),
            progress: Progress::Hidden,
        },
    )
    .expect("learn");
    let csv = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv");
    (out, csv)
}

#[test]
fn same_seed_same_bytes_any_thread_count_different_seed_different() {
    let cfg = config(Algo::Mlac, ApproxKind::Llr, 3, 6, 7);
    let (dir_a, a) = run(&cfg, "det-a", 1);
    let (_, b) = run(&cfg, "det-b", 2);
    assert_eq!(a, b, "runs.csv must not depend on the thread count");
    let (_, again) = run(&cfg, "det-c", 2);
    assert_eq!(a, again);
    let (_, other) = run(&config(Algo::Mlac, ApproxKind::Llr, 3, 6, 8), "det-d", 2);
    assert_ne!(a, other, "a different seed must give different runs");
    // The header and shape of runs.csv: 3 runs × 6 trials, greedy every 5.
    let lines: Vec<&str> = a.lines().collect();
    assert_eq!(lines[0], "run,trial,sim_time_s,return,greedy_return");
    assert_eq!(lines.len(), 1 + 3 * 6);
    assert_eq!(
        lines[5].split(',').nth(4).map(|g| !g.is_empty()),
        Some(true),
        "trial 5 has a greedy return"
    );
    assert_eq!(lines[1].split(',').nth(4), Some(""), "trial 1 has none");
    assert!(lines[1].starts_with("0,1,3,"));
    // Outputs next to it.
    for f in [
        "config.toml",
        "curve.csv",
        "greedy_curve.csv",
        "curve.png",
        "curve.svg",
    ] {
        assert!(dir_a.join(f).exists(), "{f} missing");
    }
    // The written config reproduces the run.
    let text = std::fs::read_to_string(dir_a.join("config.toml")).unwrap();
    let again = resolve(
        Some((&dir_a.join("config.toml"), &text)),
        &Overrides::default(),
    )
    .unwrap();
    assert_eq!(again, cfg);
}

/// The best greedy evaluation of `summary`: the largest mean over runs of the greedy
/// return at any evaluated trial.
fn best_greedy(summary: &runtime::learn::LearnSummary) -> f64 {
    summary
        .greedy_curve
        .iter()
        .map(|g| g.mean)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Every supported (algorithm, approximator) pair with its preset learns the swing-up:
/// within the trials given (2 runs, seed 1, a greedy evaluation every 5 trials) the mean
/// greedy return of some evaluation exceeds −2000, where the untrained policy (zero
/// action, the pendulum hanging) earns −4935 per 3 s trial; the best evaluations reached
/// here are −900 to −1550. Every return is finite.
///
/// The trial counts are about 1.5 times the latest first evaluation above −2000 measured
/// for seeds 1 to 6 (SAC: tiles 45, RBF 60, LLR 25; MLAC: RBF 75, LLR 20; RMAC: RBF 60,
/// LLR 15; VGBP: LSTD 20, RBF 20, LLR 30; SARSA 90). With the actor's and the critic's
/// updates zeroed (SAC's `α_a δ Δu`, MLAC's Eq. 3.9/3.14 step, RMAC's reference-model
/// update, the TD(λ) critic's `α_c δ z`, LSTD's solve, SARSA's `α δ`) every greedy
/// evaluation stays at −4935, but SARSA's at −3529 (a constant action) and RMAC's at best
/// −4062 (RBF) and −4716 (LLR): every pair fails. With only the critic's zeroed the best
/// is −3455 (SAC/LLR), with only the actor's every actor-critic pair fails.
#[test]
fn every_supported_combination_learns_the_swing_up() {
    let mut failed = Vec::new();
    for (algo, approx, trials) in [
        (Algo::Sac, ApproxKind::Tiles, 70),
        (Algo::Sac, ApproxKind::Rbf, 90),
        (Algo::Sac, ApproxKind::Llr, 40),
        (Algo::Mlac, ApproxKind::Rbf, 110),
        (Algo::Mlac, ApproxKind::Llr, 30),
        (Algo::Rmac, ApproxKind::Rbf, 90),
        (Algo::Rmac, ApproxKind::Llr, 25),
        (Algo::Vgbp, ApproxKind::Lstd, 30),
        (Algo::Vgbp, ApproxKind::Rbf, 30),
        (Algo::Vgbp, ApproxKind::Llr, 45),
        (Algo::Sarsa, ApproxKind::Rbf, 130),
    ] {
        let cfg = config(algo, approx, 2, trials, 1);
        let summary = learn_in(&format!("combo-{algo}-{approx}"), &cfg);
        assert_eq!(summary.records.len(), 2 * trials as usize);
        for r in &summary.records {
            assert!(r.ret.is_finite(), "{algo}/{approx}: {r:?}");
        }
        let best = best_greedy(&summary);
        eprintln!("{algo}/{approx}: best mean greedy return in {trials} trials {best:.0}");
        if best <= -2000.0 {
            failed.push(format!(
                "{algo}/{approx}: best mean greedy return in {trials} trials {best:.0}"
            ));
        }
    }
    assert!(failed.is_empty(), "no swing-up:\n{}", failed.join("\n"));
}

/// The arms and the double integrator learn with their presets (one run, seed 1, a
/// greedy evaluation every 2 trials): within the trials given some greedy evaluation
/// earns more than the level below, which the untrained policy (zero action) does not
/// reach. Levels and trial counts from measurements of seeds 1 to 4 (6 for the double
/// integrator with MLAC and the manipulator with MLAC): the best greedy return was
///
/// | system, learner               | trials | untrained | learned (worst seed) | level  |
/// |-------------------------------|--------|-----------|----------------------|--------|
/// | arm, Case I, SAC/LLR          | 10     | −2569     | −702                 | −1500  |
/// | arm, Case I, MLAC/LLR         | 10     | −2569     | −498                 | −1500  |
/// | double integrator, MLAC/LLR   | 30     | −60       | −22                  | −40    |
/// | double integrator, VGBP/LSTD  | 10     | −60       | −26                  | −40    |
/// | arm, Case II, VGBP/LSTD       | 20     | −7016     | −1906                | −3500  |
/// | manipulator §6.4.2, VGBP/LSTD | 20     | −50000    | −8648                | −30000 |
/// | manipulator §6.4.2, MLAC/LLR  | 20     | −50000    | −42289               | −46000 |
///
/// With the actor's and the critic's updates zeroed (MLAC's Eq. 3.9 step and SAC's
/// `α_a δ Δu`, the TD(λ) critic's `α_c δ z`, LSTD's solve) every greedy evaluation is the
/// untrained policy's and each of these fails; with only the critic's zeroed, each fails
/// too.
///
/// The arm of Case II with SAC/RBF and RMAC/LLR learns in hundreds of trials (§5.4),
/// beyond this test: there, learning must change the greedy policy — the greedy return
/// after trial 1 or 2 differs from the untrained policy's by more than 1 % (measured:
/// −7443 and −6952 for SAC, −6245 and −9929 for RMAC). With SAC's actor update zeroed,
/// or RMAC's reference-model and process-model updates, the greedy return stays the
/// untrained policy's (−7016) exactly.
#[test]
fn the_arm_and_the_linear_system_learn_with_their_presets() {
    use Algo::{Mlac, Rmac, Sac, Vgbp};
    use ApproxKind::{Llr, Lstd, Rbf};
    use plant::SystemName::{Arm64, ArmHorizontal, ArmVertical, DoubleIntegrator};
    let mut failed = Vec::new();
    for (system, algo, approx, trials, level) in [
        (ArmVertical, Sac, Llr, 10, Some(-1500.0)),
        (ArmVertical, Mlac, Llr, 10, Some(-1500.0)),
        (ArmHorizontal, Sac, Rbf, 2, None),
        (ArmHorizontal, Rmac, Llr, 2, None),
        (DoubleIntegrator, Mlac, Llr, 30, Some(-40.0)),
        (DoubleIntegrator, Vgbp, Lstd, 10, Some(-40.0)),
        (ArmHorizontal, Vgbp, Lstd, 20, Some(-3500.0)),
        (Arm64, Vgbp, Lstd, 20, Some(-30000.0)),
        (Arm64, Mlac, Llr, 20, Some(-46000.0)),
    ] {
        let o = Overrides {
            system: Some(system),
            algo: Some(algo),
            approx: Some(approx),
            runs: Some(1),
            trials: Some(trials),
            eval_every: Some(if level.is_some() { 2 } else { 1 }),
            ..Default::default()
        };
        let cfg = resolve(None, &o).expect("preset resolves");
        let who = format!("{system} {algo}/{approx}");
        let summary = learn_in(&format!("{system}-{algo}-{approx}"), &cfg);
        assert_eq!(summary.records.len(), trials as usize, "{who}");
        for r in &summary.records {
            let g = r.greedy.unwrap_or(0.0);
            assert!(r.ret.is_finite() && g.is_finite(), "{who}: {r:?}");
        }
        let best = best_greedy(&summary);
        eprintln!("{who}: best greedy return in {trials} trials {best:.0}");
        match level {
            Some(level) if best <= level => failed.push(format!(
                "{who}: best greedy return in {trials} trials {best:.0}, not above {level}"
            )),
            Some(_) => {}
            None => {
                let untrained = runtime::experiment::Experiment::new(&cfg, 0).greedy_return();
                let changed = summary
                    .greedy_curve
                    .iter()
                    .any(|g| (g.mean - untrained).abs() > 0.01 * untrained.abs());
                if !changed {
                    failed.push(format!(
                        "{who}: the greedy return stays the untrained policy's {untrained:.0}: {:?}",
                        summary.greedy_curve.iter().map(|g| g.mean).collect::<Vec<_>>()
                    ));
                }
            }
        }
    }
    assert!(failed.is_empty(), "not learning:\n{}", failed.join("\n"));
}

/// Runs `cfg` with `rig learn` on two threads into a fresh test directory.
fn learn_in(name: &str, cfg: &ExperimentConfig) -> runtime::learn::LearnSummary {
    let options = LearnOptions {
        out: out_dir(name),
        threads: Some(2),
        progress: Progress::Hidden,
    };
    learn(cfg, &options).unwrap()
}

#[test]
fn mlac_llr_learns_the_swing_up() {
    // A policy that never swings up earns about −4900 per 3 s trial; a swing-up about
    // −750 to −900. After 50 trials (2.5 simulated minutes) MLAC/LLR swings up.
    let cfg = config(Algo::Mlac, ApproxKind::Llr, 4, 50, 3);
    let summary = learn_in("learns", &cfg);
    let greedy = summary.greedy_curve.last().unwrap();
    assert_eq!(greedy.trial, 50);
    assert!(
        greedy.mean > -1500.0,
        "mean greedy return after 50 trials: {}",
        greedy.mean
    );
    let first = &summary.curve[0];
    assert!(
        first.mean < -2500.0,
        "the first trial cannot already swing up: {}",
        first.mean
    );
}

#[test]
fn vgbp_lstd_learns_the_swing_up_fast() {
    // §6.4.1: VGBP-LSTD learns the swing-up within about a simulated minute. After 30
    // trials (1.5 min) every one of 4 runs swings up (a policy that does not earns
    // about −4900).
    let cfg = config(Algo::Vgbp, ApproxKind::Lstd, 4, 30, 1);
    let summary = learn_in("vgbp-learns", &cfg);
    let greedy = summary.greedy_curve.last().unwrap();
    assert_eq!(greedy.trial, 30);
    assert!(
        greedy.min > -1500.0,
        "worst greedy return after 30 trials: {}",
        greedy.min
    );
}

#[test]
fn vgbp_lstd_learns_to_stay_in_the_manipulators_operating_range() {
    // §6.4.2: at first VGBP steers the arm out of its ±1.2 rad range (−4·10⁴ and the
    // trial ends); within ten sequences of the four start states it brings the arm to
    // the centre from each of them. Seed 1, 4 runs: greedy means −44 600 after trial 4,
    // −8 000 after trial 40 (the worst run −13 700).
    let o = Overrides {
        system: Some(plant::SystemName::Arm64),
        algo: Some(Algo::Vgbp),
        approx: Some(ApproxKind::Lstd),
        runs: Some(4),
        trials: Some(40),
        ..Default::default()
    };
    let cfg = resolve(None, &o).expect("preset resolves");
    let summary = learn_in("vgbp-arm64", &cfg);
    let first = &summary.greedy_curve[0];
    assert_eq!(first.trial, 4);
    assert!(
        first.mean < -3e4,
        "greedy mean after 4 trials: {}",
        first.mean
    );
    let last = summary.greedy_curve.last().unwrap();
    assert_eq!(last.trial, 40);
    assert!(
        last.min > -2e4,
        "worst greedy return after 40 trials (a run that still leaves the range \
         earns below −4·10⁴): {}",
        last.min
    );
}

#[test]
fn shipped_configuration_files_resolve() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../bench/configs");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("bench/configs exists") {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).unwrap();
            resolve(Some((&path, &text)), &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
            seen += 1;
        }
    }
    assert!(seen > 0, "no configuration files in {}", dir.display());
}

/// SAC-FH, MLAC-FH and RMAC-FH (Algorithms 4–6) learn: within 15 trials (one run, seed
/// 1, a greedy evaluation every 5 trials) some greedy return exceeds −4000, where the
/// untrained policy earns −4984 (τ_N included). Measured for seeds 1 to 6, the best
/// greedy return in 15 trials was at worst −3650 (SAC-FH), −3334 (MLAC-FH) and −3688
/// (RMAC-FH). With the actor's and the critic's updates zeroed (the actor's step of
/// Eq. 3.1 or 3.9, RMAC's reference-model update, the critic's `α_c δ z`) the best
/// greedy returns are −4984, −4984 and −4734: each fails. With only the critic's zeroed
/// SAC-FH (−4184) and MLAC-FH (−4984) fail, RMAC-FH not (−3571: with a flat critic the
/// reference model heads for one extreme action's prediction). And each return counts
/// the terminal reward.
#[test]
fn finite_horizon_learners_learn_and_count_the_terminal_reward() {
    let mut failed = Vec::new();
    for algo in [Algo::Sac, Algo::Mlac, Algo::Rmac] {
        let cfg = config_with(HorizonKind::Finite, algo, ApproxKind::Rbf, 1, 15, 1);
        let mut exp = runtime::experiment::Experiment::new(&cfg, 0);
        let mut best = f64::NEG_INFINITY;
        while let Some(r) = exp.next_trial() {
            assert!(r.ret.is_finite(), "{algo}: {r:?}");
            best = best.max(r.greedy.unwrap_or(f64::NEG_INFINITY));
        }
        eprintln!("{algo}-FH: best greedy return in 15 trials {best:.0}");
        if best <= -4000.0 {
            failed.push(format!(
                "{algo}-FH: best greedy return in 15 trials {best:.0}"
            ));
        }
        // Eq. 4.1: the return is the rewards plus τ_N(x_N) = −x_Nᵀ Q x_N of the state the
        // trial ends in (the greedy trial is deterministic, so both calls see the same one).
        let x0 = [std::f64::consts::PI, 0.0];
        let rewards: f64 = exp.greedy_trajectory(&x0).iter().map(|s| s.reward).sum();
        let tau = exp.greedy_return_from(&x0) - rewards;
        let worst =
            -(5.0 * std::f64::consts::PI.powi(2) + 0.1 * (8.0 * std::f64::consts::PI).powi(2));
        assert!(tau < 0.0 && tau > worst, "{algo}: τ_N = {tau}");
    }
    assert!(failed.is_empty(), "not learning:\n{}", failed.join("\n"));
}

#[test]
fn finite_horizon_mlac_learns_the_swing_up() {
    // §4.4.2: MLAC-FH is the fastest of Chapter 4's learners. A policy that never swings
    // up earns about −4700 per 3 s trial (τ_N included), a swing-up −800 to −950. After
    // 120 trials (6 simulated minutes) the greedy policies of both runs swing up.
    let cfg = config_with(HorizonKind::Finite, Algo::Mlac, ApproxKind::Rbf, 2, 120, 1);
    let summary = learn_in("fh-learns", &cfg);
    let greedy = summary.greedy_curve.last().unwrap();
    assert_eq!(greedy.trial, 120);
    assert!(greedy.max < -700.0 && summary.curve[0].mean < -4000.0);
    assert!(
        greedy.min > -2000.0,
        "worst greedy return after 120 trials: {}",
        greedy.min
    );
}
