//! `[actor]`, `[critic]`, `[model]`: one approximator's parameters each, and their
//! validation against the approximator the algorithm expects there and the input
//! dimension.

use plant::config::{ConfigError, check_float, check_int, check_len};
use serde::{Deserialize, Serialize};

use super::{Algo, ApproxKind};
use crate::step_size::{Decay, StepSize};

/// One approximator's parameters; which kind is given by the configuration's `approx`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Component {
    /// Local linear regression.
    Llr(LlrConfig),
    /// Normalised RBF grid.
    Rbf(RbfConfig),
    /// Tile coding.
    Tiles(TilesConfig),
    /// LSTD(λ) on an RBF grid.
    Lstd(LstdConfig),
}

/// LLR memory parameters (Tables 3.2, 6.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LlrConfig {
    /// Learning rate (`α_a`, `α_c`, `α_r`; 0 for a process model, which only stores).
    pub alpha: f64,
    /// Memory size `N`.
    pub memory: usize,
    /// Nearest neighbours `K`.
    pub neighbours: usize,
    /// Input scaling `diag(W)`.
    pub weights: Vec<f64>,
    /// Memory management.
    pub eviction: EvictionRule,
    /// With "redundant": a new sample replaces a stored one closer than this (scaled).
    pub redundancy_radius: f64,
    /// Limit predictions to the range of the neighbours' outputs (no extrapolation).
    pub clip_to_neighbours: bool,
    /// The learning rate's decay `τ` in trials: `α_k = α · (τ / (τ + k))^p` after `k`
    /// learning trials ([`crate::step_size`]); none (the thesis's constant rate) by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_trials: Option<f64>,
    /// The decay's power `p` in `(1/2, 1]` (1 if not given); only with `decay_trials`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_power: Option<f64>,
}

plant::choice! {
    /// How a full LLR memory makes room for a new sample (§3.5.2).
    #[derive(Debug, PartialEq, Eq)]
    pub enum EvictionRule {
        /// The oldest sample goes.
        Oldest => "oldest",
        /// A stored sample closer than `redundancy_radius` to the new one goes, else the
        /// oldest.
        Redundant => "redundant",
    }
}

/// RBF grid parameters (Table 3.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RbfConfig {
    /// Learning rate.
    pub alpha: f64,
    /// Centres along each input.
    pub centres: Vec<usize>,
    /// Intersection height of neighbouring basis functions.
    pub intersection: f64,
    /// The learning rate's decay `τ` in trials: `α_k = α · (τ / (τ + k))^p` after `k`
    /// learning trials ([`crate::step_size`]); none (the thesis's constant rate) by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_trials: Option<f64>,
    /// The decay's power `p` in `(1/2, 1]` (1 if not given); only with `decay_trials`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_power: Option<f64>,
}

/// Tile-coding parameters (§3.6.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TilesConfig {
    /// Learning rate.
    pub alpha: f64,
    /// Number of tilings.
    pub tilings: usize,
    /// Tiles along each input.
    pub tiles: Vec<usize>,
    /// The learning rate's decay `τ` in trials: `α_k = α · (τ / (τ + k))^p` after `k`
    /// learning trials ([`crate::step_size`]); none (the thesis's constant rate) by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_trials: Option<f64>,
    /// The decay's power `p` in `(1/2, 1]` (1 if not given); only with `decay_trials`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_power: Option<f64>,
}

/// LSTD critic parameters (§6.4.1, Table 6.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LstdConfig {
    /// Centres along each input.
    pub centres: Vec<usize>,
    /// Intersection height of neighbouring basis functions.
    pub intersection: f64,
    /// `A_0 = initial_a · I` (Eq. 6.17).
    pub initial_a: f64,
    /// What `θ` is drawn towards where data are few: `zero` (the thesis, §6.4.1: `b_0 = 0`,
    /// an optimistic value function) or `reward` (`b_0 = A_0 θ_0` with `θ_0` the value of
    /// staying at each centre, `ρ(c, 0) / (1 − γ)` — §6.5's "value function initialised
    /// using knowledge of the reward function"; not in the thesis). Measured on the
    /// pendulum (VGBP-LSTD, 20 runs × 200 trials, seed 1): `reward` never learns the
    /// swing-up (−3630 after 200 trials; `docs/results/pendulum.md`).
    #[serde(default, skip_serializing_if = "LstdPrior::is_zero")]
    pub prior: LstdPrior,
}

plant::choice! {
    /// The prior of an LSTD critic ([`LstdConfig::prior`]).
    #[derive(Debug, Default, PartialEq, Eq)]
    pub enum LstdPrior {
        /// `b_0 = 0`: `θ` is drawn towards 0 (§6.4.1).
        #[default]
        Zero => "zero",
        /// `b_0 = A_0 θ_0`, `θ_0 = ρ(c, 0) / (1 − γ)` at each basis function's centre `c`.
        Reward => "reward",
    }
}

impl LstdPrior {
    fn is_zero(&self) -> bool {
        *self == LstdPrior::Zero
    }
}

