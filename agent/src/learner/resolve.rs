//! A configuration resolved against its task into a [`Learner`]: the sections the
//! algorithm has, each component of an approximator it can use where it sits, every
//! value in its allowed range; an error names the key and what is allowed.

use plant::Task;
use plant::config::ConfigError;

use super::{
    Algorithm, Learner, ModelParts, Plain, SacParts, SarsaParts, Smooth, VgbpCritic, VgbpParts,
};
use crate::config::{
    AgentConfig, Algo, ApproxKind, Component, HorizonKind, LqrConfig, PlanningConfig, RbfConfig,
    SarsaConfig, Slot, VgbpConfig, finite_horizon_unsupported,
};

impl AgentConfig {
    /// Checks every value against its allowed range and `task`'s dimensions, and that the
    /// sections present are those the algorithm has: [`AgentConfig::resolve`] without
    /// its result.
    pub fn validate(&self, task: &Task) -> Result<(), ConfigError> {
        self.resolve(task).map(drop)
    }

    /// The learner this configuration describes for `task`: each of the algorithm's
    /// components of an approximator it can use, every value in its allowed range. The
    /// error names the key and what is allowed.
    pub fn resolve(&self, task: &Task) -> Result<Learner, ConfigError> {
        if self.horizon == HorizonKind::Finite && !self.algo.has_actor() {
            return Err(finite_horizon_unsupported(self.algo));
        }
        self.learning.validate(self.horizon)?;
        self.algo.check_approx(self.approx)?;
        self.refuse_foreign_sections()?;
        Ok(Learner {
            algorithm: self.algorithm(task)?,
            learning: self.learning.clone(),
            horizon: self.horizon,
            planning: self.planning_section()?,
            lqr: self.lqr_section(task)?,
        })
    }

    /// The sections the algorithm does not have are absent.
    fn refuse_foreign_sections(&self) -> Result<(), ConfigError> {
        let algo = self.algo;
        if self.actor.is_some() && !algo.has_actor() {
            return Err(ConfigError::new(
                "actor",
                format!("{algo} has no actor: remove the [actor] section"),
            ));
        }
        if self.model.is_some() && !algo.has_model() {
            return Err(ConfigError::new(
                "model",
                format!("{algo} learns no process model: remove the [model] section"),
            ));
        }
        if self.vgbp.is_some() && algo != Algo::Vgbp {
            return Err(ConfigError::new(
                "vgbp",
                format!("{algo} is not vgbp: remove the [vgbp] section"),
            ));
        }
        if self.sarsa.is_some() && algo != Algo::Sarsa {
            return Err(ConfigError::new(
                "sarsa",
                format!("{algo} is not sarsa: remove the [sarsa] section"),
            ));
        }
        Ok(())
    }

    /// The algorithm with its components, each checked where it sits: actor, reference
    /// model and critic read the state (and time if the horizon is finite, Eq. 4.6), the
    /// process model the state and the action.
    fn algorithm(&self, task: &Task) -> Result<Algorithm, ConfigError> {
        let (n, m) = (task.state_dim(), task.action_dim());
        let own = [self.approx];
        let (dim, what) = if self.horizon == HorizonKind::Finite {
            (n + 1, "state component and time")
        } else {
            (n, "state component")
        };
        let slot = |section, kinds, dim, what| Slot {
            section,
            kinds,
            dim,
            what,
            algo: self.algo,
            approx: self.approx,
        };
        let actor = || slot("actor", &own, dim, what);
        let critic = || slot("critic", &own, dim, what);
        // VGBP's process model is LLR whatever its critic (§6.3.1); the others learn every
        // component with the same approximator.
        let model_kinds: &[ApproxKind] = if self.algo == Algo::Vgbp {
            &[ApproxKind::Llr, ApproxKind::Rbf]
        } else {
            &own
        };
        let model = || slot("model", model_kinds, n + m, "state and action component");
        let algo = self.algo;
        let model_parts = || -> Result<ModelParts, ConfigError> {
            Ok(ModelParts {
                actor: self.actor()?.smooth(&actor())?,
                critic: self.critic.smooth(&critic())?,
                model: self.model()?.smooth(&model())?,
            })
        };
        Ok(match algo {
            Algo::Sac => Algorithm::Sac(SacParts {
                actor: self.actor()?.plain(&actor())?,
                critic: self.critic.plain(&critic())?,
            }),
            Algo::Mlac => Algorithm::Mlac(model_parts()?),
            Algo::Rmac => Algorithm::Rmac(model_parts()?),
            Algo::Vgbp => Algorithm::Vgbp(VgbpParts {
                critic: self.critic.vgbp_critic(&critic())?,
                model: self.model()?.smooth(&model())?,
                vgbp: self.vgbp_section(task)?,
            }),
            Algo::Sarsa => Algorithm::Sarsa(SarsaParts {
                q: self.critic.rbf(&critic())?,
                sarsa: self.sarsa_section(task)?,
            }),
        })
    }

