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