/// Where a component sits in the configuration: what its validation needs to know.
pub(crate) struct Slot<'a> {
    /// Its section, `actor`, `critic` or `model`.
    pub section: &'a str,
    /// The approximators allowed there.
    pub kinds: &'a [ApproxKind],
    /// Its input dimension.
    pub dim: usize,
    /// What each input is, for messages ("state component").
    pub what: &'a str,
    /// The configuration's algorithm and approximator, for messages.
    pub algo: Algo,
    /// See `algo`.
    pub approx: ApproxKind,
}

impl Slot<'_> {
    fn key(&self, k: &str) -> String {
        format!("{}.{k}", self.section)
    }
}

impl Component {
    /// The learning rate (0 for LSTD, which has none).
    pub fn alpha(&self) -> f64 {
        match self {
            Component::Llr(c) => c.alpha,
            Component::Rbf(c) => c.alpha,
            Component::Tiles(c) => c.alpha,
            Component::Lstd(_) => 0.0,
        }
    }

    /// The learning rate with its schedule (constant for LSTD's 0).
    pub fn step_size(&self) -> StepSize {
        match self {
            Component::Llr(c) => c.step_size(),
            Component::Rbf(c) => c.step_size(),
            Component::Tiles(c) => c.step_size(),
            Component::Lstd(_) => StepSize::from(0.0),
        }
    }

    fn kind(&self) -> ApproxKind {
        match self {
            Component::Llr(_) => ApproxKind::Llr,
            Component::Rbf(_) => ApproxKind::Rbf,
            Component::Tiles(_) => ApproxKind::Tiles,
            Component::Lstd(_) => ApproxKind::Lstd,
        }
    }

    /// The error for a component of a kind not allowed in `at`.
    pub(crate) fn misplaced(&self, at: &Slot) -> ConfigError {
        let names: Vec<&str> = at.kinds.iter().map(|k| k.as_str()).collect();
        ConfigError::new(
            at.section,
            format!(
                "holds {} parameters; {} expects {} parameters here (approx = \"{}\")",
                self.kind(),
                at.algo,
                names.join(" or "),
                at.approx
            ),
        )
    }

    /// Checks that the component is of a kind allowed in `at` and every value against
    /// its allowed range and the input dimension.
    pub(crate) fn validate(&self, at: &Slot) -> Result<(), ConfigError> {
        if !at.kinds.contains(&self.kind()) {
            return Err(self.misplaced(at));
        }
        check_float(&at.key("alpha"), self.alpha(), 0.0, 100.0, false)?;
        let (trials, power) = match self {
            Component::Llr(c) => (c.decay_trials, c.decay_power),
            Component::Rbf(c) => (c.decay_trials, c.decay_power),
            Component::Tiles(c) => (c.decay_trials, c.decay_power),
            Component::Lstd(_) => (None, None),
        };
        check_schedule(at, trials, power)?;
        match self {
            Component::Llr(l) => l.validate(at),
            Component::Rbf(r) => {
                check_grid(at, &r.centres, 2_000_000, |_| String::new())?;
                check_float(&at.key("intersection"), r.intersection, 0.0, 1.0, true)
            }
            Component::Lstd(l) => {
                check_grid(at, &l.centres, 5000, |n| {
                    format!("LSTD solves a dense {n}×{n} system, ")
                })?;
                check_float(&at.key("intersection"), l.intersection, 0.0, 1.0, true)?;
                check_float(&at.key("initial_a"), l.initial_a, 0.0, 1e12, true)
            }
            Component::Tiles(t) => {
                check_int(&at.key("tilings"), t.tilings as u64, 1, 1024)?;
                check_len(&at.key("tiles"), t.tiles.len(), at.dim, at.what)?;
                for (i, c) in t.tiles.iter().enumerate() {
                    check_int(&format!("{}.tiles[{i}]", at.section), *c as u64, 1, 1000)?;
                }
                Ok(())
            }
        }
    }
}

impl LlrConfig {
    fn validate(&self, at: &Slot) -> Result<(), ConfigError> {
        check_int(&at.key("memory"), self.memory as u64, 1, 1_000_000)?;
        let kmax = (crate::approx::kdtree::MAX_K as u64).min(self.memory as u64);
        check_int(&at.key("neighbours"), self.neighbours as u64, 1, kmax)?;
        check_len(&at.key("weights"), self.weights.len(), at.dim, at.what)?;
        for (i, w) in self.weights.iter().enumerate() {
            check_float(&format!("{}.weights[{i}]", at.section), *w, 0.0, 1e6, true)?;
        }
        check_float(
            &at.key("redundancy_radius"),
            self.redundancy_radius,
            0.0,
            1e6,
            false,
        )
    }
}

/// The learning rate `alpha` with the schedule `decay_trials`, `decay_power` say, of each
/// approximator that has a learning rate.
macro_rules! step_size_of {
    ($($config:ty),*) => {$(
        impl $config {
            /// The learning rate with its schedule ([`crate::step_size`]).
            pub fn step_size(&self) -> StepSize {
                let decay = self.decay_trials.map(|trials| Decay {
                    trials,
                    power: self.decay_power.unwrap_or(1.0),
                });
                StepSize::new(self.alpha, decay)
            }
        }
    )*};
}
step_size_of!(LlrConfig, RbfConfig, TilesConfig);

