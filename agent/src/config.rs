//! Experiment configuration: the fully resolved set of parameters of one experiment, its
//! TOML form, and validation with messages that name the key and the allowed range.
//!
//! A configuration is resolved in layers: the preset for (system, algorithm,
//! approximator) — the thesis's tuned values, see [`crate::preset`] — then a user's TOML
//! file, then command-line overrides. A key in the user's file that the preset does not
//! have is an error naming the key and the keys that are allowed there.

use std::fmt;
use std::path::{Path, PathBuf};

use plant::{SystemName, Task};
use serde::{Deserialize, Serialize};

/// The learning algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Algo {
    /// Standard actor-critic (Algorithm 1).
    Sac,
    /// Model learning actor-critic (Algorithm 2).
    Mlac,
    /// Reference model actor-critic (Algorithm 3).
    Rmac,
    /// Value-gradient based policy (Algorithm 7), critic-only.
    Vgbp,
    /// SARSA(λ) with ε-greedy discrete actions (§6.2), critic-only.
    Sarsa,
}

impl Algo {
    /// The approximators this algorithm can use.
    pub fn approximators(self) -> &'static [ApproxKind] {
        use ApproxKind::*;
        match self {
            Algo::Sac => &[Llr, Rbf, Tiles],
            Algo::Mlac | Algo::Rmac => &[Llr, Rbf],
            Algo::Vgbp => &[Lstd, Rbf, Llr],
            Algo::Sarsa => &[Rbf],
        }
    }

    /// Every algorithm, for help texts and validation messages.
    pub const ALL: [Algo; 5] = [Algo::Sac, Algo::Mlac, Algo::Rmac, Algo::Vgbp, Algo::Sarsa];

    /// Whether the algorithm has an actor (or reference model) component.
    pub fn has_actor(self) -> bool {
        matches!(self, Algo::Sac | Algo::Mlac | Algo::Rmac)
    }

    /// Whether the algorithm learns a process model.
    pub fn has_model(self) -> bool {
        matches!(self, Algo::Mlac | Algo::Rmac | Algo::Vgbp)
    }
}

/// The function approximator used by every component.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ApproxKind {
    /// Local linear regression (§3.5.2).
    Llr,
    /// Normalised radial basis functions (§3.5.1).
    Rbf,
    /// Tile coding (§3.5.3), SAC only.
    Tiles,
    /// LSTD(λ) on normalised RBFs (Eq. 6.16–6.19), a VGBP critic; the process model is
    /// LLR.
    Lstd,
}

impl ApproxKind {
    /// Every approximator, for help texts and validation messages.
    pub const ALL: [ApproxKind; 4] = [
        ApproxKind::Llr,
        ApproxKind::Rbf,
        ApproxKind::Tiles,
        ApproxKind::Lstd,
    ];
}

/// The horizon of the cost function ([`crate::horizon`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HorizonKind {
    /// Discounted rewards without end (Chapters 3, 5, 6).
    #[default]
    Infinite,
    /// A trial is the horizon: its samples' rewards plus the terminal reward `τ_N`, actor
    /// and critic time-varying (Chapter 4; SAC, MLAC and RMAC, Algorithms 4–6).
    Finite,
}

impl HorizonKind {
    /// Both horizons, for help texts and validation messages.
    pub const ALL: [HorizonKind; 2] = [HorizonKind::Infinite, HorizonKind::Finite];

    /// The runtime horizon of `task`: a finite horizon is one trial, `N` samples.
    pub fn of(self, task: &Task) -> crate::horizon::Horizon {
        match self {
            HorizonKind::Infinite => crate::horizon::Horizon::Infinite,
            HorizonKind::Finite => crate::horizon::Horizon::Finite {
                steps: task.steps_per_trial(),
            },
        }
    }
}

/// What the plant's sensor measures ([`plant::sensor`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SensorKind {
    /// The full state (the thesis's simulations).
    #[default]
    Full,
    /// Encoder angles only (quantised, optionally noisy); velocities are estimated.
    Angle,
}

impl SensorKind {
    /// Both sensors, for help texts and validation messages.
    pub const ALL: [SensorKind; 2] = [SensorKind::Full, SensorKind::Angle];
}

/// The state observer (`observer` crate).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObserverKind {
    /// `x̂ = y` (full-state sensor only).
    #[default]
    PassThrough,
    /// Backward-difference velocities, low-pass filtered.
    FiniteDifference,
    /// Model prediction `x̂_{k+1|k} = f̂(x̂_k, u_k)` corrected by the measured angle.
    Predictive,
}

impl ObserverKind {
    /// Every observer, for help texts and validation messages.
    pub const ALL: [ObserverKind; 3] = [
        ObserverKind::PassThrough,
        ObserverKind::FiniteDifference,
        ObserverKind::Predictive,
    ];
}

/// The predictive observer's process model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObserverModel {
    /// LLR learned online from the observer's own estimates (§3.5.2).
    #[default]
    Learned,
    /// The plant's dynamics integrated with RK4 (the simulator's own model).
    Known,
}

impl ObserverModel {
    /// Both models, for help texts and validation messages.
    pub const ALL: [ObserverModel; 2] = [ObserverModel::Learned, ObserverModel::Known];
}

/// When the agent acts, relative to the sample it acts on (thesis §6.4.1; DESIGN.md "The
/// observer and the latency budget"; [`observer::timing`](../../observer/timing/index.html)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObserverMode {
    /// The agent acts on `x̂_k`; its action takes effect within the interval
    /// `[t_k, t_{k+1})`, as soon as it is computed and transported (`run.delay_ms` /
    /// `run.delay_from` after `t_k`; 0: at `t_k`, the thesis's simulations).
    #[default]
    Direct,
    /// The agent acts on the one-step prediction `x̂_{k+1|k} = f̂(x̂_k, u_k)`; its action
    /// is applied at `t_{k+1}`, for the whole next interval (a one-sample action
    /// pipeline, §6.4.1's physical setup): a delay below `Ts` does not reach the plant.
    /// Needs `observer = "predictive"` (the model) and an infinite horizon.
    Predictive,
}

