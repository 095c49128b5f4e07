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

#[test]
fn every_supported_combination_runs_and_stays_finite() {
    for (algo, approx) in [
        (Algo::Sac, ApproxKind::Tiles),
        (Algo::Sac, ApproxKind::Rbf),
        (Algo::Sac, ApproxKind::Llr),
        (Algo::Mlac, ApproxKind::Rbf),
        (Algo::Mlac, ApproxKind::Llr),
        (Algo::Rmac, ApproxKind::Rbf),
        (Algo::Rmac, ApproxKind::Llr),
        (Algo::Vgbp, ApproxKind::Lstd),
        (Algo::Vgbp, ApproxKind::Rbf),
        (Algo::Vgbp, ApproxKind::Llr),
        (Algo::Sarsa, ApproxKind::Rbf),
    ] {
        let cfg = config(algo, approx, 2, 5, 1);
        let (_, csv) = run(&cfg, &format!("combo-{algo}-{approx}"), 2);
        for line in csv.lines().skip(1) {
            let ret: f64 = line.split(',').nth(3).unwrap().parse().unwrap();
            // 100 samples of −ρ ≤ 5π² + 0.1 ω² + 9: finite and negative.
            assert!(ret.is_finite() && ret < 0.0, "{algo}/{approx}: {line}");
        }
    }
}

#[test]
fn the_arm_and_the_linear_system_run_with_their_presets() {
    use plant::SystemName;
    for (system, algo, approx) in [
        (SystemName::ArmVertical, Algo::Sac, ApproxKind::Llr),
        (SystemName::ArmVertical, Algo::Mlac, ApproxKind::Llr),
        (SystemName::ArmHorizontal, Algo::Sac, ApproxKind::Rbf),
        (SystemName::ArmHorizontal, Algo::Rmac, ApproxKind::Llr),
        (SystemName::DoubleIntegrator, Algo::Mlac, ApproxKind::Llr),
        (SystemName::DoubleIntegrator, Algo::Vgbp, ApproxKind::Lstd),
        (SystemName::ArmHorizontal, Algo::Vgbp, ApproxKind::Lstd),
        (SystemName::Arm64, Algo::Vgbp, ApproxKind::Lstd),
        (SystemName::Arm64, Algo::Mlac, ApproxKind::Llr),
    ] {
        let o = Overrides {
            system: Some(system),
            algo: Some(algo),
            approx: Some(approx),
            runs: Some(1),
            trials: Some(2),
            eval_every: Some(1),
            ..Default::default()
        };
        let cfg = resolve(None, &o).expect("preset resolves");
        let (_, csv) = run(&cfg, &format!("{system}-{algo}-{approx}"), 1);
        let rows: Vec<&str> = csv.lines().skip(1).collect();
        assert_eq!(rows.len(), 2);
        for line in rows {
            let f: Vec<f64> = line
                .split(',')
                .skip(2)
                .map(|v| v.parse().unwrap())
                .collect();
            assert!(
                f.iter().all(|v| v.is_finite()) && f[1] < 0.0,
                "{system}: {line}"
            );
        }
    }
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

#[test]
fn finite_horizon_learners_run_and_count_the_terminal_reward() {
    for algo in [Algo::Sac, Algo::Mlac, Algo::Rmac] {
        let cfg = config_with(HorizonKind::Finite, algo, ApproxKind::Rbf, 1, 3, 1);
        let mut exp = runtime::experiment::Experiment::new(&cfg, 0);
        while let Some(r) = exp.next_trial() {
            assert!(r.ret.is_finite() && r.ret < 0.0, "{algo}: {r:?}");
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
