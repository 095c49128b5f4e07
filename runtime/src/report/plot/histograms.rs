//! Distributions as histogram outlines on a logarithmic count axis.

use std::path::Path;

use crate::report::error::{DrawError, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Drawing, KEY_WIDTH, colours, draw_legend, render};

/// One distribution in [`plot_histograms`]: a legend entry and its values.
pub struct Histogram<'a> {
    /// Legend entry.
    pub label: &'a str,
    /// The values (x-axis units).
    pub values: &'a [f64],
}

/// Plots distributions as histogram outlines over one x axis (`bins` equal bins on
/// `[0, x_max]`; larger values are counted in the last bin) with a logarithmic count
/// axis, so that rare tails stay visible; into a PNG and an SVG image.
pub fn plot_histograms(
    png: &Path,
    svg: &Path,
    title: &str,
    x_label: &str,
    series: &[Histogram],
    x_max: f64,
    bins: usize,
) -> Result<(), PlotError> {
    if !(x_max.is_finite() && x_max > 0.0 && bins > 0) {
        let why = format!("x range [0, {x_max}] with {bins} bins");
        return Err(PlotError::data(title, why));
    }
    let width = x_max / bins as f64;
    let counts: Vec<Vec<u64>> = series
        .iter()
        .map(|h| {
            let mut c = vec![0u64; bins];
            for v in h.values.iter().filter(|v| v.is_finite()) {
                c[((v.max(0.0) / width) as usize).min(bins - 1)] += 1;
            }
            c
        })
        .collect();
    let top = counts.iter().flatten().copied().max().unwrap_or(1).max(1) as f64 * 2.0;
    render(
        png,
        svg,
        &Histograms {
            title,
            x_label,
            series,
            counts: &counts,
            x_max,
            width,
            top,
        },
    )
}

/// [`plot_histograms`]' input with the bin counts.
struct Histograms<'a> {
    title: &'a str,
    x_label: &'a str,
    series: &'a [Histogram<'a>],
    counts: &'a [Vec<u64>],
    x_max: f64,
    width: f64,
    top: f64,
}

impl Drawing for Histograms<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let Histograms {
            title,
            x_label,
            series,
            counts,
            x_max,
            width,
            top,
        } = *self;
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 26))
            .margin(15)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..x_max, (0.5..top).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc("Cycles")
            .axis_desc_style(("sans-serif", 20))
            .label_style(("sans-serif", 16))
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.08))
            .draw()?;
        for ((h, c), colour) in series.iter().zip(counts).zip(colours()) {
            // The outline of the bars: a step line, empty bins drawn at the axis.
            let mut pts = Vec::with_capacity(2 * c.len() + 2);
            for (i, &n) in c.iter().enumerate() {
                let y = (n as f64).max(0.5);
                pts.push((i as f64 * width, y));
                pts.push(((i + 1) as f64 * width, y));
            }
            let line = colour.stroke_width(2);
            chart
                .draw_series(LineSeries::new(pts, line))?
                .label(h.label)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + KEY_WIDTH, y)], line));
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 16)?;
        root.present()?;
        Ok(())
    }
}