impl ObserverMode {
    /// Both modes, for help texts and validation messages.
    pub const ALL: [ObserverMode; 2] = [ObserverMode::Direct, ObserverMode::Predictive];
}

/// Sensor and state observer (`[observer]`); the defaults — full state, pass-through —
/// are the thesis's simulations, and a configuration with them is written without this
/// section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverConfig {
    /// What the plant measures.
    pub sensor: SensorKind,
    /// Encoder counts per revolution (angle sensor).
    pub counts_per_rev: u32,
    /// Standard deviation of Gaussian angle noise before quantisation \[rad\].
    pub noise_std: f64,
    /// The observer.
    pub observer: ObserverKind,
    /// The predictive observer's process model.
    pub model: ObserverModel,
    /// Finite difference: low-pass coefficient `a` in [0, 1) (0: raw difference).
    pub filter: f64,
    /// Predictive: velocity gain `l` on the angle innovation, in [0, 2).
    pub gain: f64,
    /// Timing: the agent acts on `x̂_k` (direct) or on `x̂_{k+1|k}` with its action applied
    /// at the next sample instant (predictive).
    #[serde(default)]
    pub mode: ObserverMode,
}

impl Default for ObserverConfig {
    fn default() -> Self {
        Self {
            sensor: SensorKind::Full,
            counts_per_rev: 4096,
            noise_std: 0.0,
            observer: ObserverKind::PassThrough,
            model: ObserverModel::Learned,
            filter: 0.0,
            gain: 1.0,
            mode: ObserverMode::Direct,
        }
    }
}

impl ObserverConfig {
    /// Whether this is the default (full state, pass-through, default parameters).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// A value chosen by name, on the command line and in configuration files.
pub trait Choice: Copy + 'static {
    /// Every value, in the order messages list them.
    fn all() -> &'static [Self];
    /// Its spelling.
    fn spelling(self) -> &'static str;
    /// The spellings, comma-separated.
    fn spellings() -> String {
        let names: Vec<&str> = Self::all().iter().map(|v| v.spelling()).collect();
        names.join(", ")
    }
    /// The value spelled `s`; the error lists the spellings.
    fn parse(s: &str) -> Result<Self, String> {
        Self::all()
            .iter()
            .copied()
            .find(|v| v.spelling() == s)
            .ok_or_else(|| format!("one of: {}", Self::spellings()))
    }
}

impl Choice for SystemName {
    fn all() -> &'static [Self] {
        &SystemName::ALL
    }
    fn spelling(self) -> &'static str {
        self.as_str()
    }
}

macro_rules! names {
    ($t:ty, $($v:ident => $s:literal),*) => {
        impl $t {
            /// The command-line / config spelling.
            pub fn as_str(self) -> &'static str { match self { $(Self::$v => $s),* } }
        }
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result { f.write_str(self.as_str()) }
        }
        impl Choice for $t {
            fn all() -> &'static [Self] { &Self::ALL }
            fn spelling(self) -> &'static str { self.as_str() }
        }
    };
}
names!(Algo, Sac => "sac", Mlac => "mlac", Rmac => "rmac", Vgbp => "vgbp", Sarsa => "sarsa");
names!(ApproxKind, Llr => "llr", Rbf => "rbf", Tiles => "tiles", Lstd => "lstd");
names!(HorizonKind, Infinite => "infinite", Finite => "finite");
names!(SensorKind, Full => "full", Angle => "angle");
names!(ObserverKind, PassThrough => "pass-through", FiniteDifference => "finite-difference", Predictive => "predictive");
names!(ObserverModel, Learned => "learned", Known => "known");
names!(ObserverMode, Direct => "direct", Predictive => "predictive");
names!(LstdPrior, Zero => "zero", Reward => "reward");

/// A complete experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentConfig {
    /// The system learned on.
    pub system: SystemName,
    /// The algorithm.
    pub algo: Algo,
    /// The approximator of every component.
    pub approx: ApproxKind,
    /// Infinite (discounted) or finite horizon (Chapter 4); absent: infinite.
    #[serde(default)]
    pub horizon: HorizonKind,
    /// Trials, runs, seed, evaluation.
    pub run: RunConfig,
    /// Parameters of Template 2.1 and the exploration.
    pub learning: LearningConfig,
    /// The actor (SAC, MLAC) or reference model (RMAC); none for VGBP and SARSA. With a
    /// finite horizon its input (like the critic's) is the state followed by time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actor: Option<Component>,
    /// The critic `V(x)` (SARSA: `Q(x, ·)`, one output per action).
    pub critic: Component,
    /// The process model (MLAC, RMAC, VGBP).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<Component>,
    /// VGBP's action selection.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vgbp: Option<VgbpConfig>,
    /// SARSA's action set and ε-greedy schedule.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sarsa: Option<SarsaConfig>,
    /// Sensor and state observer; absent: full state, pass-through.
    #[serde(default, skip_serializing_if = "ObserverConfig::is_default")]
    pub observer: ObserverConfig,
}

/// VGBP's action selection (§6.3, [`crate::vgbp`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VgbpConfig {
    /// Re-evaluations of the value gradient at the predicted next state (0: Eq. 6.21 as
    /// the thesis has it).
    pub lookahead: u32,
    /// Action levels per component at which the right-hand side of Eq. 6.6 is searched
    /// (with the model affine in `u`, Eq. 6.9, and `V` not linearised); 0: no search,
    /// the action of Eq. 6.21 and the look-ahead.
    #[serde(default)]
    pub grid: u32,
    /// Fit Eq. 6.21's process model at `(x, u = 0)` rather than at the state `x`
    /// (Algorithm 7 line 12, the default `false`).
    #[serde(default)]
    pub fit_at_zero_action: bool,
}

/// SARSA's discrete actions and exploration (§6.4.1, Eq. 6.22).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SarsaConfig {
    /// The action values (per action dimension; the set is their product).
    pub actions: Vec<f64>,
    /// ε decays by this factor per trial.
    pub epsilon_decay: f64,
    /// ε never falls below this.
    pub epsilon_min: f64,
}

