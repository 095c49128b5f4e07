//! Assembles an agent from a validated configuration.

use plant::Task;

use crate::Agent;
use crate::actor_critic::{ActorCritic, Learning, TaskInfo};
use crate::approx::llr::{Eviction, Llr, LlrParams, Search};
use crate::approx::rbf::{Rbf, RbfParams};
use crate::approx::tiles::{Tiles, TilesParams};
use crate::approx::{Approximator, Critic, Differentiable};
use crate::config::{Algo, Component, ExperimentConfig};
use crate::explore::Exploration;
use crate::mlac::Mlac;
use crate::model::ProcessModel;
use crate::rmac::Rmac;
use crate::sac::Sac;

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
        Component::Rbf(r) => Built::Rbf(Box::new(Rbf::new(&RbfParams {
            centres: r.centres.clone(),
            range: s.range.clone(),
            periodic: s.periodic.clone(),
            intersection: r.intersection,
            outputs: s.outputs,
            initial: 0.0,
            bounds: s.bounds.clone(),
        }))),
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
    fn critic(self) -> Box<dyn Critic> {
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
pub fn build(task: &Task, cfg: &ExperimentConfig, run_seed: u64) -> Box<dyn Agent> {
    let info = TaskInfo::of(task);
    let (n, m) = (task.state_dim(), task.action_dim());
    let state = |outputs, bounds| Space {
        range: task.state_range.clone(),
        periodic: task.angle_mask.clone(),
        outputs,
        bounds,
    };
    let action_range: Vec<(f64, f64)> = (0..m)
        .map(|j| (task.action_low[j], task.action_high[j]))
        .collect();
    let model_space = Space {
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
        outputs: n,
        bounds: None,
    };
    let action_bounds = Some((task.action_low.clone(), task.action_high.clone()));
    let l = &cfg.learning;
    let critic = make(&cfg.critic, &state(1, None)).critic();
    let model = || {
        let c = cfg
            .model
            .as_ref()
            .expect("validated: MLAC and RMAC have a model");
        ProcessModel::new(
            make(c, &model_space).differentiable(),
            task.angle_mask.clone(),
            c.alpha(),
        )
    };
    let improver: Box<dyn crate::actor_critic::Improver> = match cfg.algo {
        Algo::Sac => Box::new(Sac::new(
            make(&cfg.actor, &state(m, action_bounds)).any(),
            cfg.actor.alpha(),
        )),
        Algo::Mlac => Box::new(Mlac::new(
            info.clone(),
            make(&cfg.actor, &state(m, action_bounds)).any(),
            model(),
            cfg.actor.alpha(),
            l.gamma,
            l.saturation_margin,
        )),
        Algo::Rmac => Box::new(Rmac::new(
            info.clone(),
            make(&cfg.actor, &state(n, None)).any(),
            model(),
            cfg.actor.alpha(),
        )),
    };
    Box::new(ActorCritic::new(
        info,
        Learning {
            gamma: l.gamma,
            lambda: l.lambda,
            alpha_critic: cfg.critic.alpha(),
        },
        critic,
        improver,
        Exploration::new(l.sigma, l.explore_every, run_seed),
    ))
}
