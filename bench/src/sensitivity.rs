//! The sensitivity analysis's plot (thesis §3.7 and §7.2.1 left the analysis as future
//! work): per algorithm a column, the final greedy return (upper row) and the rise time
//! t₉₀ (lower row) over the factor each parameter is scaled by (logarithmic axis), one
//! line per parameter through the preset at factor 1.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use runtime::report::plot::{
    Drawing, KEY_WIDTH, colours, draw_legend, padded_range, render, tick_label,
};
use runtime::report::{DrawError, PlotError};

/// One parameter's line: `(factor, final greedy return, rise time [min])` per point,
/// ordered by factor.
#[derive(Clone, Debug)]
pub struct Sweep<'a> {
    /// The parameter's name (legend entry).
    pub parameter: &'a str,
    /// The points, the preset (factor 1) included.
    pub points: Vec<(f64, f64, f64)>,
}

/// Plots each algorithm's sweeps `(algorithm, sweeps)` into a PNG and an SVG image.
///
/// # Errors
/// Fails if there is nothing to plot, a factor is not positive, a number is not finite,
/// or an image cannot be written.
pub fn plot_sensitivity(
    png: &Path,
    svg: &Path,
    title: &str,
    algorithms: &[(&str, Vec<Sweep>)],
) -> Result<(), PlotError> {
    if algorithms.is_empty() || algorithms.iter().any(|(_, s)| s.is_empty()) {
        return Err(PlotError::data(title, "nothing to plot"));
    }
    let fine =
        |p: &(f64, f64, f64)| p.0 > 0.0 && p.0.is_finite() && p.1.is_finite() && p.2.is_finite();
    for (algo, sweeps) in algorithms {
        if let Some(s) = sweeps.iter().find(|s| !s.points.iter().all(fine)) {
            let why = format!(
                "{algo} {} has a non-finite value or a factor ≤ 0",
                s.parameter
            );
            return Err(PlotError::data(title, why));
        }
    }
    render(png, svg, &Sensitivity { title, algorithms })
}

struct Sensitivity<'a> {
    title: &'a str,
    algorithms: &'a [(&'a str, Vec<Sweep<'a>>)],
}

/// Which number of a point a row shows, and its axis label.
type Row = (&'static str, fn(&(f64, f64, f64)) -> f64);

impl Drawing for Sensitivity<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let root = root.titled(self.title, ("sans-serif", 24))?;
        let panels = root.split_evenly((2, self.algorithms.len()));
        let points = || {
            self.algorithms
                .iter()
                .flat_map(|(_, s)| s.iter().flat_map(|s| s.points.iter()))
        };
        let (lo, hi) = points().fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| {
            (lo.min(p.0), hi.max(p.0))
        });
        let x = (lo / 1.3)..(hi * 1.3);
        let mut factors: Vec<f64> = points().map(|p| p.0).collect();
        factors.sort_by(f64::total_cmp);
        factors.dedup();
        let rows: [Row; 2] = [("final greedy return", |p| p.1), ("t₉₀ [min]", |p| p.2)];
        for (r, (y_label, value)) in rows.into_iter().enumerate() {
            // One y range per row, so the algorithms compare at a glance.
            let y = padded_range(points().map(value), 0.05);
            let y_span = y.end - y.start;
            for (c, (algo, sweeps)) in self.algorithms.iter().enumerate() {
                let area = &panels[r * self.algorithms.len() + c];
                let mut chart = ChartBuilder::on(area)
                    .caption(*algo, ("sans-serif", 18))
                    .margin(10)
                    .x_label_area_size(36)
                    .y_label_area_size(70)
                    .build_cartesian_2d(
                        x.clone().log_scale().with_key_points(factors.clone()),
                        y.clone(),
                    )?;
                chart
                    .configure_mesh()
                    .x_desc("factor on the preset's value")
                    .y_desc(y_label)
                    .axis_desc_style(("sans-serif", 15))
                    .label_style(("sans-serif", 13))
                    .x_label_formatter(&|v| format!("×{v}"))
                    .y_label_formatter(&|v| tick_label(*v, y_span))
                    .light_line_style(WHITE.mix(0.0))
                    .bold_line_style(BLACK.mix(0.08))
                    .draw()?;
                for (s, colour) in sweeps.iter().zip(colours()) {
                    let line = colour.stroke_width(2);
                    let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, value(p))).collect();
                    chart
                        .draw_series(LineSeries::new(pts.clone(), line))?
                        .label(s.parameter)
                        .legend(move |(x, y)| PathElement::new([(x, y), (x + KEY_WIDTH, y)], line));
                    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
                }
                if r == 0 && c == 0 {
                    draw_legend(&mut chart, SeriesLabelPosition::LowerLeft, 13)?;
                }
            }
        }
        root.present()?;
        Ok(())
    }
}
