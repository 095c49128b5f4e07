//! The building blocks of the presets: LLR memories by role, RBF grids.

use crate::config::{Component, EvictionRule, LlrConfig, RbfConfig};

/// LLR memories of actors, critics and reference models replace a stored sample closer
/// than this (in scaled units) instead of purging the oldest; see the module docs.
pub const REDUNDANCY_RADIUS: f64 = 0.05;

/// SAC's actor and critic memories use a wider radius (see the module docs).
pub const SAC_REDUNDANCY_RADIUS: f64 = 0.1;

/// An actor or reference-model memory (redundancy-based management).
pub(super) fn llr(alpha: f64, memory: usize, neighbours: usize, weights: Vec<f64>) -> Component {
    Component::Llr(llr_memory(alpha, memory, neighbours, weights))
}

fn llr_memory(alpha: f64, memory: usize, neighbours: usize, weights: Vec<f64>) -> LlrConfig {
    LlrConfig {
        alpha,
        memory,
        neighbours,
        weights,
        eviction: EvictionRule::Redundant,
        redundancy_radius: REDUNDANCY_RADIUS,
        clip_to_neighbours: false,
        decay_trials: None,
        decay_power: None,
    }
}

/// A critic memory: as an actor memory, with predictions clipped to the neighbours'
/// values (see the module docs).
pub(super) fn llr_critic(
    alpha: f64,
    memory: usize,
    neighbours: usize,
    weights: Vec<f64>,
) -> Component {
    Component::Llr(LlrConfig {
        clip_to_neighbours: true,
        ..llr_memory(alpha, memory, neighbours, weights)
    })
}

/// A process-model memory: it only stores transitions, and the thesis's 100 most recent
/// ones (Table 3.2) are what it is tuned for, so the oldest is purged.
pub(super) fn llr_model(memory: usize, neighbours: usize, weights: Vec<f64>) -> Component {
    Component::Llr(LlrConfig {
        alpha: 0.0,
        memory,
        neighbours,
        weights,
        eviction: EvictionRule::Oldest,
        redundancy_radius: 0.0,
        clip_to_neighbours: false,
        decay_trials: None,
        decay_power: None,
    })
}

/// An RBF network with `centres` per input and neighbouring functions intersecting at
/// `intersection` (Table 3.1).
pub(super) fn rbf(alpha: f64, centres: Vec<usize>, intersection: f64) -> Component {
    Component::Rbf(RbfConfig {
        alpha,
        centres,
        intersection,
        decay_trials: None,
        decay_power: None,
    })
}
