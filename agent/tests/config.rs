//! The validation of the agent's configuration, on the presets' learners varied: the
//! sections present must be those of the algorithm, each of the approximator it expects.

use agent::config::{AgentConfig, Algo, ApproxKind, HorizonKind};
use agent::preset::preset;
use plant::{SystemName, Task};

fn pendulum(algo: Algo, approx: ApproxKind, horizon: HorizonKind) -> AgentConfig {
    preset(SystemName::Pendulum, algo, approx, horizon)
        .unwrap()
        .agent
}

#[test]
fn sections_must_be_those_of_the_algorithm() {
    let task = Task::new(SystemName::Pendulum);
    let mut c = pendulum(Algo::Mlac, ApproxKind::Llr, HorizonKind::Infinite);
    c.validate(&task).unwrap();
    c.model = None;
    assert_eq!(c.validate(&task).unwrap_err().key, "model");
    let mut c = pendulum(Algo::Sac, ApproxKind::Rbf, HorizonKind::Finite);
    c.validate(&task).unwrap();
    // Validation, for a configuration not made from a preset.
    c.algo = Algo::Sarsa;
    assert_eq!(c.validate(&task).unwrap_err().key, "horizon");
    let mut c = pendulum(Algo::Vgbp, ApproxKind::Lstd, HorizonKind::Infinite);
    c.sarsa = pendulum(Algo::Sarsa, ApproxKind::Rbf, HorizonKind::Infinite).sarsa;
    let e = c.validate(&task).unwrap_err();
    assert_eq!(e.message, "vgbp is not sarsa: remove the [sarsa] section");
}

#[test]
fn a_component_of_another_approximator_is_named() {
    let task = Task::new(SystemName::Pendulum);
    let mut c = pendulum(Algo::Sac, ApproxKind::Llr, HorizonKind::Infinite);
    c.critic = pendulum(Algo::Sac, ApproxKind::Rbf, HorizonKind::Infinite).critic;
    let e = c.validate(&task).unwrap_err();
    assert_eq!(
        e.to_string(),
        "`critic`: holds rbf parameters; sac expects llr parameters here (approx = \"llr\")"
    );
}
