//! The thesis's figures as data: for each, the experiments (presets) it plots, the
//! thesis's numbers, and its claims (checked in [`super::claims`]).

use std::path::Path;

use agent::config::{Algo, ApproxKind, HorizonKind};
use plant::SystemName;

use runtime::config::{ExperimentConfig, Overrides, resolve};

use super::claims::{
    Verdict, better, clearly_better, faster, fastest, fastest_of, find, llr_share, not, rbf_dip,
    swing_counts,
};
use super::measures::Measured;

/// One learning curve of a figure.
pub(super) struct Curve {
    pub(super) label: &'static str,
    pub(super) cfg: ExperimentConfig,
}

/// A qualitative claim of the thesis about a figure, checked on the measured curves.
pub(super) struct Claim {
    /// What the thesis says.
    pub(super) says: &'static str,
    /// The check: whether the curves confirm the claim, and why.
    pub(super) check: fn(&[Measured]) -> Verdict,
}

/// A figure of the thesis.
pub(super) struct Figure {
    pub(super) id: &'static str,
    pub(super) title: &'static str,
    pub(super) curves: Vec<Curve>,
    /// The thesis's numbers for the table, per curve label.
    pub(super) thesis: &'static [(&'static str, &'static str)],
    pub(super) claims: Vec<Claim>,
}

pub(super) fn preset(
    system: SystemName,
    algo: Algo,
    approx: ApproxKind,
    horizon: HorizonKind,
) -> ExperimentConfig {
    ExperimentConfig::preset(system, algo, approx, horizon).expect("every figure's preset exists")
}

/// Figure 6.1's VGBP-LSTD as the thesis has it: the action of Eq. 6.21 as printed.
const EQ_6_21: &str = "VGBP-LSTD, Eq. 6.21 (thesis)";

/// This project's VGBP-LSTD preset: Eq. 6.21 refined by a search of Eq. 6.6
/// ([`agent::preset::VGBP_ACTION_GRID`]).
const SEARCH: &str = "VGBP-LSTD, search of Eq. 6.6 (this project)";

/// VGBP-LSTD on the pendulum with the thesis's action selection: Eq. 6.21 exactly
/// (`lookahead = 0`, `grid = 0`).
fn vgbp_lstd_eq_6_21() -> ExperimentConfig {
    let mut cfg = preset(
        SystemName::Pendulum,
        Algo::Vgbp,
        ApproxKind::Lstd,
        HorizonKind::Infinite,
    );
    cfg.change_agent(|a| {
        let v = a.vgbp.as_mut().expect("VGBP has a [vgbp] section");
        v.lookahead = 0;
        v.grid = 0;
    })
    .expect("Eq. 6.21's selection is a valid [vgbp]");
    cfg
}

/// Chapter 6's MLAC/LLR (Table 6.2), shipped as `bench/configs/fig6.1-mlac-llr.toml`.
pub(super) fn mlac_chapter6() -> ExperimentConfig {
    let text = include_str!("../../configs/fig6.1-mlac-llr.toml");
    resolve(
        Some((Path::new("bench/configs/fig6.1-mlac-llr.toml"), text)),
        &Overrides::default(),
    )
    .expect("the shipped configuration resolves")
}

/// A curve with §3.7's input saturation ignored: the actor's outputs unbounded and
/// MLAC's `∇_u f̂` not cut at the bounds (the plant still saturates).
pub(super) fn saturation_ignored(mut cfg: ExperimentConfig) -> ExperimentConfig {
    cfg.change_agent(|a| {
        a.learning.bounded_actor = false;
        a.learning.saturation_margin = 0.0;
    })
    .expect("an unbounded actor is a valid [learning]");
    cfg
}

pub(super) fn both(a: Verdict, b: Verdict) -> Verdict {
    a.and(b)
}