/// How many experiments, of how many trials, from which seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// Trials per run.
    pub trials: u32,
    /// Independent runs (learning experiments).
    pub runs: u32,
    /// Seed from which every random stream of every run is derived.
    pub seed: u64,
    /// A greedy evaluation trial after every this many trials (0, or more than `trials`:
    /// none).
    pub eval_every: u32,
    /// Sample-to-actuation delay \[ms\], applied deterministically in lockstep: over each
    /// sample period the previous action stays in effect for this long, then the new one
    /// (0: the thesis's simulations, the action applies at the sample instant).
    #[serde(default)]
    pub delay_ms: f64,
    /// A recorded distribution of sample-to-actuation delays: a CSV file, one delay per
    /// row in column `delay_column`; each sample's delay is drawn from it (uniformly, from
    /// the run seed's stream [`plant::delay::STREAM`]) and applied as `delay_ms` is.
    /// Empty: none. Exclusive with `delay_ms`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub delay_from: String,
    /// The column of `delay_from` holding the delays; its unit is its name's suffix
    /// (`_s`, `_ms`, `_us`, `_ns`; `sample_to_actuation` of `rig latency`'s latency.csv is
    /// ns). Empty: `delay_ms`, else `sample_to_actuation`, whichever the file has.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub delay_column: String,
}

/// Learning parameters shared by the components.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LearningConfig {
    /// Discount `γ`, in (0, 1); a finite horizon also allows 1 (no discount, as in
    /// Algorithms 4–6).
    pub gamma: f64,
    /// Eligibility-trace decay `λ` of the critic.
    pub lambda: f64,
    /// Exploration standard deviation `σ`.
    pub sigma: f64,
    /// Explore on every this-many-th step (1: every step, §3.6; 3: §6.4.1).
    pub explore_every: u32,
    /// MLAC: `∇_u f̂` is taken as zero within this distance of an action bound (§3.5.1).
    pub saturation_margin: f64,
    /// The actor's outputs are saturated to the action bounds and its updates stop there
    /// (§3.5.1, the thesis's second remedy for input saturation; default). `false`
    /// ignores the saturation in the actor — the plant still saturates what it applies —
    /// for §3.7's claim that ignoring it does not produce a well-performing policy.
    #[serde(default = "yes")]
    pub bounded_actor: bool,
}

fn yes() -> bool {
    true
}

/// One approximator's parameters; which kind is given by [`ExperimentConfig::approx`].
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
    /// Memory management: "oldest" or "redundant".
    pub eviction: String,
    /// With "redundant": a new sample replaces a stored one closer than this (scaled).
    pub redundancy_radius: f64,
    /// Limit predictions to the range of the neighbours' outputs (no extrapolation).
    pub clip_to_neighbours: bool,
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
    /// swing-up (−3630 after 200 trials; README, Chapter 6 results).
    #[serde(default, skip_serializing_if = "LstdPrior::is_zero")]
    pub prior: LstdPrior,
}

/// The prior of an LSTD critic ([`LstdConfig::prior`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LstdPrior {
    /// `b_0 = 0`: `θ` is drawn towards 0 (§6.4.1).
    #[default]
    Zero,
    /// `b_0 = A_0 θ_0`, `θ_0 = ρ(c, 0) / (1 − γ)` at each basis function's centre `c`.
    Reward,
}

impl LstdPrior {
    /// Both priors, for validation messages.
    pub const ALL: [LstdPrior; 2] = [LstdPrior::Zero, LstdPrior::Reward];

    fn is_zero(&self) -> bool {
        *self == LstdPrior::Zero
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

    fn kind(&self) -> ApproxKind {
        match self {
            Component::Llr(_) => ApproxKind::Llr,
            Component::Rbf(_) => ApproxKind::Rbf,
            Component::Tiles(_) => ApproxKind::Tiles,
            Component::Lstd(_) => ApproxKind::Lstd,
        }
    }
}

/// A configuration error: where, which key, what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfigError {
    /// The file the value came from, if any.
    pub file: Option<PathBuf>,
    /// Dotted key, e.g. `critic.neighbours`.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.file {
            Some(p) => write!(f, "{}: `{}`: {}", p.display(), self.key, self.message),
            None => write!(f, "`{}`: {}", self.key, self.message),
        }
    }
}

impl std::error::Error for ConfigError {}

fn err(key: &str, message: impl Into<String>) -> ConfigError {
    ConfigError {
        file: None,
        key: key.to_string(),
        message: message.into(),
    }
}

/// The error for a finite horizon with an algorithm that has none (VGBP, SARSA).
pub(crate) fn finite_horizon_unsupported(algo: Algo) -> ConfigError {
    err(
        "horizon",
        format!(
            "\"finite\" (Chapter 4) is for sac, mlac and rmac; {algo} needs horizon = \"infinite\""
        ),
    )
}

/// Checks `lo ≤ v ≤ hi` (and finiteness) for a float key.
fn check_f(key: &str, v: f64, lo: f64, hi: f64, open: bool) -> Result<(), ConfigError> {
    let ok = v.is_finite()
        && if open {
            v > lo && v < hi
        } else {
            v >= lo && v <= hi
        };
    if ok {
        Ok(())
    } else {
        let range = if open {
            format!("({lo}, {hi})")
        } else {
            format!("[{lo}, {hi}]")
        };
        Err(err(
            key,
            format!("{v} is out of range: must be a finite number in {range}"),
        ))
    }
}

fn check_i(key: &str, v: u64, lo: u64, hi: u64) -> Result<(), ConfigError> {
    if v >= lo && v <= hi {
        Ok(())
    } else {
        Err(err(
            key,
            format!("{v} is out of range: must be an integer in {lo}..={hi}"),
        ))
    }
}

fn check_len(key: &str, len: usize, want: usize, what: &str) -> Result<(), ConfigError> {
    if len == want {
        Ok(())
    } else {
        Err(err(
            key,
            format!("has {len} entries; must have {want}, one per {what}"),
        ))
    }
}