/// Checks a learning-rate schedule's keys: `τ` positive and finite, `p` in `(1/2, 1]`
/// (Eq. 2.21–2.22) and only with `τ`, and no schedule for a process model, which has no
/// learning rate.
fn check_schedule(at: &Slot, trials: Option<f64>, power: Option<f64>) -> Result<(), ConfigError> {
    match (trials, power) {
        (None, None) => return Ok(()),
        (None, Some(_)) => {
            return Err(ConfigError::new(
                &at.key("decay_power"),
                format!(
                    "is the power of a decay: give `{}` too",
                    at.key("decay_trials")
                ),
            ));
        }
        _ if at.section == "model" => {
            return Err(ConfigError::new(
                &at.key("decay_trials"),
                "a process model has no learning rate to decay; a schedule is for [actor] and [critic]",
            ));
        }
        (Some(trials), _) => check_float(&at.key("decay_trials"), trials, 0.0, 1e9, true)?,
    }
    match power {
        Some(p) if !(p > 0.5 && p <= 1.0) => Err(ConfigError::new(
            &at.key("decay_power"),
            format!(
                "{p} is out of range: must be a finite number in (0.5, 1] (Σα_k = ∞ needs p ≤ 1, Σα_k² < ∞ needs p > 1/2, Eq. 2.21–2.22)"
            ),
        )),
        _ => Ok(()),
    }
}

/// Checks an RBF grid's `centres`: one entry per input, 1 to 1000 each, at most `max`
/// basis functions in all (`why` of the count says why the limit).
fn check_grid(
    at: &Slot,
    centres: &[usize],
    max: u64,
    why: fn(u64) -> String,
) -> Result<(), ConfigError> {
    check_len(&at.key("centres"), centres.len(), at.dim, at.what)?;
    for (i, c) in centres.iter().enumerate() {
        check_int(&format!("{}.centres[{i}]", at.section), *c as u64, 1, 1000)?;
    }
    let total: u64 = centres.iter().map(|&c| c as u64).product();
    if total > max {
        return Err(ConfigError::new(
            &at.key("centres"),
            format!(
                "{total} basis functions in all: {}at most {max}",
                why(total)
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn critic(dim: usize) -> Slot<'static> {
        Slot {
            section: "critic",
            kinds: &[ApproxKind::Lstd, ApproxKind::Llr],
            dim,
            what: "state component",
            algo: Algo::Vgbp,
            approx: ApproxKind::Lstd,
        }
    }

    /// An LLR memory of 10 samples on two inputs, `neighbours` of them read.
    fn memory(neighbours: usize, decay_trials: Option<f64>) -> LlrConfig {
        LlrConfig {
            alpha: 0.1,
            memory: 10,
            neighbours,
            weights: vec![1.0, 0.1],
            eviction: EvictionRule::Oldest,
            redundancy_radius: 0.0,
            clip_to_neighbours: false,
            decay_trials,
            decay_power: None,
        }
    }

    #[test]
    fn grids_and_memories_are_checked_against_their_limits() {
        let lstd = |centres| {
            Component::Lstd(LstdConfig {
                centres,
                intersection: 0.5,
                initial_a: 0.5,
                prior: LstdPrior::Zero,
            })
        };
        lstd(vec![20, 20]).validate(&critic(2)).unwrap();
        let e = lstd(vec![80, 80]).validate(&critic(2)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "`critic.centres`: 6400 basis functions in all: LSTD solves a dense 6400×6400 system, at most 5000"
        );
        let e = lstd(vec![20]).validate(&critic(2)).unwrap_err();
        assert_eq!(
            e.message,
            "has 1 entries; must have 2, one per state component"
        );
        let e = Component::Llr(memory(11, None))
            .validate(&critic(2))
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "`critic.neighbours`: 11 is out of range: must be an integer in 1..=10"
        );
        let rbf = Component::Rbf(RbfConfig {
            alpha: 0.1,
            centres: vec![9, 9],
            intersection: 0.5,
            decay_trials: None,
            decay_power: None,
        });
        let e = rbf.validate(&critic(2)).unwrap_err();
        assert_eq!(e.key, "critic");
        assert!(
            e.message
                .starts_with("holds rbf parameters; vgbp expects lstd or llr")
        );
    }

    /// A process model only stores (or fits without a rate of its own to decay): a
    /// schedule there is refused, also when built in code rather than read from a file.
    #[test]
    fn a_process_model_takes_no_schedule() {
        let llr = memory(3, Some(100.0));
        let model = Slot {
            section: "model",
            kinds: &[ApproxKind::Llr],
            ..critic(2)
        };
        let e = Component::Llr(llr.clone()).validate(&model).unwrap_err();
        assert_eq!(e.key, "model.decay_trials");
        Component::Llr(llr).validate(&critic(2)).unwrap();
    }
}