pub(super) fn figures() -> Vec<Figure> {
    use Algo::*;
    use ApproxKind::*;
    use HorizonKind::{Finite, Infinite};
    use SystemName::*;
    let c = |label, cfg| Curve { label, cfg };
    vec![
        Figure {
            id: "3.12",
            title: "Figure 3.12: SAC with tile coding, RBF and LLR (pendulum)",
            curves: vec![
                c("SAC/tiles", preset(Pendulum, Sac, Tiles, Infinite)),
                c("SAC/RBF", preset(Pendulum, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(Pendulum, Sac, Llr, Infinite)),
            ],
            thesis: &[
                ("SAC/RBF", "learning dip at the start (§3.6.1, Fig. 3.10)"),
                (
                    "SAC/LLR",
                    "no learning dip; converged in about 3 min (§3.6.1, §3.6.2)",
                ),
            ],
            claims: vec![Claim {
                says: "LLR comes out on top in learning speed (§3.6.1, Fig. 3.12)",
                check: |m| {
                    both(
                        faster(m, "SAC/LLR", "SAC/RBF"),
                        faster(m, "SAC/LLR", "SAC/tiles"),
                    )
                },
            }],
        },
        Figure {
            id: "3.17",
            title: "Figure 3.17: MLAC with RBF and LLR (pendulum)",
            curves: vec![
                c("MLAC/RBF", preset(Pendulum, Mlac, Rbf, Infinite)),
                c("MLAC/LLR", preset(Pendulum, Mlac, Llr, Infinite)),
                c(
                    "MLAC/RBF, saturation ignored",
                    saturation_ignored(preset(Pendulum, Mlac, Rbf, Infinite)),
                ),
                c(
                    "MLAC/LLR, saturation ignored",
                    saturation_ignored(preset(Pendulum, Mlac, Llr, Infinite)),
                ),
            ],
            thesis: &[
                ("MLAC/RBF", "converges in over 10 min (§3.6.2)"),
                (
                    "MLAC/LLR",
                    "converges in just over 3 min; maximum after about 2–2.5 min (§3.6.2)",
                ),
            ],
            claims: vec![
                Claim {
                    says: "LLR is far superior to RBF in learning speed and performance (§3.6.2)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "MLAC/RBF"),
                            better(m, "MLAC/LLR", "MLAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "input saturation must be dealt with when learning a process model: simply ignoring it does not produce a well-performing policy (§3.7; ignored = actor outputs unbounded and ∇_u f̂ not cut at the bounds)",
                    check: |m| {
                        both(
                            clearly_better(m, "MLAC/RBF", "MLAC/RBF, saturation ignored"),
                            clearly_better(m, "MLAC/LLR", "MLAC/LLR, saturation ignored"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "3.22",
            title: "Figure 3.22: RMAC with RBF and LLR (pendulum)",
            curves: vec![
                c("RMAC/RBF", preset(Pendulum, Rmac, Rbf, Infinite)),
                c("RMAC/LLR", preset(Pendulum, Rmac, Llr, Infinite)),
            ],
            thesis: &[
                (
                    "RMAC/RBF",
                    "a tad slower than LLR, better final policy (§3.6.3)",
                ),
                (
                    "RMAC/LLR",
                    "faster, but a final policy not near as good (§3.6.3)",
                ),
            ],
            claims: vec![
                Claim {
                    says: "LLR still outperforms RBF in learning speed (§3.6.3)",
                    check: |m| faster(m, "RMAC/LLR", "RMAC/RBF"),
                },
                Claim {
                    says: "but the final policy with LLR is not near as good (§3.6.3)",
                    check: |m| better(m, "RMAC/RBF", "RMAC/LLR"),
                },
            ],
        },
        Figure {
            id: "3.23",
            title: "Figure 3.23: SAC, MLAC and RMAC with RBF and LLR (pendulum)",
            curves: vec![
                c("SAC/RBF", preset(Pendulum, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(Pendulum, Sac, Llr, Infinite)),
                c("MLAC/RBF", preset(Pendulum, Mlac, Rbf, Infinite)),
                c("MLAC/LLR", preset(Pendulum, Mlac, Llr, Infinite)),
                c("RMAC/RBF", preset(Pendulum, Rmac, Rbf, Infinite)),
                c("RMAC/LLR", preset(Pendulum, Rmac, Llr, Infinite)),
            ],
            thesis: &[],
            claims: vec![
                Claim {
                    says: "LLR is the approximator of choice for quick learning: with each algorithm it learns faster than RBFs (§3.7)",
                    check: |m| {
                        both(
                            both(
                                faster(m, "SAC/LLR", "SAC/RBF"),
                                faster(m, "MLAC/LLR", "MLAC/RBF"),
                            ),
                            faster(m, "RMAC/LLR", "RMAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "MLAC and RMAC only show their power with LLR: with LLR they learn faster than SAC/LLR (§3.7)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "SAC/LLR"),
                            faster(m, "RMAC/LLR", "SAC/LLR"),
                        )
                    },
                },
                Claim {
                    says: "model learning speeds learning up: MLAC/LLR learns fastest of all (§3.7)",
                    check: |m| fastest(m, "MLAC/LLR"),
                },
                Claim {
                    says: "with RBFs, MLAC and RMAC do not learn faster than SAC (§3.7)",
                    check: |m| {
                        both(
                            not(faster(m, "MLAC/RBF", "SAC/RBF")),
                            not(faster(m, "RMAC/RBF", "SAC/RBF")),
                        )
                    },
                },
                Claim {
                    says: "the LLR versions of SAC and MLAC end much better than their RBF counterparts (§3.7)",
                    check: |m| {
                        both(
                            better(m, "SAC/LLR", "SAC/RBF"),
                            better(m, "MLAC/LLR", "MLAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "RMAC/LLR does not reach the best solution; RMAC is the only method that ends better with RBFs (§3.7)",
                    check: |m| {
                        let best = m
                            .iter()
                            .max_by(|a, b| a.final_greedy.total_cmp(&b.final_greedy))
                            .expect("curves");
                        let text = format!(
                            "best final greedy return: {} {:.1}",
                            best.label, best.final_greedy
                        );
                        both(
                            Verdict::new(best.label != "RMAC/LLR", text),
                            better(m, "RMAC/RBF", "RMAC/LLR"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "4.4",
            title: "Figure 4.4: SAC-FH, MLAC-FH and RMAC-FH (pendulum, finite horizon)",
            curves: vec![
                c("SAC-FH", preset(Pendulum, Sac, Rbf, Finite)),
                c("MLAC-FH", preset(Pendulum, Mlac, Rbf, Finite)),
                c("RMAC-FH", preset(Pendulum, Rmac, Rbf, Finite)),
            ],
            thesis: &[
                ("SAC-FH", "last episode −995.7 ± 199.4 (Table 4.1)"),
                ("MLAC-FH", "last episode −835.4 ± 55.4 (Table 4.1)"),
                ("RMAC-FH", "last episode −840.8 ± 38.0 (Table 4.1)"),
            ],
            claims: vec![Claim {
                says: "a learned model enhances the policy's quality, and MLAC-FH's learning speed (§4.5)",
                check: |m| {
                    both(
                        both(
                            better(m, "MLAC-FH", "SAC-FH"),
                            better(m, "RMAC-FH", "SAC-FH"),
                        ),
                        faster(m, "MLAC-FH", "SAC-FH"),
                    )
                },
            }],
        },
        Figure {
            id: "5.5",
            title: "Figure 5.5: two-link arm, Case I (vertical, damping injection)",
            curves: vec![
                c("SAC/RBF", preset(ArmVertical, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(ArmVertical, Sac, Llr, Infinite)),
                c("MLAC/LLR", preset(ArmVertical, Mlac, Llr, Infinite)),
            ],
            thesis: &[
                ("SAC/RBF", "reaches it after more than 45 min (§5.3.2)"),
                ("SAC/LLR", "a similar result after 10 min (§5.3.2)"),
                (
                    "MLAC/LLR",
                    "close to its final result in less than 3 min (§5.3.2)",
                ),
            ],
            claims: vec![
                Claim {
                    says: "MLAC/LLR reaches its final level first, then SAC/LLR, then SAC/RBF (§5.3)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "SAC/LLR"),
                            faster(m, "SAC/LLR", "SAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "LLR learns a good policy in about 25–50 % of the time RBFs take (§5.5)",
                    check: |m| llr_share(m),
                },
                Claim {
                    says: "SAC/RBF's learning dips slightly between 10 and 30 minutes (optimistic initialisation); LLR overcomes this (§5.5)",
                    check: rbf_dip,
                },
                Claim {
                    says: "SAC/RBF's final policy is better than those learned with LLR (§5.5)",
                    check: |m| {
                        both(
                            better(m, "SAC/RBF", "SAC/LLR"),
                            better(m, "SAC/RBF", "MLAC/LLR"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "5.9",
            title: "Figure 5.9: two-link arm, Case II (horizontal, reaching)",
            curves: vec![
                c("SAC/RBF", preset(ArmHorizontal, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(ArmHorizontal, Sac, Llr, Infinite)),
                c("MLAC/LLR", preset(ArmHorizontal, Mlac, Llr, Infinite)),
            ],
            thesis: &[
                (
                    "SAC/RBF",
                    "≥ 40 min more than MLAC/LLR to an equivalent return (§5.4.2)",
                ),
                (
                    "SAC/LLR",
                    "≥ 20 min more than MLAC/LLR to an equivalent return (§5.4.2)",
                ),
                ("MLAC/LLR", "close to its final policy after 5 min (§5.4.2)"),
            ],
            claims: vec![
                Claim {
                    says: "MLAC/LLR reaches its final policy a lot sooner than both others (§5.4)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "SAC/LLR"),
                            faster(m, "MLAC/LLR", "SAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "LLR learns a good policy in about 25–50 % of the time RBFs take (§5.5)",
                    check: |m| llr_share(m),
                },
                Claim {
                    says: "SAC/RBF's learning dips slightly between 10 and 30 minutes (optimistic initialisation); LLR overcomes this (§5.5)",
                    check: rbf_dip,
                },
                Claim {
                    says: "in final return MLAC/LLR outperforms SAC/LLR and is only slightly behind SAC/RBF (§5.4)",
                    check: |m| better(m, "MLAC/LLR", "SAC/LLR"),
                },
            ],
        },
        Figure {
            id: "6.1",
            title: "Figure 6.1: MLAC, VGBP-LLR, VGBP-LSTD and SARSA (pendulum)",
            curves: vec![
                c("MLAC/LLR", mlac_chapter6()),
                c("VGBP-LLR", preset(Pendulum, Vgbp, Llr, Infinite)),
                c(EQ_6_21, vgbp_lstd_eq_6_21()),
                c(SEARCH, preset(Pendulum, Vgbp, Lstd, Infinite)),
                c("SARSA", preset(Pendulum, Sarsa, Rbf, Infinite)),
                c(
                    "VGBP-RBF (TD, per sample)",
                    preset(Pendulum, Vgbp, Rbf, Infinite),
                ),
            ],
            thesis: &[
                ("MLAC/LLR", "converges in about 9 min (§6.4.1)"),
                (
                    "VGBP-LLR",
                    "converges after 3 min; final slightly worse than MLAC (§6.4.1)",
                ),
                (
                    EQ_6_21,
                    "“A swing-up is learned in less than a minute of system interaction” (§6.4.1)",
                ),
                (SEARCH, "— (not in the thesis)"),
                (
                    "SARSA",
                    "needs more interaction; final slightly better than VGBP-LLR (§6.4.1)",
                ),
            ],
            claims: vec![
                Claim {
                    says: "VGBP-LLR converges faster than MLAC (3 vs 9 min), to a slightly worse policy (§6.4.1)",
                    check: |m| {
                        both(
                            faster(m, "VGBP-LLR", "MLAC/LLR"),
                            better(m, "MLAC/LLR", "VGBP-LLR"),
                        )
                    },
                },
                Claim {
                    says: "SARSA needs more interaction than the model-learning algorithms (§6.4.1)",
                    check: |m| {
                        both(
                            faster(m, "VGBP-LLR", "SARSA"),
                            faster(m, "MLAC/LLR", "SARSA"),
                        )
                    },
                },
                Claim {
                    says: "VGBP-LSTD achieved the highest learning speed (§6.5)",
                    check: |m| fastest_of(m, EQ_6_21, SEARCH),
                },
                Claim {
                    says: "VGBP's final policy is less stable: it needed two or three swings to get the pendulum upright, the other algorithms the same number each time (§6.5; swings of each run's final greedy policy)",
                    check: |m| {
                        let distinct = |label| swing_counts(find(m, label));
                        let (vgbp, v_text) = distinct(EQ_6_21);
                        let (mlac, m_text) = distinct("MLAC/LLR");
                        let (sarsa, s_text) = distinct("SARSA");
                        let text = format!("{v_text}; {m_text}; {s_text}");
                        Verdict::new(vgbp.len() > mlac.len().max(sarsa.len()), text)
                    },
                },
                Claim {
                    says: "updating the critic at the end of a trial performs better than updating it at each sample (§6.5; checked against VGBP with a per-sample TD(λ) critic on the same RBF grid — a per-sample LSTD was not run)",
                    check: |m| better(m, EQ_6_21, "VGBP-RBF (TD, per sample)"),
                },
            ],
        },
        Figure {
            id: "6.5",
            title: "Figure 6.5: VGBP-LSTD on the 2-DOF manipulator (§6.4.2)",
            curves: vec![c("VGBP-LSTD", preset(Arm64, Vgbp, Lstd, Infinite))],
            thesis: &[(
                "VGBP-LSTD",
                "a proper policy in a short time; a low minimum bound from runs leaving the range (§6.4.2)",
            )],
            claims: vec![
                Claim {
                    says: "VGBP tends to explore unseen states, including bad terminal states (§6.4.2)",
                    check: |m| {
                        let v = &m[0];
                        let text = format!(
                            "{} of {} learning trials left the operating range",
                            v.ended_early,
                            v.runs * v.trials
                        );
                        Verdict::new(v.ended_early > 0, text)
                    },
                },
                Claim {
                    says: "where extreme actions are required for large parts of the state space, the maximum action is taken (§6.5; at least half the samples of the final policies at a bound)",
                    check: |m| {
                        let v = &m[0];
                        let text = format!(
                            "{:.0} % of the final greedy policies' samples at an action bound",
                            100.0 * v.at_bound
                        );
                        Verdict::new(v.at_bound >= 0.5, text)
                    },
                },
                Claim {
                    says: "VGBP finds a proper policy in a short amount of time (§6.4.2)",
                    check: |m| {
                        let v = &m[0];
                        let text = format!(
                            "final greedy return {:.0} ± {:.0}; rise time t₉₀ {:.1} min",
                            v.final_greedy, v.final_greedy_sd, v.reaches_min
                        );
                        Verdict::new(v.reaches_min < 10.0, text)
                    },
                },
            ],
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Figure 6.1 shows VGBP-LSTD as the thesis has it (Eq. 6.21 as printed) and this
    /// project's search beside it, which differ only in the action selection; the
    /// thesis's claims about VGBP-LSTD are checked on the thesis's curve.
    #[test]
    fn figure_6_1_has_the_thesis_curve_and_the_search_beside_it() {
        let f = figures().into_iter().find(|f| f.id == "6.1").unwrap();
        let cfg = |label| &f.curves.iter().find(|c| c.label == label).unwrap().cfg;
        let (thesis, ours) = (cfg(EQ_6_21), cfg(SEARCH));
        let v = thesis.agent().vgbp.as_ref().unwrap();
        assert_eq!((v.lookahead, v.grid), (0, 0));
        assert!(ours.agent().vgbp.as_ref().unwrap().grid > 0);
        let mut same = ours.clone();
        same.change_agent(|a| a.vgbp = thesis.agent().vgbp.clone())
            .unwrap();
        assert_eq!(&same, thesis);
        let said: Vec<&str> = f.thesis.iter().map(|(label, _)| *label).collect();
        assert!(said.contains(&EQ_6_21) && said.contains(&SEARCH));
        assert!(f.thesis.iter().all(|(_, says)| !says.contains("−1000")));
    }

    /// What the report says the thesis says names where the thesis says it.
    #[test]
    fn every_thesis_statement_and_claim_cites_its_section() {
        let cited = |s: &str| s.contains('§') || s.contains("Table");
        for f in figures() {
            for (label, says) in f.thesis {
                assert!(
                    cited(says) || label.contains("this project"),
                    "{}: {says}",
                    f.id
                );
            }
            for c in &f.claims {
                assert!(cited(c.says), "{}: {}", f.id, c.says);
            }
        }
    }
}
