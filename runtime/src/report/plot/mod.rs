//! Learning-curve plots in the style of the thesis's figures.
//!
//! The x axis is simulated time in minutes, the y axis the sum of rewards per
//! trial. A [`SeriesStyle::Band`] series is drawn like Figures 3.6–3.19: a light
//! band between the min and max over runs, a darker band for the 95 % confidence
//! interval of the mean, and the mean as a solid line. Several series can share
//! one plot, like Figures 3.12 and 3.23; [`SeriesStyle::Line`] draws only the
//! mean (dashed), which keeps crowded overlays readable.
//!
//! Text is rendered in pure Rust (plotters' `ab_glyph` feature) with the Ubuntu
//! Light typeface embedded by the `epaint_default_fonts` crate, licensed under
//! the Ubuntu Font Licence 1.0. No system font library is needed.
//!
//! The same house style serves distributions ([`plot_histograms`]) and means with
//! error bars ([`plot_points`]); [`Drawing`] and [`render`] draw any other picture.

mod curves;
mod histograms;
mod points;

pub use curves::{Series, SeriesStyle, X_LABEL, Y_LABEL, plot_curves};
pub use histograms::{Histogram, plot_histograms};
pub use points::{PointSeries, plot_points};

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use super::error::{DrawError, PlotError};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::{CoordTranslate, Shift};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::{FontStyle, RGBColor, register_font};

/// Size in pixels of the PNG (and SVG) image.
pub const PLOT_SIZE: (u32, u32) = (1000, 600);

/// Series colours, used in order and repeated when there are more series
/// (the "tableau 10" palette, which stays distinguishable when shaded).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Width in pixels of a legend key.
pub const KEY_WIDTH: i32 = 24;

/// A picture that draws itself the same way on any plotters backend.
pub trait Drawing {
    /// Draws the picture on `root`.
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static;
}

/// Draws `picture` into a PNG and an SVG image of [`PLOT_SIZE`].
pub fn render(png: &Path, svg: &Path, picture: &impl Drawing) -> Result<(), PlotError> {
    register_fonts()?;
    let image = |path: &Path, why| PlotError::Image {
        path: path.to_path_buf(),
        why,
    };
    picture
        .draw(BitMapBackend::new(png, PLOT_SIZE).into_drawing_area())
        .map_err(|why| image(png, why))?;
    picture
        .draw(SVGBackend::new(svg, PLOT_SIZE).into_drawing_area())
        .map_err(|why| image(svg, why))
}

/// Registers the embedded font as plotters' `sans-serif`, once per process.
pub fn register_fonts() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// A chart in the house style on `root`: caption, axis descriptions, tick labels to the
/// span's precision, a light mesh; drawn, ready for series.
fn styled_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    (x_label, y_label): (&str, &str),
    x: Range<f64>,
    y: Range<f64>,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, DrawError>
where
    DB::ErrorType: 'static,
{
    let (x_span, y_span) = (x.end - x.start, y.end - y.start);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 26))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .axis_desc_style(("sans-serif", 20))
        .label_style(("sans-serif", 16))
        .x_label_formatter(&|v| tick_label(*v, x_span))
        .y_label_formatter(&|v| tick_label(*v, y_span))
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.08))
        .draw()?;
    Ok(chart)
}

/// The range of `values`, widened by `fraction` of its span on each side (see
/// `Extent::padded`).
pub fn padded_range(values: impl Iterator<Item = f64>, fraction: f64) -> Range<f64> {
    let mut e = Extent::default();
    for v in values {
        e.add(v);
    }
    e.padded(fraction)
}

/// The smallest interval holding a set of finite numbers.
#[derive(Default)]
struct Extent(Option<(f64, f64)>);

impl Extent {
    /// Widens the interval to hold `v`.
    fn add(&mut self, v: f64) {
        self.0 = Some(match self.0 {
            None => (v, v),
            Some((lo, hi)) => (lo.min(v), hi.max(v)),
        });
    }

    /// The interval widened by `fraction` of its span on each side. An empty
    /// span is widened by 5 % of its magnitude (at least 1) so that plotters
    /// always gets a non-empty range.
    fn padded(&self, fraction: f64) -> Range<f64> {
        let (lo, hi) = self.0.unwrap_or((0.0, 1.0));
        let pad = if hi > lo {
            fraction * (hi - lo)
        } else {
            (0.05 * lo.abs()).max(1.0)
        };
        lo - pad..hi + pad
    }
}

/// A tick label for `v` on an axis spanning `span`, with just enough decimals
/// for the ticks plotters picks (about ten per axis) and never "-0".
pub fn tick_label(v: f64, span: f64) -> String {
    let decimals = (1.0 - span.log10()).ceil().clamp(0.0, 9.0) as usize;
    let scale = 10f64.powi(decimals as i32);
    // Adding 0.0 turns a rounded -0.0 into 0.0.
    format!("{:.decimals$}", (v * scale).round() / scale + 0.0)
}

/// The palette, repeated forever.
pub fn colours() -> impl Iterator<Item = RGBColor> {
    PALETTE.iter().copied().cycle()
}

/// The legend of `chart`'s labelled series in the house style, at `position`, its
/// labels in `font_size` px.
pub fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", font_size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .draw()?;
    Ok(())
}

/// Legend key of a dashed line.
fn dashed_key(
    x: i32,
    y: i32,
    style: ShapeStyle,
) -> DashedPathElement<std::array::IntoIter<(i32, i32), 2>, i32> {
    DashedPathElement::new([(x, y), (x + KEY_WIDTH, y)], 6, 3, style)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(-1000.0, 2600.0), "-1000");
        assert_eq!(tick_label(2.0, 20.0), "2");
        assert_eq!(tick_label(0.5, 2.0), "0.5");
        assert_eq!(tick_label(0.30000000000000004, 1.0), "0.3");
        assert_eq!(tick_label(-1e-13, 2600.0), "0");
        assert_eq!(tick_label(0.05, 0.2), "0.05");
    }
}
