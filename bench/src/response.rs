//! Time responses of learned policies, like the thesis's Figures 4.1b, 5.2a and 6.2: one
//! greedy trial of each policy, its first state component (the angle `φ`, or `φ₁` of an
//! arm) over time in the upper panel and its first action component in the lower.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use runtime::report::plot::{Drawing, colours, draw_legend, padded_range, render, tick_label};
use runtime::report::{DrawError, PlotError};
use runtime::response::ResponseSample;

/// Plots the time responses `(label, samples)` into a PNG and an SVG image.
///
/// # Errors
/// Fails if there is no response, one is empty or holds a non-finite number, or an image
/// cannot be written.
pub fn plot_responses(
    png: &Path,
    svg: &Path,
    title: &str,
    responses: &[(&str, &[ResponseSample])],
    labels: (&str, &str),
) -> Result<(), PlotError> {
    if responses.is_empty() {
        return Err(PlotError::data(title, "no time response"));
    }
    for (label, r) in responses {
        if r.is_empty() {
            return Err(PlotError::data(
                title,
                format!("response '{label}' is empty"),
            ));
        }
        let finite =
            |s: &ResponseSample| s.t.is_finite() && s.x[0].is_finite() && s.u[0].is_finite();
        if !r.iter().all(finite) {
            let why = format!("response '{label}' has a non-finite value");
            return Err(PlotError::data(title, why));
        }
    }
    render(
        png,
        svg,
        &Responses {
            title,
            responses,
            labels,
        },
    )
}

/// [`plot_responses`]' input.
struct Responses<'a> {
    title: &'a str,
    responses: &'a [(&'a str, &'a [ResponseSample])],
    labels: (&'a str, &'a str),
}

/// Which number of a sample a panel shows.
type Component = fn(&ResponseSample) -> f64;

impl Drawing for Responses<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let Responses {
            title,
            responses,
            labels: (x_label, u_label),
        } = *self;
        root.fill(&WHITE)?;
        let root = root.titled(title, ("sans-serif", 24))?;
        let panels = root.split_evenly((2, 1));
        let t_end = responses
            .iter()
            .flat_map(|(_, r)| r.iter().map(|s| s.t))
            .fold(0.0, f64::max);
        let panel_specs: [(&str, Component); 2] = [(x_label, |s| s.x[0]), (u_label, |s| s.u[0])];
        for ((y_label, value), area) in panel_specs.into_iter().zip(&panels) {
            let y = padded_range(
                responses.iter().flat_map(|(_, r)| r.iter().map(value)),
                0.05,
            );
            let y_span = y.end - y.start;
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..t_end.max(1e-3), y)?;
            chart
                .configure_mesh()
                .x_desc("Time [s]")
                .y_desc(y_label)
                .axis_desc_style(("sans-serif", 18))
                .label_style(("sans-serif", 14))
                .y_label_formatter(&|v| tick_label(*v, y_span))
                .light_line_style(WHITE.mix(0.0))
                .bold_line_style(BLACK.mix(0.08))
                .draw()?;
            for ((label, r), colour) in responses.iter().zip(colours()) {
                let style = colour.stroke_width(2);
                chart
                    .draw_series(LineSeries::new(r.iter().map(|s| (s.t, value(s))), style))?
                    .label(*label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 24, y)], style));
            }
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
        }
        root.present()?;
        Ok(())
    }
}