    /// `[actor]`, which the algorithm has.
    fn actor(&self) -> Result<&Component, ConfigError> {
        self.actor.as_ref().ok_or_else(|| {
            ConfigError::new(
                "actor",
                format!("{} has an actor: an [actor] section is required", self.algo),
            )
        })
    }

    /// `[model]`, which the algorithm has.
    fn model(&self) -> Result<&Component, ConfigError> {
        self.model.as_ref().ok_or_else(|| {
            ConfigError::new(
                "model",
                format!(
                    "{} learns a process model: a [model] section is required",
                    self.algo
                ),
            )
        })
    }

    /// `[vgbp]`, checked; VGBP also needs a reward strictly concave in the action.
    fn vgbp_section(&self, task: &Task) -> Result<VgbpConfig, ConfigError> {
        let v = self
            .vgbp
            .as_ref()
            .ok_or_else(|| ConfigError::new("vgbp", "vgbp needs a [vgbp] section"))?;
        v.validate()?;
        if task.reward.p.iter().any(|&p| p <= 0.0) {
            return Err(ConfigError::new(
                "algo",
                format!(
                    "vgbp needs a reward strictly concave in the action (P > 0); {} has P = {:?}",
                    task.name, task.reward.p
                ),
            ));
        }
        Ok(v.clone())
    }

    /// A section that chooses MLAC's actions with its process model (`[planning]`,
    /// `[lqr]`) needs MLAC with an infinite horizon; `does` says what the section does.
    fn needs_mlac_model(&self, section: &str, does: &str) -> Result<(), ConfigError> {
        if self.algo == Algo::Mlac && self.horizon == HorizonKind::Infinite {
            return Ok(());
        }
        Err(ConfigError::new(
            section,
            format!(
                "{does} with MLAC's process model and an infinite horizon; {} with a {} horizon has none: remove the [{section}] section",
                self.algo, self.horizon
            ),
        ))
    }

    /// `[planning]`, checked: MLAC's, with an infinite horizon.
    fn planning_section(&self) -> Result<Option<PlanningConfig>, ConfigError> {
        let Some(p) = &self.planning else {
            return Ok(None);
        };
        self.needs_mlac_model("planning", "plans")?;
        p.validate()?;
        Ok(Some(p.clone()))
    }

    /// `[lqr]`, checked: MLAC's, with an infinite horizon, and not beside `[planning]`.
    fn lqr_section(&self, task: &Task) -> Result<Option<LqrConfig>, ConfigError> {
        let Some(l) = &self.lqr else {
            return Ok(None);
        };
        self.needs_mlac_model("lqr", "regulates")?;
        if self.planning.is_some() {
            return Err(ConfigError::new(
                "lqr",
                "[lqr] and [planning] both choose MLAC's actions: keep one of them",
            ));
        }
        l.validate(task)?;
        Ok(Some(l.clone()))
    }

    /// `[sarsa]`, checked.
    fn sarsa_section(&self, task: &Task) -> Result<SarsaConfig, ConfigError> {
        let s = self
            .sarsa
            .as_ref()
            .ok_or_else(|| ConfigError::new("sarsa", "sarsa needs a [sarsa] section"))?;
        s.validate(task)?;
        Ok(s.clone())
    }
}

impl Component {
    /// The component as an approximator with a gradient, checked for `at`.
    pub(crate) fn smooth(&self, at: &Slot) -> Result<Smooth, ConfigError> {
        self.validate(at)?;
        match self {
            Component::Llr(c) => Ok(Smooth::Llr(c.clone())),
            Component::Rbf(c) => Ok(Smooth::Rbf(c.clone())),
            _ => Err(self.misplaced(at)),
        }
    }

    /// The component as any approximator but LSTD, checked for `at`.
    pub(crate) fn plain(&self, at: &Slot) -> Result<Plain, ConfigError> {
        match self {
            Component::Tiles(c) => self.validate(at).map(|()| Plain::Tiles(c.clone())),
            _ => self.smooth(at).map(Plain::Smooth),
        }
    }

    /// The component as VGBP's critic, checked for `at`.
    pub(crate) fn vgbp_critic(&self, at: &Slot) -> Result<VgbpCritic, ConfigError> {
        match self {
            Component::Lstd(c) => self.validate(at).map(|()| VgbpCritic::Lstd(c.clone())),
            _ => self.smooth(at).map(VgbpCritic::Td),
        }
    }

    /// The component as an RBF grid, checked for `at`.
    pub(crate) fn rbf(&self, at: &Slot) -> Result<RbfConfig, ConfigError> {
        match self.smooth(at)? {
            Smooth::Rbf(c) => Ok(c),
            Smooth::Llr(_) => Err(self.misplaced(at)),
        }
    }
}
