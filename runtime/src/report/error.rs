//! What can go wrong in a report: a curve of bad numbers, a plot of nothing, a file
//! that cannot be written.

use crate::error::FileError;

/// Why a learning curve could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum CurveError {
    /// The trials, times and value rows differ in length.
    #[error("curve: length mismatch: {trials} trials, {times} times, {rows} value rows")]
    Lengths {
        /// Trials given.
        trials: usize,
        /// Simulated times given.
        times: usize,
        /// Rows of values given.
        rows: usize,
    },
    /// A trial's simulated time is NaN or infinite.
    #[error("curve: trial {trial}: simulated time is {time}")]
    Time {
        /// The trial.
        trial: u32,
        /// Its time.
        time: f64,
    },
    /// A point's statistics could not be computed.
    #[error("curve: trial {trial} (t = {time} s)")]
    Point {
        /// The trial.
        trial: u32,
        /// Its simulated time, s.
        time: f64,
        /// Why.
        #[source]
        why: PointError,
    },
    /// A run has no greedy evaluation to judge it by.
    #[error("run {run} has no greedy evaluation (more trials than run.eval_every needed)")]
    NoEvaluation {
        /// The run.
        run: u32,
    },
    /// The curve's file could not be written.
    #[error(transparent)]
    File(#[from] FileError),
}

/// Why one point of a curve could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum PointError {
    /// No run has a value there.
    #[error("no values")]
    NoValues,
    /// A run's value is NaN or infinite.
    #[error("run {run} has non-finite value {value}")]
    NonFinite {
        /// The run.
        run: usize,
        /// Its value.
        value: f64,
    },
    /// The sum of the values overflows `f64`.
    #[error("the sum of the values overflows f64")]
    SumOverflow,
    /// The confidence interval overflows `f64`.
    #[error("the confidence interval overflows f64")]
    IntervalOverflow,
    /// Student's t distribution refused the degrees of freedom.
    #[error("Student's t with {dof} degrees of freedom: {why}")]
    StudentsT {
        /// Degrees of freedom.
        dof: usize,
        /// statrs's words.
        why: String,
    },
}

/// Why a plot could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Nothing, or nothing finite, to draw.
    #[error("plot '{title}': {why}")]
    Data {
        /// The plot's title.
        title: String,
        /// What is wrong with its data.
        why: String,
    },
    /// The embedded font could not be registered with plotters.
    #[error("the embedded Ubuntu Light font could not be loaded")]
    Font,
    /// Drawing into an image failed.
    #[error("writing {}", path.display())]
    Image {
        /// The image.
        path: std::path::PathBuf,
        /// plotters' error.
        #[source]
        why: DrawError,
    },
}

/// An error of a plotters backend, whatever the backend.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct DrawError(Box<dyn std::error::Error + Send + Sync>);

impl<E: std::error::Error + Send + Sync + 'static> From<plotters::drawing::DrawingAreaErrorKind<E>>
    for DrawError
{
    fn from(e: plotters::drawing::DrawingAreaErrorKind<E>) -> Self {
        Self(Box::new(e))
    }
}

impl PlotError {
    /// A plot titled `title` whose data is wrong in the way `why` says.
    pub fn data(title: &str, why: impl Into<String>) -> Self {
        Self::Data {
            title: title.to_string(),
            why: why.into(),
        }
    }
}
