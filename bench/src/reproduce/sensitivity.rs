//! The sensitivity analysis: final return and rise time of the learners as each
//! parameter is scaled by [`FACTORS`].

use std::fmt::Write as _;
use std::time::Duration;

use agent::config::{AgentConfig, Component};
use plant::SystemName;

use runtime::config::ExperimentConfig;
use runtime::output::write_atomic;

use super::figures::preset;
use super::measures::Measured;
use super::{ReproduceError, Runner};

/// The parameters the sensitivity analysis varies, and how.
/// Scales a parameter of a configuration by a factor.
pub(super) type Scale = fn(&mut AgentConfig, f64);

/// `(name, short name for directories, how)` of each parameter.
pub(super) const PARAMETERS: [(&str, &str, Scale); 5] = [
    ("α_a (actor rate)", "alpha_a", |c, f| {
        if let Some(Component::Llr(l)) = &mut c.actor {
            l.alpha *= f;
        }
    }),
    ("α_c (critic rate)", "alpha_c", |c, f| {
        if let Component::Llr(l) = &mut c.critic {
            l.alpha *= f;
        }
    }),
    ("K (neighbours, every memory)", "K", |c, f| {
        for_each_llr(c, |l| {
            l.neighbours = ((l.neighbours as f64 * f).round() as usize).max(3)
        })
    }),
    ("N (memory size, every memory)", "N", |c, f| {
        for_each_llr(c, |l| {
            l.memory = ((l.memory as f64 * f).round() as usize).max(10)
        })
    }),
    ("σ (exploration)", "sigma", |c, f| c.learning.sigma *= f),
];

/// Factors applied to each parameter (the preset is factor 1).
pub const FACTORS: [f64; 4] = [0.25, 0.5, 2.0, 4.0];

pub(super) fn for_each_llr(a: &mut AgentConfig, mut f: impl FnMut(&mut agent::config::LlrConfig)) {
    for comp in [a.actor.as_mut(), Some(&mut a.critic), a.model.as_mut()]
        .into_iter()
        .flatten()
    {
        if let Component::Llr(l) = comp {
            f(l);
        }
    }
}

/// One algorithm's sensitivity: its name, its preset's measures, and per parameter, per
/// factor, the measures (`None`: not a valid configuration).
pub type AlgoSensitivity = (
    String,
    Measured,
    Vec<(String, Vec<(f64, Option<Measured>)>)>,
);

/// The sensitivity analysis (§3.7 and §7.2.1 leave it as future work): final greedy
/// return and learning speed of SAC/LLR and MLAC/LLR on the pendulum when each main
/// parameter is scaled by [`FACTORS`] around the preset.
pub struct Sensitivity {
    /// Runs per variation.
    pub runs: u32,
    /// Per algorithm: the preset's measures and, per parameter, per factor, the measures
    /// (`None`: the variation is not a valid configuration).
    pub algos: Vec<AlgoSensitivity>,
    /// Wall-clock time.
    pub wall: Duration,
}

/// `base` with a parameter scaled by `f`; `None` where scaling changes nothing (e.g. a
/// rounded K) or makes an invalid configuration.
pub(super) fn varied(base: &ExperimentConfig, apply: Scale, f: f64) -> Option<ExperimentConfig> {
    let mut cfg = base.clone();
    cfg.change_agent(|a| apply(a, f)).ok()?;
    (cfg != *base).then_some(cfg)
}

pub(super) fn sensitivity(runner: &mut Runner) -> Result<Sensitivity, ReproduceError> {
    use agent::config::{Algo::*, ApproxKind::Llr, HorizonKind::Infinite};
    let spent = runner.spent;
    let runs = runner.opts.runs.unwrap_or(10);
    let dir = runner.opts.out.join("sensitivity");
    let algorithms = [("SAC/LLR", Sac), ("MLAC/LLR", Mlac)];
    let bases = algorithms.map(|(_, algo)| preset(SystemName::Pendulum, algo, Llr, Infinite));
    let experiments: Vec<ExperimentConfig> = bases
        .iter()
        .flat_map(|base| {
            let varied = PARAMETERS
                .iter()
                .flat_map(|&(_, _, apply)| FACTORS.map(|f| varied(base, apply, f)));
            std::iter::once(base.clone()).chain(varied.flatten())
        })
        .collect();
    runner.start("sensitivity", &experiments, Some(runs));
    let mut algos = Vec::new();
    for ((name, _), base) in algorithms.into_iter().zip(&bases) {
        let (at_preset, _) = runner.run(
            &dir,
            "sensitivity",
            &format!("{name} preset"),
            base,
            Some(runs),
        )?;
        let mut params = Vec::new();
        for (param, key, apply) in PARAMETERS {
            let mut row = Vec::new();
            for f in FACTORS {
                let m = match varied(base, apply, f) {
                    Some(cfg) => {
                        let label = format!("{name} {key} x{f}");
                        Some(runner.run(&dir, "sensitivity", &label, &cfg, Some(runs))?.0)
                    }
                    None => None,
                };
                row.push((f, m));
            }
            params.push((param.to_string(), row));
        }
        algos.push((name.to_string(), at_preset, params));
    }
    let mut csv = String::from("algo,parameter,factor,final_greedy_mean,final_greedy_sd,t90_min\n");
    for (name, p, params) in &algos {
        let _ = writeln!(
            csv,
            "{name},preset,1,{},{},{}",
            p.final_greedy, p.final_greedy_sd, p.reaches_min
        );
        for (param, row) in params {
            for (f, m) in row {
                if let Some(m) = m {
                    let _ = writeln!(
                        csv,
                        "{name},{param},{f},{},{},{}",
                        m.final_greedy, m.final_greedy_sd, m.reaches_min
                    );
                }
            }
        }
    }
    write_atomic(&dir.join("sensitivity.csv"), &csv)?;
    let sweeps: Vec<(&str, Vec<crate::sensitivity::Sweep>)> = algos
        .iter()
        .map(|(name, preset, params)| {
            let sweeps = params
                .iter()
                .map(|(param, row)| {
                    let mut points: Vec<(f64, f64, f64)> = row
                        .iter()
                        .filter_map(|(f, m)| {
                            m.as_ref().map(|m| (*f, m.final_greedy, m.reaches_min))
                        })
                        .chain([(1.0, preset.final_greedy, preset.reaches_min)])
                        .collect();
                    points.sort_by(|a, b| a.0.total_cmp(&b.0));
                    crate::sensitivity::Sweep {
                        // The symbol, without the explanation in brackets.
                        parameter: param.split(" (").next().unwrap_or(param),
                        points,
                    }
                })
                .collect();
            (name.as_str(), sweeps)
        })
        .collect();
    crate::sensitivity::plot_sensitivity(
        &dir.join("sensitivity.png"),
        &dir.join("sensitivity.svg"),
        &format!("Sensitivity: final greedy return and t₉₀ ({runs} runs per point)"),
        &sweeps,
    )?;
    Ok(Sensitivity {
        runs,
        algos,
        wall: runner.spent - spent,
    })
}

impl Sensitivity {
    /// Per algorithm, the worst final greedy return over all variations, and the
    /// largest loss against the preset.
    pub(super) fn worst(&self) -> Vec<(String, f64, f64)> {
        self.algos
            .iter()
            .map(|(name, p, params)| {
                let worst = params
                    .iter()
                    .flat_map(|(_, row)| row.iter().filter_map(|(_, m)| m.as_ref()))
                    .map(|m| m.final_greedy)
                    .fold(p.final_greedy, f64::min);
                (name.clone(), worst, p.final_greedy - worst)
            })
            .collect()
    }
}