impl ExperimentConfig {
    /// The sample-to-actuation delays of a run with seed `run_seed`: `run.delay_from`'s
    /// recorded distribution, else the fixed `run.delay_ms` ([`plant::delay::Delays`]).
    /// The error names the file, column, row and allowed range.
    pub fn delays_for_run(
        &self,
        task: &Task,
        run_seed: u64,
    ) -> Result<plant::delay::Delays, String> {
        if self.run.delay_from.is_empty() {
            return Ok(plant::delay::Delays::fixed(self.run.delay_ms * 1e-3));
        }
        Ok(plant::delay::Delays::recorded(self.delays(task)?, run_seed))
    }

    /// `run.delay_from`'s delays \[s\].
    fn delays(&self, task: &Task) -> Result<std::sync::Arc<Vec<f64>>, String> {
        let column = (!self.run.delay_column.is_empty()).then_some(self.run.delay_column.as_str());
        plant::delay::read_csv(Path::new(&self.run.delay_from), column, task.ts)
            .map(std::sync::Arc::new)
    }

    /// Checks every value against its allowed range and the system's dimensions.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let task = Task::new(self.system);
        let (n, m) = (task.state_dim(), task.action_dim());
        check_i("run.trials", self.run.trials.into(), 1, 10_000_000)?;
        check_i("run.runs", self.run.runs.into(), 1, 100_000)?;
        check_i("run.eval_every", self.run.eval_every.into(), 0, 10_000_000)?;
        if self.run.delay_ms != 0.0 {
            // Less than one sample period.
            check_f("run.delay_ms", self.run.delay_ms, 0.0, task.ts * 1e3, true)?;
        }
        if !self.run.delay_from.is_empty() {
            if self.run.delay_ms != 0.0 {
                return Err(err(
                    "run.delay_from",
                    "is exclusive with run.delay_ms (--delay-from, --delay-ms): give one of them",
                ));
            }
            self.delays(&task).map_err(|e| err("run.delay_from", e))?;
        } else if !self.run.delay_column.is_empty() {
            return Err(err(
                "run.delay_column",
                "needs run.delay_from (--delay-from), the file it is a column of",
            ));
        }
        let o = &self.observer;
        check_i(
            "observer.counts_per_rev",
            o.counts_per_rev.into(),
            4,
            1 << 30,
        )?;
        check_f("observer.noise_std", o.noise_std, 0.0, 1.0, false)?;
        if !(o.filter.is_finite() && (0.0..1.0).contains(&o.filter)) {
            return Err(err(
                "observer.filter",
                format!("{} is out of range: must be a number in [0, 1)", o.filter),
            ));
        }
        if !(o.gain.is_finite() && (0.0..2.0).contains(&o.gain)) {
            return Err(err(
                "observer.gain",
                format!("{} is out of range: must be a number in [0, 2)", o.gain),
            ));
        }
        if o.mode == ObserverMode::Predictive {
            if o.observer != ObserverKind::Predictive {
                return Err(err(
                    "observer.mode",
                    format!(
                        "\"predictive\" needs observer = \"predictive\" (its process model predicts x̂_{{k+1|k}}), not \"{}\"",
                        o.observer
                    ),
                ));
            }
            if self.horizon == HorizonKind::Finite {
                return Err(err(
                    "observer.mode",
                    "\"predictive\" needs an infinite horizon (a finite-horizon agent's time index would be one sample off the plant's)",
                ));
            }
        }
        if o.sensor == SensorKind::Angle && o.observer == ObserverKind::PassThrough {
            return Err(err(
                "observer.observer",
                "\"pass-through\" needs sensor = \"full\"; an angle sensor needs \"finite-difference\" or \"predictive\"",
            ));
        }
        let l = &self.learning;
        let finite = self.horizon == HorizonKind::Finite;
        if finite && !self.algo.has_actor() {
            return Err(finite_horizon_unsupported(self.algo));
        }
        if !finite {
            check_f("learning.gamma", l.gamma, 0.0, 1.0, true)?;
        } else if !(l.gamma > 0.0 && l.gamma <= 1.0) {
            return Err(err(
                "learning.gamma",
                format!(
                    "{} is out of range: must be a number in (0, 1] (1: no discount, Algorithms 4–6)",
                    l.gamma
                ),
            ));
        }
        check_f("learning.lambda", l.lambda, 0.0, 1.0, false)?;
        check_f("learning.sigma", l.sigma, 0.0, 1e3, false)?;
        check_i(
            "learning.explore_every",
            l.explore_every.into(),
            1,
            1_000_000,
        )?;
        check_f(
            "learning.saturation_margin",
            l.saturation_margin,
            0.0,
            1e3,
            false,
        )?;
        let allowed = self.algo.approximators();
        if !allowed.contains(&self.approx) {
            let names: Vec<&str> = allowed.iter().map(|a| a.as_str()).collect();
            return Err(err(
                "approx",
                format!(
                    "{} works with {}, not {}{}",
                    self.algo,
                    names.join(", "),
                    self.approx,
                    if self.approx == ApproxKind::Tiles {
                        " (tile coding has no gradient, §3.5)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let own = [self.approx];
        // Actor, reference model and critic read the state, and time if finite (Eq. 4.6).
        let (d, input) = if finite {
            (n + 1, "state component and time")
        } else {
            (n, "state component")
        };
        match (&self.actor, self.algo.has_actor()) {
            (None, true) => {
                return Err(err(
                    "actor",
                    format!("{} has an actor: an [actor] section is required", self.algo),
                ));
            }
            (Some(_), false) => {
                return Err(err(
                    "actor",
                    format!("{} has no actor: remove the [actor] section", self.algo),
                ));
            }
            (Some(c), true) => self.check_component("actor", c, &own, d, input)?,
            (None, false) => {}
        }
        self.check_component("critic", &self.critic, &own, d, input)?;
        // VGBP's process model is LLR whatever its critic (§6.3.1); the others learn every
        // component with the same approximator.
        let model_kinds: &[ApproxKind] = if self.algo == Algo::Vgbp {
            &[ApproxKind::Llr, ApproxKind::Rbf]
        } else {
            &own
        };
        match (&self.model, self.algo.has_model()) {
            (None, true) => {
                return Err(err(
                    "model",
                    format!(
                        "{} learns a process model: a [model] section is required",
                        self.algo
                    ),
                ));
            }
            (Some(_), false) => {
                return Err(err(
                    "model",
                    format!(
                        "{} learns no process model: remove the [model] section",
                        self.algo
                    ),
                ));
            }
            (Some(c), true) => {
                self.check_component("model", c, model_kinds, n + m, "state and action component")?
            }
            (None, false) => {}
        }
        match (&self.vgbp, self.algo) {
            (None, Algo::Vgbp) => return Err(err("vgbp", "vgbp needs a [vgbp] section")),
            (Some(_), a) if a != Algo::Vgbp => {
                return Err(err(
                    "vgbp",
                    format!("{a} is not vgbp: remove the [vgbp] section"),
                ));
            }
            (Some(v), _) => {
                check_i("vgbp.lookahead", v.lookahead.into(), 0, 100)?;
                if v.grid == 1 || v.grid > 1001 {
                    return Err(err(
                        "vgbp.grid",
                        format!(
                            "{} is out of range: must be 0 (no search) or an integer in 2..=1001",
                            v.grid
                        ),
                    ));
                }
            }
            (None, _) => {}
        }
        if self.algo == Algo::Vgbp && task.reward.p.iter().any(|&p| p <= 0.0) {
            return Err(err(
                "algo",
                format!(
                    "vgbp needs a reward strictly concave in the action (P > 0); {} has P = {:?}",
                    self.system, task.reward.p
                ),
            ));
        }
        match (&self.sarsa, self.algo) {
            (None, Algo::Sarsa) => Err(err("sarsa", "sarsa needs a [sarsa] section")),
            (Some(_), a) if a != Algo::Sarsa => Err(err(
                "sarsa",
                format!("{a} is not sarsa: remove the [sarsa] section"),
            )),
            (Some(c), _) => {
                let count = c.actions.len() as u64;
                check_i("sarsa.actions", count, 1, 64)?;
                if count.pow(m as u32) > 4096 {
                    return Err(err(
                        "sarsa.actions",
                        format!("{count}^{m} discrete actions: at most 4096"),
                    ));
                }
                for (i, &a) in c.actions.iter().enumerate() {
                    let (lo, hi) = (
                        task.action_low
                            .iter()
                            .copied()
                            .fold(f64::INFINITY, f64::min),
                        task.action_high
                            .iter()
                            .copied()
                            .fold(f64::NEG_INFINITY, f64::max),
                    );
                    check_f(&format!("sarsa.actions[{i}]"), a, lo, hi, false)?;
                }
                check_f("sarsa.epsilon_decay", c.epsilon_decay, 0.0, 1.0, false)?;
                check_f("sarsa.epsilon_min", c.epsilon_min, 0.0, 1.0, false)
            }
            (None, _) => Ok(()),
        }
    }

    fn check_component(
        &self,
        section: &str,
        c: &Component,
        kinds: &[ApproxKind],
        dim: usize,
        what: &str,
    ) -> Result<(), ConfigError> {
        let key = |k: &str| format!("{section}.{k}");
        if !kinds.contains(&c.kind()) {
            let names: Vec<&str> = kinds.iter().map(|k| k.as_str()).collect();
            return Err(err(
                section,
                format!(
                    "holds {} parameters; {} expects {} parameters here (approx = \"{}\")",
                    c.kind(),
                    self.algo,
                    names.join(" or "),
                    self.approx
                ),
            ));
        }
        check_f(&key("alpha"), c.alpha(), 0.0, 100.0, false)?;
        match c {
            Component::Llr(l) => {
                check_i(&key("memory"), l.memory as u64, 1, 1_000_000)?;
                let kmax = (crate::approx::kdtree::MAX_K as u64).min(l.memory as u64);
                check_i(&key("neighbours"), l.neighbours as u64, 1, kmax)?;
                check_len(&key("weights"), l.weights.len(), dim, what)?;
                for (i, w) in l.weights.iter().enumerate() {
                    check_f(&format!("{section}.weights[{i}]"), *w, 0.0, 1e6, true)?;
                }
                if l.eviction != "oldest" && l.eviction != "redundant" {
                    return Err(err(
                        &key("eviction"),
                        format!(
                            "\"{}\" is not a memory-management rule: use \"oldest\" or \"redundant\"",
                            l.eviction
                        ),
                    ));
                }
                check_f(
                    &key("redundancy_radius"),
                    l.redundancy_radius,
                    0.0,
                    1e6,
                    false,
                )?;
            }
            Component::Rbf(r) => {
                check_len(&key("centres"), r.centres.len(), dim, what)?;
                for (i, c) in r.centres.iter().enumerate() {
                    check_i(&format!("{section}.centres[{i}]"), *c as u64, 1, 1000)?;
                }
                let total: u64 = r.centres.iter().map(|&c| c as u64).product();
                if total > 2_000_000 {
                    return Err(err(
                        &key("centres"),
                        format!("{total} basis functions in all: at most 2000000"),
                    ));
                }
                check_f(&key("intersection"), r.intersection, 0.0, 1.0, true)?;
            }
            Component::Lstd(l) => {
                check_len(&key("centres"), l.centres.len(), dim, what)?;
                for (i, c) in l.centres.iter().enumerate() {
                    check_i(&format!("{section}.centres[{i}]"), *c as u64, 1, 1000)?;
                }
                let total: u64 = l.centres.iter().map(|&c| c as u64).product();
                if total > 5000 {
                    return Err(err(
                        &key("centres"),
                        format!(
                            "{total} basis functions in all: LSTD solves a dense {total}×{total} system, at most 5000"
                        ),
                    ));
                }
                check_f(&key("intersection"), l.intersection, 0.0, 1.0, true)?;
                check_f(&key("initial_a"), l.initial_a, 0.0, 1e12, true)?;
            }
            Component::Tiles(t) => {
                check_i(&key("tilings"), t.tilings as u64, 1, 1024)?;
                check_len(&key("tiles"), t.tiles.len(), dim, what)?;
                for (i, c) in t.tiles.iter().enumerate() {
                    check_i(&format!("{section}.tiles[{i}]"), *c as u64, 1, 1000)?;
                }
            }
        }
        Ok(())
    }

    /// The configuration as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a configuration always serialises")
    }
}

/// Command-line choices and overrides, applied over preset and file.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// `--system`.
    pub system: Option<SystemName>,
    /// `--algo`.
    pub algo: Option<Algo>,
    /// `--approx`.
    pub approx: Option<ApproxKind>,
    /// `--horizon`.
    pub horizon: Option<HorizonKind>,
    /// `--trials`.
    pub trials: Option<u32>,
    /// `--runs`.
    pub runs: Option<u32>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--eval-every`.
    pub eval_every: Option<u32>,
    /// `--sensor`.
    pub sensor: Option<SensorKind>,
    /// `--observer`.
    pub observer: Option<ObserverKind>,
    /// `--delay-ms`.
    pub delay_ms: Option<f64>,
    /// `--delay-from`.
    pub delay_from: Option<String>,
    /// `--delay-column`.
    pub delay_column: Option<String>,
    /// `--observer-mode`.
    pub observer_mode: Option<ObserverMode>,
}

/// Resolves preset ← file ← overrides into a validated configuration.
pub fn resolve(
    file: Option<(&Path, &str)>,
    o: &Overrides,
) -> Result<ExperimentConfig, ConfigError> {
    let path = file.map(|(p, _)| p.to_path_buf());
    let with_file = |mut e: ConfigError| {
        e.file = path.clone();
        e
    };
    let user: toml::Table = match file {
        Some((_, text)) => toml::from_str(text)
            .map_err(|e| with_file(err("", format!("not valid TOML: {}", e.message()))))?,
        None => toml::Table::new(),
    };
    let pick = |key: &str| -> Result<Option<String>, ConfigError> {
        match user.get(key) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s.clone())),
            Some(v) => Err(with_file(err(key, format!("{v} must be a string")))),
        }
    };
    let system =
        choose("system", o.system, pick("system")?, SystemName::Pendulum).map_err(with_file)?;
    let algo = choose("algo", o.algo, pick("algo")?, Algo::Mlac).map_err(with_file)?;
    let approx = choose("approx", o.approx, pick("approx")?, ApproxKind::Llr).map_err(with_file)?;
    let horizon = choose(
        "horizon",
        o.horizon,
        pick("horizon")?,
        HorizonKind::Infinite,
    )
    .map_err(with_file)?;
    let preset = crate::preset::preset(system, algo, approx, horizon).map_err(with_file)?;
    let mut merged = toml::Table::try_from(&preset).expect("a preset always serialises");
    // The observer section is written only when it differs from the default; a user's
    // file may still set any of its keys.
    merged.entry("observer").or_insert_with(|| {
        toml::Value::Table(toml::Table::try_from(ObserverConfig::default()).expect("serialises"))
    });
    // So are the optional keys of `[run]`.
    if let Some(toml::Value::Table(run)) = merged.get_mut("run") {
        for key in ["delay_from", "delay_column"] {
            run.entry(key)
                .or_insert_with(|| toml::Value::String(String::new()));
        }
    }
    // And an LSTD critic's prior.
    if let Some(toml::Value::Table(critic)) = merged.get_mut("critic")
        && critic.contains_key("initial_a")
    {
        critic
            .entry("prior")
            .or_insert_with(|| toml::Value::String("zero".into()));
    }
    merge(&mut merged, user, "").map_err(with_file)?;
    check_observer_choices(&merged).map_err(with_file)?;
    check_choice::<LstdPrior>(&merged, "critic", "prior").map_err(with_file)?;
    let mut cfg: ExperimentConfig = toml::Value::Table(merged)
        .try_into()
        .map_err(|e: toml::de::Error| with_file(err("", e.message())))?;
    cfg.system = system;
    cfg.algo = algo;
    cfg.approx = approx;
    cfg.horizon = horizon;
    if let Some(v) = o.trials {
        cfg.run.trials = v;
    }
    if let Some(v) = o.runs {
        cfg.run.runs = v;
    }
    if let Some(v) = o.seed {
        cfg.run.seed = v;
    }
    if let Some(v) = o.delay_ms {
        cfg.run.delay_ms = v;
    }
    if let Some(v) = &o.delay_from {
        cfg.run.delay_from.clone_from(v);
    }
    if let Some(v) = &o.delay_column {
        cfg.run.delay_column.clone_from(v);
    }
    if let Some(v) = o.observer_mode {
        cfg.observer.mode = v;
    }
    if let Some(v) = o.eval_every {
        cfg.run.eval_every = v;
    }
    if let Some(v) = o.sensor {
        cfg.observer.sensor = v;
    }
    if let Some(v) = o.observer {
        cfg.observer.observer = v;
    }
    cfg.validate().map_err(with_file)?;
    Ok(cfg)
}

/// Checks the spellings of the `[observer]` choice keys, so that a wrong one is reported
/// with its key and the allowed values.
fn check_observer_choices(merged: &toml::Table) -> Result<(), ConfigError> {
    check_choice::<SensorKind>(merged, "observer", "sensor")?;
    check_choice::<ObserverKind>(merged, "observer", "observer")?;
    check_choice::<ObserverModel>(merged, "observer", "model")?;
    check_choice::<ObserverMode>(merged, "observer", "mode")
}

/// `[section] key`, when present, is one of `T`'s spellings; the error names the key and
/// the allowed values.
fn check_choice<T: Choice>(
    merged: &toml::Table,
    section: &str,
    key: &str,
) -> Result<(), ConfigError> {
    let Some(toml::Value::Table(t)) = merged.get(section) else {
        return Ok(());
    };
    let full = format!("{section}.{key}");
    match t.get(key) {
        None => Ok(()),
        Some(toml::Value::String(s)) => T::parse(s)
            .map(|_| ())
            .map_err(|_| err(&full, format!("\"{s}\" is not one of: {}", T::spellings()))),
        Some(v) => Err(err(
            &full,
            format!("{v} must be a string, one of: {}", T::spellings()),
        )),
    }
}

/// The value of a choice key: the command line's, else the file's spelling, else
/// `default`.
fn choose<T: Choice>(
    key: &str,
    flag: Option<T>,
    file: Option<String>,
    default: T,
) -> Result<T, ConfigError> {
    match (flag, file) {
        (Some(v), _) => Ok(v),
        (None, Some(s)) => {
            T::parse(&s).map_err(|_| err(key, format!("\"{s}\" is not one of: {}", T::spellings())))
        }
        (None, None) => Ok(default),
    }
}

/// Overlays `user` on `base`, rejecting keys `base` does not have.
fn merge(base: &mut toml::Table, user: toml::Table, prefix: &str) -> Result<(), ConfigError> {
    for (k, v) in user {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        let Some(slot) = base.get_mut(&k) else {
            let mut known: Vec<&str> = base.keys().map(String::as_str).collect();
            known.sort();
            let place = if prefix.is_empty() {
                "at the top level".to_string()
            } else {
                format!("in [{prefix}]")
            };
            return Err(err(
                &key,
                format!(
                    "unknown key; the keys allowed {place} are: {}",
                    known.join(", ")
                ),
            ));
        };
        match (slot, v) {
            (toml::Value::Table(b), toml::Value::Table(u)) => merge(b, u, &key)?,
            (toml::Value::Table(_), other) => {
                return Err(err(&key, format!("must be a table, not {other}")));
            }
            (slot, v) => {
                if std::mem::discriminant(slot) != std::mem::discriminant(&v)
                    && !matches!(
                        (&*slot, &v),
                        (toml::Value::Float(_), toml::Value::Integer(_))
                    )
                {
                    return Err(err(
                        &key,
                        format!(
                            "{v} has the wrong type: expected a {} like {slot}",
                            slot.type_str()
                        ),
                    ));
                }
                *slot = match (&*slot, v) {
                    (toml::Value::Float(_), toml::Value::Integer(i)) => {
                        toml::Value::Float(i as f64)
                    }
                    (_, v) => v,
                };
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resolve_str(text: &str) -> Result<ExperimentConfig, ConfigError> {
        resolve(Some((Path::new("exp.toml"), text)), &Overrides::default())
    }

    #[test]
    fn default_is_pendulum_mlac_llr_with_table_3_2() {
        let c = resolve(None, &Overrides::default()).unwrap();
        assert_eq!(
            (c.system, c.algo, c.approx),
            (SystemName::Pendulum, Algo::Mlac, ApproxKind::Llr)
        );
        let Some(Component::Llr(actor)) = &c.actor else {
            panic!()
        };
        assert_eq!(
            (actor.alpha, actor.memory, actor.neighbours),
            (0.05, 2000, 25)
        );
    }

    #[test]
    fn file_overrides_and_round_trips() {
        let c =
            resolve_str("algo = \"sac\"\n[critic]\nneighbours = 12\n[run]\nruns = 3\n").unwrap();
        assert_eq!(c.algo, Algo::Sac);
        assert_eq!(c.run.runs, 3);
        let Component::Llr(critic) = &c.critic else {
            panic!()
        };
        assert_eq!(critic.neighbours, 12);
        let again: ExperimentConfig = toml::from_str(&c.to_toml()).unwrap();
        assert_eq!(again, c);
        // A resolved configuration fed back as a file resolves to itself.
        assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
    }

    #[test]
    fn unknown_key_is_named() {
        let e = resolve_str("[actor]\nalpa = 0.1\n").unwrap_err();
        assert_eq!(e.key, "actor.alpa");
        assert!(
            e.to_string()
                .starts_with("exp.toml: `actor.alpa`: unknown key"),
            "{e}"
        );
        assert!(
            e.message
                .contains("alpha, clip_to_neighbours, eviction, memory, neighbours"),
            "{e}"
        );
    }

    #[test]
    fn out_of_range_is_named_with_the_range() {
        let e = resolve_str("[learning]\ngamma = 1.5\n").unwrap_err();
        assert_eq!(e.key, "learning.gamma");
        assert!(e.message.contains("(0, 1)"), "{e}");
        let e = resolve_str("[critic]\nneighbours = 0\n").unwrap_err();
        assert_eq!(e.key, "critic.neighbours");
        assert!(e.message.contains("1..=128"), "{e}");
        let e = resolve_str("[actor]\nweights = [1.0]\n").unwrap_err();
        assert_eq!(e.key, "actor.weights");
        let e = resolve_str("[actor]\nmemory = \"big\"\n").unwrap_err();
        assert!(e.message.contains("wrong type"), "{e}");
        let e = resolve_str("system = \"cartpole\"\n").unwrap_err();
        assert!(e.message.contains("pendulum, arm-vertical"), "{e}");
    }

    #[test]
    fn finite_horizon_adds_time_to_actor_and_critic() {
        let c = resolve_str("horizon = \"finite\"\nalgo = \"sac\"\napprox = \"rbf\"\n").unwrap();
        assert_eq!(c.horizon, HorizonKind::Finite);
        assert_eq!(c.learning.gamma, 1.0, "Algorithms 4–6 do not discount");
        assert_eq!(resolve_str(&c.to_toml()).unwrap(), c);
        let e = resolve_str("horizon = \"finit\"\n").unwrap_err();
        assert_eq!(e.key, "horizon");
        assert!(e.to_string().starts_with("exp.toml: `horizon`"), "{e}");
        assert!(e.message.contains("infinite, finite"), "{e}");
        let fh = "horizon = \"finite\"\nalgo = \"mlac\"\napprox = \"rbf\"\n";
        let e = resolve_str(&format!("{fh}[critic]\ncentres = [9, 9]\n")).unwrap_err();
        assert_eq!(e.key, "critic.centres");
        assert!(
            e.message
                .contains("must have 3, one per state component and time"),
            "{e}"
        );
        assert!(resolve_str(&format!("{fh}[learning]\ngamma = 1.01\n")).is_err());
        let e = resolve_str("[learning]\ngamma = 1.0\n").unwrap_err();
        assert_eq!(e.key, "learning.gamma", "an infinite horizon must discount");
        let e =
            resolve_str("horizon = \"finite\"\nalgo = \"vgbp\"\napprox = \"lstd\"\n").unwrap_err();
        assert_eq!(e.key, "horizon");
        let e =
            resolve_str("horizon = \"finite\"\nalgo = \"sac\"\napprox = \"llr\"\n").unwrap_err();
        assert_eq!(e.key, "approx");
        // Validation, for a configuration not made by `resolve`.
        let mut c = c;
        c.algo = Algo::Sarsa;
        assert_eq!(c.validate().unwrap_err().key, "horizon");
    }

    #[test]
    fn tile_coding_is_for_sac_only() {
        let o = Overrides {
            algo: Some(Algo::Mlac),
            approx: Some(ApproxKind::Tiles),
            ..Default::default()
        };
        let e = resolve(None, &o).unwrap_err();
        assert_eq!(e.key, "approx");
    }

    #[test]
    fn the_default_observer_section_is_not_written() {
        let c = resolve(None, &Overrides::default()).unwrap();
        assert!(c.observer.is_default());
        assert!(!c.to_toml().contains("[observer]"));
    }

    #[test]
    fn observer_keys_resolve_and_round_trip() {
        let text = "[observer]\nsensor = \"angle\"\ncounts_per_rev = 1024\nobserver = \"predictive\"\nmodel = \"known\"\n";
        let c = resolve(Some((Path::new("o.toml"), text)), &Overrides::default()).unwrap();
        assert_eq!(c.observer.sensor, SensorKind::Angle);
        assert_eq!(c.observer.counts_per_rev, 1024);
        assert_eq!(c.observer.model, ObserverModel::Known);
        let again = resolve(
            Some((Path::new("c.toml"), &c.to_toml())),
            &Overrides::default(),
        )
        .unwrap();
        assert_eq!(again, c);
    }

    #[test]
    fn lstd_prior_choices_and_errors() {
        let vgbp = "algo = \"vgbp\"\napprox = \"lstd\"\n";
        let none = Overrides::default();
        let file = |text: String| resolve(Some((Path::new("v.toml"), &text)), &none);
        let prior = |c: &ExperimentConfig| match &c.critic {
            Component::Lstd(l) => l.prior,
            other => panic!("not LSTD: {other:?}"),
        };
        assert_eq!(prior(&file(vgbp.to_string()).unwrap()), LstdPrior::Zero);
        let c = file(format!("{vgbp}[critic]\nprior = \"reward\"\n")).unwrap();
        assert_eq!(prior(&c), LstdPrior::Reward);
        // The default is not written; the other choice is, and reads back.
        assert!(!file(vgbp.to_string()).unwrap().to_toml().contains("prior"));
        let again = file(c.to_toml()).unwrap();
        assert_eq!(prior(&again), LstdPrior::Reward);
        let e = file(format!("{vgbp}[critic]\nprior = \"pessimistic\"\n"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "v.toml: `critic.prior`: \"pessimistic\" is not one of: zero, reward"
        );
    }

    #[test]
    fn observer_errors_name_file_key_and_range() {
        let bad = |text: &str, o: &Overrides| {
            resolve(Some((Path::new("o.toml"), text)), o)
                .unwrap_err()
                .to_string()
        };
        let none = Overrides::default();
        let e = bad("[observer]\nsensor = \"camera\"\n", &none);
        assert_eq!(
            e,
            "o.toml: `observer.sensor`: \"camera\" is not one of: full, angle"
        );
        let e = bad("[observer]\ncounts_per_rev = 2\n", &none);
        assert!(
            e.starts_with("o.toml: `observer.counts_per_rev`: 2 is out of range"),
            "{e}"
        );
        let e = bad("[observer]\ngain = 2.5\n", &none);
        assert!(e.contains("`observer.gain`") && e.contains("[0, 2)"), "{e}");
        let e = bad("[observer]\nnoise_std = -1.0\n", &none);
        assert!(e.contains("`observer.noise_std`"), "{e}");
        let angle = Overrides {
            sensor: Some(SensorKind::Angle),
            ..Default::default()
        };
        let e = bad("", &angle);
        assert!(
            e.contains("`observer.observer`") && e.contains("pass-through"),
            "{e}"
        );
        let e = bad("[observer]\nfilter = 1.0\n", &none);
        assert!(e.contains("`observer.filter`"), "{e}");
    }

    #[test]
    fn timing_and_delay_keys_resolve_round_trip_and_are_checked() {
        let text =
            "[observer]\nsensor = \"angle\"\nobserver = \"predictive\"\nmode = \"predictive\"\n";
        let c = resolve(Some((Path::new("t.toml"), text)), &Overrides::default()).unwrap();
        assert_eq!(c.observer.mode, ObserverMode::Predictive);
        let again = resolve(
            Some((Path::new("c.toml"), &c.to_toml())),
            &Overrides::default(),
        );
        assert_eq!(again.unwrap(), c);
        let bad = |text: &str| {
            resolve(Some((Path::new("t.toml"), text)), &Overrides::default())
                .unwrap_err()
                .to_string()
        };
        let e = bad("[observer]\nmode = \"predictive\"\n");
        assert!(
            e.contains("`observer.mode`") && e.contains("predictive"),
            "{e}"
        );
        let e = bad("[observer]\nmode = \"late\"\n");
        assert!(
            e.contains("`observer.mode`") && e.contains("direct, predictive"),
            "{e}"
        );
        let csv = std::env::temp_dir().join(format!("cfg-delays-{}.csv", std::process::id()));
        std::fs::write(&csv, "delay_ms\n1\n2\n").unwrap();
        let from = format!("[run]\ndelay_from = {:?}\n", csv.display().to_string());
        let c = resolve(Some((Path::new("t.toml"), &from)), &Overrides::default()).unwrap();
        assert!(c.to_toml().contains("delay_from"));
        let e = bad(&format!("{from}delay_ms = 3.0\n"));
        assert!(
            e.contains("`run.delay_from`") && e.contains("exclusive"),
            "{e}"
        );
        let e = bad("[run]\ndelay_column = \"x_ms\"\n");
        assert!(e.contains("`run.delay_column`"), "{e}");
        // The default configuration does not mention the optional keys.
        let plain = resolve(None, &Overrides::default()).unwrap().to_toml();
        assert!(!plain.contains("delay_from") && !plain.contains("\nmode ="));
    }
}
