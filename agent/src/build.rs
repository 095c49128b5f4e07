//! Assembles an agent from a validated configuration.

use plant::Task;

use crate::Agent;
use crate::actor_critic::{ActorCritic, Improver, Learning, TaskInfo};
use crate::approx::llr::{Eviction, Llr, LlrParams, Search};
use crate::approx::rbf::{Rbf, RbfParams};
use crate::approx::tiles::{Tiles, TilesParams};
use crate::approx::{Approximator, Differentiable, ValueFunction};
use crate::config::{AgentConfig, Algo, Component, LstdPrior, SarsaConfig};
use crate::critic::{Critic, TdLambda};
use crate::explore::Exploration;
use crate::horizon::Horizon;
use crate::lstd::Lstd;
use crate::mlac::Mlac;
use crate::model::ProcessModel;
use crate::rmac::Rmac;
use crate::sac::Sac;
use crate::sarsa::{Epsilon, Sarsa};
use crate::vgbp::Vgbp;

/// Where an approximator lives: its input space and output size and bounds.
struct Space {
    range: Vec<(f64, f64)>,
    periodic: Vec<bool>,
    outputs: usize,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
}

enum Built {
    Llr(Box<Llr>),
    Rbf(Box<Rbf>),
    Tiles(Box<Tiles>),
}

fn make(c: &Component, s: &Space) -> Built {
    match c {
        Component::Llr(l) => Built::Llr(Box::new(Llr::new(&LlrParams {
            memory: l.memory,
            neighbours: l.neighbours,
            weights: l.weights.clone(),
            periodic: s.periodic.clone(),
            outputs: s.outputs,
            bounds: s.bounds.clone(),
            eviction: if l.eviction == "redundant" {
                Eviction::Redundant(l.redundancy_radius)
            } else {
                Eviction::Oldest
            },
            search: Search::KdTree,
            clip_to_neighbours: l.clip_to_neighbours,
        }))),
        Component::Rbf(r) => Built::Rbf(Box::new(rbf(&r.centres, r.intersection, s))),
        Component::Lstd(l) => Built::Rbf(Box::new(rbf(&l.centres, l.intersection, s))),
        Component::Tiles(t) => Built::Tiles(Box::new(Tiles::new(&TilesParams {
            tilings: t.tilings,
            tiles: t.tiles.clone(),
            range: s.range.clone(),
            periodic: s.periodic.clone(),
            outputs: s.outputs,
            bounds: s.bounds.clone(),
        }))),
    }
}

fn rbf(centres: &[usize], intersection: f64, s: &Space) -> Rbf {
    Rbf::new(&RbfParams {
        centres: centres.to_vec(),
        range: s.range.clone(),
        periodic: s.periodic.clone(),
        intersection,
        outputs: s.outputs,
        initial: 0.0,
        bounds: s.bounds.clone(),
    })
}

impl Built {
    fn any(self) -> Box<dyn Approximator> {
        match self {
            Built::Llr(a) => a,
            Built::Rbf(a) => a,
            Built::Tiles(a) => a,
        }
    }
    fn differentiable(self) -> Box<dyn Differentiable> {
        match self {
            Built::Llr(a) => a,
            Built::Rbf(a) => a,
            Built::Tiles(_) => {
                unreachable!("validation rejects tile coding where a gradient is needed")
            }
        }
    }
    fn value_function(self) -> Box<dyn ValueFunction> {
        match self {
            Built::Llr(a) => a,
            Built::Rbf(a) => a,
            // A tile-coding critic is used by SAC only, which never asks for its gradient.
            Built::Tiles(a) => Box::new(GradientFree(*a)),
        }
    }
}

/// A tile-coding critic for SAC: SAC never asks the critic for a gradient.
struct GradientFree(Tiles);

impl Approximator for GradientFree {
    fn input_dim(&self) -> usize {
        self.0.input_dim()
    }
    fn output_dim(&self) -> usize {
        self.0.output_dim()
    }
    fn value(&self, x: &[f64], y: &mut [f64]) {
        self.0.value(x, y)
    }
    fn shift(&mut self, x: &[f64], step: &[f64]) {
        self.0.shift(x, step)
    }
    fn fit(&mut self, x: &[f64], target: &[f64], rate: f64) {
        self.0.fit(x, target, rate)
    }
}

impl crate::checkpoint::Persist for GradientFree {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        self.0.save(s)
    }
    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        self.0.restore(r)
    }
}

impl Differentiable for GradientFree {
    fn value_and_jacobian(&self, _: &[f64], _: &mut [f64], _: &mut [f64]) {
        unreachable!("tile coding has no gradient; validation allows it for SAC only")
    }
}

impl crate::approx::Traced for GradientFree {
    fn visit(&mut self, x: &[f64], decay: f64) {
        self.0.visit(x, decay)
    }
    fn visit_value(&mut self, x: &[f64], decay: f64) -> f64 {
        self.0.visit_value(x, decay)
    }
    fn apply_td(&mut self, step: f64) {
        self.0.apply_td(step)
    }
    fn clear_traces(&mut self) {
        self.0.clear_traces()
    }
}

/// The agent `cfg` describes, for `task`, with every random stream derived from
/// `run_seed`.
pub fn build(task: &Task, cfg: &AgentConfig, run_seed: u64) -> Box<dyn Agent> {
    let spaces = Spaces {
        task,
        horizon: cfg.horizon.of(task),
    };
    if let Some(s) = &cfg.sarsa {
        return sarsa(&spaces, cfg, s, run_seed);
    }
    let info = TaskInfo {
        horizon: spaces.horizon,
        ..TaskInfo::of(task)
    };
    let l = &cfg.learning;
    Box::new(ActorCritic::new(
        info.clone(),
        Learning {
            gamma: l.gamma,
            lambda: l.lambda,
        },
        critic(&spaces, cfg),
        improver(&spaces, cfg, info),
        Exploration::new(l.sigma, l.explore_every, run_seed),
    ))
}

