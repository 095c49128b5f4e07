//! Why `rig reproduce` could not regenerate a figure.

use plant::config::ConfigError;
use runtime::error::FileError;
use runtime::learn::LearnError;
use runtime::report::{CurveError, PlotError};

use crate::optimal::OptimumError;

/// What stopped the reproduction.
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    /// `--only` names no figure of this command.
    #[error("`--only` {id:?}: not a figure this command regenerates; one of {figures}")]
    NoFigure {
        /// The figure asked for.
        id: String,
        /// The figures there are, in words.
        figures: String,
    },
    /// The reference optimum could not be computed.
    #[error(transparent)]
    Optimum(#[from] OptimumError),
    /// An experiment could not be learned.
    #[error(transparent)]
    Learn(#[from] LearnError),
    /// `--runs` or `--trials` out of the range of `[run]`.
    #[error("`--runs`/`--trials`")]
    RunCount(#[from] ConfigError),
    /// An output could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// A figure's folder could not be created.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A curve's final greedy returns could not be computed: the curve's label.
    #[error("{label}")]
    Measure {
        /// The curve.
        label: String,
        /// Why.
        #[source]
        source: CurveError,
    },
}
