//! Assembles an agent from a resolved learner ([`crate::learner`]).

use plant::Task;

use crate::Agent;
use crate::actor_critic::{ActorCritic, Improver, Learning, TaskInfo};
use crate::approx::llr::{Eviction, Llr, LlrParams, Search};
use crate::approx::rbf::{Rbf, RbfParams};
use crate::approx::tiles::{Tiles, TilesParams};
use crate::approx::{Approximator, Differentiable, Traced, ValueFunction};
use crate::config::{EvictionRule, LearningConfig, LstdPrior, PlanningMethod, TilesConfig};
use crate::critic::{Critic, TdLambda};
use crate::explore::Exploration;
use crate::horizon::Horizon;
use crate::ilqr::Ilqr;
use crate::learner::{Algorithm, Learner, Plain, SarsaParts, Smooth, VgbpCritic};
use crate::lqr::Lqr;
use crate::lstd::Lstd;
use crate::mlac::Mlac;
use crate::model::ProcessModel;
use crate::plan::Planner;
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

/// An approximator with a gradient, built.
enum Built {
    Llr(Box<Llr>),
    Rbf(Box<Rbf>),
}

fn smooth(c: &Smooth, s: &Space) -> Built {
    match c {
        Smooth::Llr(l) => Built::Llr(Box::new(Llr::new(&LlrParams {
            memory: l.memory,
            neighbours: l.neighbours,
            weights: l.weights.clone(),
            periodic: s.periodic.clone(),
            outputs: s.outputs,
            bounds: s.bounds.clone(),
            eviction: match l.eviction {
                EvictionRule::Redundant => Eviction::Redundant(l.redundancy_radius),
                EvictionRule::Oldest => Eviction::Oldest,
            },
            search: Search::KdTree,
            clip_to_neighbours: l.clip_to_neighbours,
        }))),
        Smooth::Rbf(r) => Built::Rbf(Box::new(rbf(&r.centres, r.intersection, s))),
    }
}

fn tiles(t: &TilesConfig, s: &Space) -> Tiles {
    Tiles::new(&TilesParams {
        tilings: t.tilings,
        tiles: t.tiles.clone(),
        range: s.range.clone(),
        periodic: s.periodic.clone(),
        outputs: s.outputs,
        bounds: s.bounds.clone(),
    })
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
    fn differentiable(self) -> Box<dyn Differentiable> {
        match self {
            Built::Llr(a) => a,
            Built::Rbf(a) => a,
        }
    }
    fn value_function(self) -> Box<dyn ValueFunction> {
        match self {
            Built::Llr(a) => a,
            Built::Rbf(a) => a,
        }
    }
}

/// SAC's actor: any approximator.
fn plain_actor(c: &Plain, s: &Space) -> Box<dyn Approximator> {
    match c {
        Plain::Smooth(c) => smooth(c, s).differentiable(),
        Plain::Tiles(t) => Box::new(tiles(t, s)),
    }
}

/// SAC's critic: any approximator; tile coding, without a gradient, too (SAC reads only
/// its values).
fn plain_critic(c: &Plain, s: &Space) -> Box<dyn Traced> {
    match c {
        Plain::Smooth(c) => smooth(c, s).value_function(),
        Plain::Tiles(t) => Box::new(tiles(t, s)),
    }
}

