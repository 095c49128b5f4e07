//! Why `rig latency` was refused or could not measure.

use std::path::PathBuf;

use observer::config::ObserverKind;
use plant::config::ConfigError;
use runtime::error::FileError;
use runtime::process::SystemError;
use runtime::report::PlotError;
use runtime::run::RunError;

use crate::loop_bench::LoopError;

/// Why `rig latency` was refused, or what stopped it.
#[derive(Debug, thiserror::Error)]
pub enum LatencyError {
    /// The experiment's configuration.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The run measured.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The ping-pong baseline.
    #[error(transparent)]
    Baseline(#[from] LoopError),
    /// The process could not be placed, prioritised or kept from deep sleep.
    #[error(transparent)]
    System(#[from] SystemError),
    /// An output or a recorded file could not be read or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The histograms could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The recording could not be read.
    #[error(transparent)]
    Mcap(#[from] mcap::McapError),
    /// The rig's own executable, which runs the ping-pong, was not found.
    #[error("cannot find the rig executable")]
    Executable(#[source] std::io::Error),
    /// A period out of range.
    #[error("`--period-ms` {0} is out of range: must be a number in [0.1, 1000]")]
    Period(f64),
    /// A lockstep clock asked for.
    #[error("`rig latency` measures real time: a lockstep clock has no period")]
    Lockstep,
    /// The predictive mode asked for with an external driver.
    #[error(
        "`--observer-mode predictive` needs the simulated plant: an external driver applies each action as it arrives (`--observer-mode direct`, the default with `--driver`)"
    )]
    PredictiveDriver,
    /// The predictive mode asked for with an observer that does not predict.
    #[error(
        "`--observer-mode predictive` (rig latency's default) needs `--observer predictive` (its process model predicts x̂_(k+1|k)); with `--observer {0}` add `--observer-mode direct`"
    )]
    PredictiveObserver(ObserverKind),
    /// No cycles asked for.
    #[error("`--cycles` must be at least 1")]
    NoCyclesAsked,
    /// A sweep that would not shorten the period.
    #[error("sweep factor {0} must be > 1")]
    SweepFactor(f64),
    /// A sweep asked for with an external driver.
    #[error("`--sweep` needs the simulated plant: an external driver keeps its own period")]
    SweepDriver,
    /// A topic the recording lacks.
    #[error("the recording has no {0}")]
    NoTopic(String),
    /// A recorded message that is not JSON.
    #[error("{topic}: {error}")]
    Json {
        /// The message's topic.
        topic: String,
        /// Why it could not be parsed.
        error: serde_json::Error,
    },
    /// A recorded message without a field.
    #[error("{topic}: a message without {key}")]
    NoKey {
        /// The message's topic.
        topic: String,
        /// The field.
        key: String,
    },
    /// A line of the plant's cycles that is not four integers.
    #[error("{}: bad line {line:?}", path.display())]
    BadLine {
        /// The cycles' file.
        path: PathBuf,
        /// The line.
        line: String,
        /// The number that could not be read, if one could not.
        #[source]
        source: Option<std::num::ParseIntError>,
    },
    /// The plant recorded no cycle.
    #[error("{}: no cycles were recorded", .0.display())]
    NoCycles(PathBuf),
    /// The driver received no action.
    #[error("the recording has no action commands to the driver")]
    NoCommands,
}