/// The input spaces of a task's approximators.
struct Spaces<'a> {
    task: &'a Task,
    horizon: Horizon,
}

impl Spaces<'_> {
    /// The space of actors, critics and reference models: the state, and time if the
    /// horizon is finite (Eq. 4.6); `outputs` outputs, within `bounds` if given.
    fn state(&self, outputs: usize, bounds: Option<(Vec<f64>, Vec<f64>)>) -> Space {
        let (task, time) = (self.task, self.horizon.time_range());
        Space {
            range: task.state_range.iter().copied().chain(time).collect(),
            periodic: task
                .angle_mask
                .iter()
                .copied()
                .chain(time.map(|_| false))
                .collect(),
            outputs,
            bounds,
        }
    }

    /// The process model's space: state and action in, the next state out.
    fn model(&self) -> Space {
        let task = self.task;
        let m = task.action_dim();
        let action_range = (0..m).map(|j| (task.action_low[j], task.action_high[j]));
        Space {
            range: task
                .state_range
                .iter()
                .copied()
                .chain(action_range)
                .collect(),
            periodic: task
                .angle_mask
                .iter()
                .copied()
                .chain(std::iter::repeat_n(false, m))
                .collect(),
            outputs: task.state_dim(),
            bounds: None,
        }
    }
}

/// SARSA (§6.4.1): an RBF Q-function with one output per action of the set.
fn sarsa(spaces: &Spaces, cfg: &AgentConfig, s: &SarsaConfig, run_seed: u64) -> Box<dyn Agent> {
    let actions = Sarsa::action_set(&s.actions, spaces.task.action_dim());
    let Built::Rbf(q) = make(&cfg.critic, &spaces.state(actions.len(), None)) else {
        unreachable!("validated: SARSA's Q-function is an RBF grid")
    };
    Box::new(Sarsa::new(
        *q,
        actions,
        cfg.critic.alpha(),
        cfg.learning.gamma,
        cfg.learning.lambda,
        Epsilon {
            decay: s.epsilon_decay,
            min: s.epsilon_min,
        },
        run_seed,
    ))
}

/// The critic: TD(λ) on any approximator, or LSTD (§6.4.1) on an RBF grid, optionally
/// with the reward prior.
fn critic(spaces: &Spaces, cfg: &AgentConfig) -> Box<dyn Critic> {
    match (&cfg.critic, make(&cfg.critic, &spaces.state(1, None))) {
        (Component::Lstd(c), Built::Rbf(v)) => {
            let prior = (c.prior == LstdPrior::Reward).then(|| {
                // θ_0 = ρ(c, 0) / (1 − γ): the value of staying at each centre.
                let mut centre = vec![0.0; v.input_dim()];
                (0..v.len())
                    .map(|i| {
                        v.centre(i, &mut centre);
                        spaces.task.reward.state_reward(&centre) / (1.0 - cfg.learning.gamma)
                    })
                    .collect()
            });
            Box::new(Lstd::new(*v, c.initial_a, prior))
        }
        (c, built) => Box::new(TdLambda::new(built.value_function(), c.alpha())),
    }
}

/// The algorithm's actor update: SAC, MLAC, RMAC or VGBP, with its actor (or reference
/// model) and process model.
fn improver(spaces: &Spaces, cfg: &AgentConfig, info: TaskInfo) -> Box<dyn Improver> {
    let task = spaces.task;
    let (n, m) = (task.state_dim(), task.action_dim());
    let l = &cfg.learning;
    let action_bounds = l
        .bounded_actor
        .then(|| (task.action_low.clone(), task.action_high.clone()));
    let model = || {
        let c = cfg
            .model
            .as_ref()
            .expect("validated: MLAC, RMAC and VGBP have a model");
        ProcessModel::new(
            make(c, &spaces.model()).differentiable(),
            task.angle_mask.clone(),
            c.alpha(),
        )
    };
    let actor = |outputs, bounds| {
        let c = cfg
            .actor
            .as_ref()
            .expect("validated: SAC, MLAC and RMAC have an actor");
        (make(c, &spaces.state(outputs, bounds)).any(), c.alpha())
    };
    match cfg.algo {
        Algo::Sac => {
            let (a, alpha) = actor(m, action_bounds);
            Box::new(Sac::new(a, alpha))
        }
        Algo::Mlac => {
            let (a, alpha) = actor(m, action_bounds);
            Box::new(Mlac::new(
                info,
                a,
                model(),
                alpha,
                l.gamma,
                l.saturation_margin,
            ))
        }
        Algo::Rmac => {
            let (a, alpha) = actor(n, None);
            Box::new(Rmac::new(info, a, model(), alpha))
        }
        Algo::Vgbp => Box::new(
            Vgbp::new(
                info,
                model(),
                l.gamma,
                cfg.vgbp.as_ref().map_or(0, |v| v.lookahead),
            )
            .with_action_grid(cfg.vgbp.as_ref().map_or(0, |v| v.grid))
            .with_fit_at_zero_action(cfg.vgbp.as_ref().is_some_and(|v| v.fit_at_zero_action)),
        ),
        Algo::Sarsa => unreachable!("built by `sarsa`"),
    }
}