/// The agent `learner` describes, for `task`, with every random stream derived from
/// `run_seed`.
pub fn build(task: &Task, learner: &Learner, run_seed: u64) -> Box<dyn Agent> {
    let spaces = Spaces {
        task,
        horizon: learner.horizon.of(task),
    };
    let l = &learner.learning;
    let info = TaskInfo {
        horizon: spaces.horizon,
        ..TaskInfo::of(task)
    };
    let (critic, improver): (Box<dyn Critic>, Box<dyn Improver>) = match &learner.algorithm {
        Algorithm::Sarsa(p) => return sarsa(&spaces, p, l, run_seed),
        Algorithm::Sac(p) => {
            let actor = plain_actor(&p.actor, &spaces.actor(l));
            let critic = plain_critic(&p.critic, &spaces.state(1, None));
            let critic: Box<dyn Critic<dyn Approximator>> =
                Box::new(TdLambda::values_only(critic, p.critic.step_size()));
            let sac: Box<dyn Improver<dyn Approximator>> =
                Box::new(Sac::new(actor, p.actor.step_size()));
            return actor_critic(info, l, run_seed, critic, sac);
        }
        Algorithm::Mlac(p) => {
            let actor = smooth(&p.actor, &spaces.actor(l)).differentiable();
            let mlac = Mlac::new(
                info.clone(),
                actor,
                spaces.process_model(&p.model),
                p.actor.step_size(),
                l.gamma,
                l.saturation_margin,
            );
            let improver: Box<dyn Improver> = match (&learner.planning, &learner.lqr) {
                (Some(plan), _) if plan.method == PlanningMethod::Ilqr => Box::new(
                    Ilqr::new(mlac, plan.clone(), l.gamma).within(task.operating_range.as_ref()),
                ),
                (Some(plan), _) => Box::new(Planner::new(mlac, plan.clone(), l.gamma, run_seed)),
                (None, Some(lqr)) => Box::new(Lqr::new(mlac, lqr.clone(), l.gamma)),
                (None, None) => Box::new(mlac),
            };
            (td_critic(&spaces, &p.critic), improver)
        }
        Algorithm::Rmac(p) => {
            let n = task.state_dim();
            let reference = smooth(&p.actor, &spaces.state(n, None)).differentiable();
            let rmac = Rmac::new(
                info.clone(),
                reference,
                spaces.process_model(&p.model),
                p.actor.step_size(),
            );
            (td_critic(&spaces, &p.critic), Box::new(rmac))
        }
        Algorithm::Vgbp(p) => {
            let v = &p.vgbp;
            let vgbp = Vgbp::new(
                info.clone(),
                spaces.process_model(&p.model),
                l.gamma,
                v.lookahead,
            )
            .with_action_grid(v.grid)
            .with_fit_at_zero_action(v.fit_at_zero_action);
            (vgbp_critic(&spaces, &p.critic, l.gamma), Box::new(vgbp))
        }
    };
    actor_critic(info, l, run_seed, critic, improver)
}

/// The actor-critic of `critic` and `improver`, learning as `l` says.
fn actor_critic<F: Approximator + ?Sized + 'static>(
    info: TaskInfo,
    l: &LearningConfig,
    run_seed: u64,
    critic: Box<dyn Critic<F>>,
    improver: Box<dyn Improver<F>>,
) -> Box<dyn Agent> {
    Box::new(ActorCritic::new(
        info,
        Learning {
            gamma: l.gamma,
            lambda: l.lambda,
        },
        critic,
        improver,
        Exploration::new(l.sigma, l.explore_every, run_seed),
    ))
}

/// The input spaces of a task's approximators.
struct Spaces<'a> {
    task: &'a Task,
    horizon: Horizon,
}

impl Spaces<'_> {
    /// An actor's space: the state (and time), one output per action, within the action
    /// bounds if the actor is bounded.
    fn actor(&self, l: &LearningConfig) -> Space {
        let task = self.task;
        let bounds = l
            .bounded_actor
            .then(|| (task.action_low.clone(), task.action_high.clone()));
        self.state(task.action_dim(), bounds)
    }

    /// The learned process model on `c`.
    fn process_model(&self, c: &Smooth) -> ProcessModel {
        ProcessModel::new(
            smooth(c, &self.model()).differentiable(),
            self.task.angle_mask.clone(),
            c.alpha(),
        )
    }

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
fn sarsa(spaces: &Spaces, p: &SarsaParts, l: &LearningConfig, run_seed: u64) -> Box<dyn Agent> {
    let actions = Sarsa::action_set(&p.sarsa.actions, spaces.task.action_dim());
    let q = rbf(
        &p.q.centres,
        p.q.intersection,
        &spaces.state(actions.len(), None),
    );
    Box::new(Sarsa::new(
        q,
        actions,
        p.q.step_size(),
        l.gamma,
        l.lambda,
        Epsilon {
            decay: p.sarsa.epsilon_decay,
            min: p.sarsa.epsilon_min,
        },
        run_seed,
    ))
}

/// A TD(λ) critic on a smooth approximator.
fn td_critic(spaces: &Spaces, c: &Smooth) -> Box<dyn Critic> {
    Box::new(TdLambda::new(
        smooth(c, &spaces.state(1, None)).value_function(),
        c.step_size(),
    ))
}

/// VGBP's critic: TD(λ), or LSTD (§6.4.1) on an RBF grid, optionally with the reward
/// prior.
fn vgbp_critic(spaces: &Spaces, c: &VgbpCritic, gamma: f64) -> Box<dyn Critic> {
    let c = match c {
        VgbpCritic::Td(c) => return td_critic(spaces, c),
        VgbpCritic::Lstd(c) => c,
    };
    let v = rbf(&c.centres, c.intersection, &spaces.state(1, None));
    let prior = (c.prior == LstdPrior::Reward).then(|| {
        // θ_0 = ρ(c, 0) / (1 − γ): the value of staying at each centre.
        let mut centre = vec![0.0; v.input_dim()];
        (0..v.len())
            .map(|i| {
                v.centre(i, &mut centre);
                spaces.task.reward.state_reward(&centre) / (1.0 - gamma)
            })
            .collect()
    });
    Box::new(Lstd::new(v, c.initial_a, prior))
}
