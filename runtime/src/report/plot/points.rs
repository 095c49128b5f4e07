//! Means with 95 % confidence-interval error bars over a numeric x axis.

use std::ops::Range;
use std::path::Path;

use crate::report::error::{DrawError, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Drawing, KEY_WIDTH, PALETTE, dashed_key, draw_legend, padded_range, render, styled_chart,
};

/// One series of [`plot_points`]: a legend entry and its points `(x, mean, ci_low,
/// ci_high)`, ordered by `x`.
pub struct PointSeries<'a> {
    /// Legend entry.
    pub label: &'a str,
    /// `(x, mean, ci_low, ci_high)` per point.
    pub points: &'a [(f64, f64, f64, f64)],
    /// Dashed (else solid) line.
    pub dashed: bool,
    /// Index into [`PALETTE`] (modulo its length).
    pub colour: usize,
}

/// Plots means with 95 % confidence-interval error bars over a numeric x axis (e.g. a
/// final return per injected delay), into a PNG and an SVG image; each series has its
/// colour from [`PALETTE`].
///
/// # Errors
///
/// Fails if there is no point, a number is not finite, or an image cannot be written.
pub fn plot_points(
    png: &Path,
    svg: &Path,
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[PointSeries],
) -> Result<(), PlotError> {
    let all = || series.iter().flat_map(|s| s.points.iter());
    if all().next().is_none() {
        return Err(PlotError::data(title, "no points"));
    }
    if let Some(p) = all().find(|p| ![p.0, p.1, p.2, p.3].iter().all(|v| v.is_finite())) {
        return Err(PlotError::data(title, format!("non-finite value in {p:?}")));
    }
    let x = padded_range(all().map(|p| p.0), 0.05);
    let y = padded_range(all().flat_map(|p| [p.1, p.2, p.3]), 0.08);
    render(
        png,
        svg,
        &Points {
            title,
            labels: (x_label, y_label),
            series,
            x,
            y,
        },
    )
}

/// [`plot_points`]' input with its axis ranges.
struct Points<'a> {
    title: &'a str,
    labels: (&'a str, &'a str),
    series: &'a [PointSeries<'a>],
    x: Range<f64>,
    y: Range<f64>,
}

impl Drawing for Points<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let Points {
            title,
            labels: (x_label, y_label),
            series,
            ..
        } = *self;
        let (x, y) = (self.x.clone(), self.y.clone());
        root.fill(&WHITE)?;
        let x_span = x.end - x.start;
        let mut chart = styled_chart(&root, title, (x_label, y_label), x, y)?;
        // Offset the error bars of the series a little so that they do not hide each other.
        let shift = 0.006 * x_span;
        let mid = (series.len() as f64 - 1.0) / 2.0;
        for (i, s) in series.iter().enumerate() {
            let colour = PALETTE[s.colour % PALETTE.len()];
            let dx = (i as f64 - mid) * shift;
            let line = colour.stroke_width(2);
            let mean = s.points.iter().map(|p| (p.0 + dx, p.1));
            if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(mean, 8, 5, line))?
                    .label(s.label)
                    .legend(move |(x, y)| dashed_key(x, y, line));
            } else {
                chart
                    .draw_series(LineSeries::new(mean, line))?
                    .label(s.label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + KEY_WIDTH, y)], line));
            }
            // Error bars: the interval and its caps.
            let cap = 0.008 * x_span;
            chart.draw_series(s.points.iter().flat_map(|p| {
                let x = p.0 + dx;
                [
                    vec![(x, p.2), (x, p.3)],
                    vec![(x - cap, p.2), (x + cap, p.2)],
                    vec![(x - cap, p.3), (x + cap, p.3)],
                ]
                .map(|path| PathElement::new(path, line))
            }))?;
            chart.draw_series(
                s.points
                    .iter()
                    .map(|p| Circle::new((p.0 + dx, p.1), 4, colour.filled())),
            )?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerLeft, 16)?;
        root.present()?;
        Ok(())
    }
}
