//! Learning-curve reports: statistics across runs, CSV files and plots.
//!
//! The thesis evaluates every algorithm by its *learning curve*, the sum of
//! rewards per trial over simulated time, repeated for 30 (chapter 3) or 20
//! (chapters 5 and 6) independent learning experiments. Its figures show the
//! mean, the min–max range and the 95 % confidence interval of the mean
//! (e.g. Figures 3.6, 3.10, 3.11, 3.13, 3.14, 3.18, 3.19) and overlay several
//! algorithms in one plot (Figures 3.12 and 3.23).
//!
//! - [`curve`](mod@curve) reduces per-run values to those statistics
//!   ([`curve()`]) and writes them as deterministic CSV ([`write_curve_csv`]).
//! - [`plot`] draws one or more curves in that style into a PNG and an SVG
//!   ([`plot_curves`]).

pub mod curve;
mod error;
pub mod plot;

pub use curve::{CurvePoint, curve, write_curve_csv};
pub use error::{CurveError, DrawError, PlotError, PointError};
pub use plot::{Series, SeriesStyle, plot_curves};
