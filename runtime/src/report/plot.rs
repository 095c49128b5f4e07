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

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Context, Result, bail, ensure};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::{FontStyle, RGBColor, register_font};

use super::curve::CurvePoint;

/// Size in pixels of the PNG (and SVG) image.
pub const PLOT_SIZE: (u32, u32) = (1000, 600);

/// Label of the x axis.
pub const X_LABEL: &str = "Time [min]";

/// Label of the y axis.
pub const Y_LABEL: &str = "Sum of rewards per trial";

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

/// Opacity of the min–max band.
const RANGE_ALPHA: f64 = 0.15;
/// Opacity of the 95 % confidence band.
const CI_ALPHA: f64 = 0.35;
/// Width in pixels of a legend key.
pub const KEY_WIDTH: i32 = 24;
/// Colour of the reference line and of the legend keys that explain the bands.
const NEUTRAL: RGBColor = RGBColor(90, 90, 90);

/// How a [`Series`] is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Mean as a solid line, with a light min–max band and a darker band for
    /// the 95 % confidence interval of the mean.
    Band,
    /// Mean only, as a dashed line.
    Line,
}

/// One learning curve in a plot.
#[derive(Clone, Debug)]
pub struct Series<'a> {
    /// Legend entry.
    pub label: String,
    /// The curve, ordered by simulated time.
    pub points: &'a [CurvePoint],
    /// How the curve is drawn.
    pub style: SeriesStyle,
}

/// Plots learning curves into a PNG and an SVG image of the same plot.
///
/// Series get colours from [`PALETTE`] in order. `reference`, if given, is drawn
/// as a dashed horizontal line with its label in the legend (e.g. the return of
/// the optimal policy). The y range covers everything drawn, padded so that a
/// flat curve still renders.
///
/// # Errors
///
/// Fails if `series` is empty, a series has no points, its times decrease, any
/// number is NaN or infinite, or an image cannot be written.
pub fn plot_curves(
    png: &Path,
    svg: &Path,
    title: &str,
    series: &[Series],
    reference: Option<(&str, f64)>,
) -> Result<()> {
    render(png, svg, &Plot::new(title, series, reference)?)
}

/// A picture that draws itself the same way on any plotters backend.
pub trait Drawing {
    /// Draws the picture on `root`.
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// Draws `picture` into a PNG and an SVG image of [`PLOT_SIZE`].
pub fn render(png: &Path, svg: &Path, picture: &impl Drawing) -> Result<()> {
    register_fonts()?;
    picture
        .draw(BitMapBackend::new(png, PLOT_SIZE).into_drawing_area())
        .with_context(|| format!("writing {}", png.display()))?;
    picture
        .draw(SVGBackend::new(svg, PLOT_SIZE).into_drawing_area())
        .with_context(|| format!("writing {}", svg.display()))
}

/// Registers the embedded font as plotters' `sans-serif`, once per process.
pub fn register_fonts() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    ensure!(ok, "the embedded Ubuntu Light font could not be loaded");
    Ok(())
}

/// Validated input of [`plot_curves`] together with the axis ranges.
struct Plot<'s, 'a> {
    title: &'s str,
    series: &'s [Series<'a>],
    reference: Option<(&'s str, f64)>,
    x: Range<f64>,
    y: Range<f64>,
}

impl<'s, 'a> Plot<'s, 'a> {
    /// Checks the input and computes the axis ranges (x in minutes).
    fn new(
        title: &'s str,
        series: &'s [Series<'a>],
        reference: Option<(&'s str, f64)>,
    ) -> Result<Self> {
        ensure!(!series.is_empty(), "plot '{title}': no series to plot");
        // Learning curves start at time zero, like the thesis's figures.
        let mut x = Extent::default();
        x.add(0.0);
        let mut y = Extent::default();
        for s in series {
            ensure!(
                !s.points.is_empty(),
                "plot '{title}': series '{}' has no points",
                s.label
            );
            for (i, p) in s.points.iter().enumerate() {
                let fields = [p.sim_time_s, p.mean, p.min, p.max, p.ci_low, p.ci_high];
                if fields.iter().any(|v| !v.is_finite()) {
                    bail!(
                        "plot '{title}': series '{}', trial {}: non-finite value in {p:?}",
                        s.label,
                        p.trial
                    );
                }
                if i > 0 && p.sim_time_s < s.points[i - 1].sim_time_s {
                    bail!(
                        "plot '{title}': series '{}': time decreases at trial {}",
                        s.label,
                        p.trial
                    );
                }
                x.add(minutes(p));
                y.add(p.mean);
                if s.style == SeriesStyle::Band {
                    for v in [p.min, p.max, p.ci_low, p.ci_high] {
                        y.add(v);
                    }
                }
            }
        }
        if let Some((label, value)) = reference {
            ensure!(
                value.is_finite(),
                "plot '{title}': reference '{label}' is {value}"
            );
            y.add(value);
        }
        Ok(Self {
            title,
            series,
            reference,
            x: x.padded(0.0),
            y: y.padded(0.05),
        })
    }
}

/// A chart in the house style on `root`: caption, axis descriptions, tick labels to the
/// span's precision, a light mesh; drawn, ready for series.
fn styled_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    (x_label, y_label): (&str, &str),
    x: Range<f64>,
    y: Range<f64>,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>>
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

impl Drawing for Plot<'_, '_> {
    /// Draws the plot onto `root` and presents it.
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let mut chart = styled_chart(
            &root,
            self.title,
            (X_LABEL, Y_LABEL),
            self.x.clone(),
            self.y.clone(),
        )?;

        let mut any_band = false;
        // Shaded bands first, so that no band hides another series' mean line.
        for (s, colour) in self.series.iter().zip(colours()) {
            if s.style == SeriesStyle::Band {
                any_band = true;
                chart.draw_series([
                    band(s.points, |p| (p.min, p.max), colour.mix(RANGE_ALPHA)),
                    band(s.points, |p| (p.ci_low, p.ci_high), colour.mix(CI_ALPHA)),
                ])?;
            }
        }
        for (s, colour) in self.series.iter().zip(colours()) {
            let mean = s.points.iter().map(|p| (minutes(p), p.mean));
            let line = colour.stroke_width(2);
            match s.style {
                SeriesStyle::Band => chart
                    .draw_series(LineSeries::new(mean, line))?
                    .label(s.label.as_str())
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + KEY_WIDTH, y)], line)),
                SeriesStyle::Line => chart
                    .draw_series(DashedLineSeries::new(mean, 8, 5, line))?
                    .label(s.label.as_str())
                    .legend(move |(x, y)| dashed_key(x, y, line)),
            };
            if let [p] = s.points {
                // A line through one point is invisible: mark the point instead.
                chart.draw_series([Circle::new((minutes(p), p.mean), 4, colour.filled())])?;
            }
        }
        if let Some((label, value)) = self.reference {
            let ends = [(self.x.start, value), (self.x.end, value)];
            let style = NEUTRAL.stroke_width(2);
            chart
                .draw_series(DashedLineSeries::new(ends, 10, 6, style))?
                .label(label)
                .legend(move |(x, y)| dashed_key(x, y, style));
        }
        if any_band {
            // Legend-only entries that explain the two shades of a band series.
            for (label, alpha) in [
                ("min–max over runs", RANGE_ALPHA),
                ("95 % CI of the mean", CI_ALPHA),
            ] {
                let shade = NEUTRAL.mix(alpha).filled();
                chart
                    .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
                    .label(label)
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 6), (x + KEY_WIDTH, y + 6)], shade)
                    });
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .label_font(("sans-serif", 16))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()?;
        root.present()?;
        Ok(())
    }
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

/// Simulated time of `p` in minutes.
fn minutes(p: &CurvePoint) -> f64 {
    p.sim_time_s / 60.0
}

/// A filled polygon between the lower and upper bounds given by `bounds`.
fn band(
    points: &[CurvePoint],
    bounds: impl Fn(&CurvePoint) -> (f64, f64),
    colour: RGBAColor,
) -> Polygon<(f64, f64)> {
    let upper = points.iter().map(|p| (minutes(p), bounds(p).1));
    let lower = points.iter().rev().map(|p| (minutes(p), bounds(p).0));
    Polygon::new(upper.chain(lower).collect::<Vec<_>>(), colour.filled())
}

/// Legend key of a dashed line.
fn dashed_key(
    x: i32,
    y: i32,
    style: ShapeStyle,
) -> DashedPathElement<std::array::IntoIter<(i32, i32), 2>, i32> {
    DashedPathElement::new([(x, y), (x + KEY_WIDTH, y)], 6, 3, style)
}

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
) -> Result<()> {
    ensure!(
        x_max.is_finite() && x_max > 0.0 && bins > 0,
        "histogram '{title}': x range [0, {x_max}] with {bins} bins"
    );
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
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>
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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", 16))
            .draw()?;
        root.present()?;
        Ok(())
    }
}

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
) -> Result<()> {
    let all = || series.iter().flat_map(|s| s.points.iter());
    ensure!(all().next().is_some(), "plot '{title}': no points");
    if let Some(p) = all().find(|p| ![p.0, p.1, p.2, p.3].iter().all(|v| v.is_finite())) {
        bail!("plot '{title}': non-finite value in {p:?}");
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
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>
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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .label_font(("sans-serif", 16))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()?;
        root.present()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::curve::curve;
    use std::fs;
    use std::path::PathBuf;

    /// A fresh, empty directory under the system temp dir.
    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("rig-report-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A synthetic learning curve: 400 trials of 3 s, `runs` runs, learning with
    /// time constant `tau` trials towards `final_return`, with a deterministic
    /// spread between runs.
    fn synthetic(runs: usize, tau: f64, final_return: f64) -> Vec<CurvePoint> {
        let trials: Vec<u32> = (1..=400).collect();
        let times: Vec<f64> = trials.iter().map(|&k| 3.0 * f64::from(k)).collect();
        let values: Vec<Vec<f64>> = trials
            .iter()
            .map(|&k| {
                let k = f64::from(k);
                (0..runs)
                    .map(|r| {
                        let r = r as f64;
                        let progress = 1.0 - (-k / (tau * (1.0 + 0.1 * r))).exp();
                        let noise = 60.0 * ((k * 0.37 + r * 1.7).sin()) * (1.0 - progress);
                        -3000.0 + (final_return + 3000.0) * progress + noise - 5.0 * r
                    })
                    .collect()
            })
            .collect();
        curve(&trials, &times, &values).unwrap()
    }

    /// Width and height from the IHDR chunk of a PNG file.
    fn png_size(bytes: &[u8]) -> (u32, u32) {
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
        assert_eq!(&bytes[12..16], b"IHDR");
        let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
        (be(16), be(20))
    }

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(-1000.0, 2600.0), "-1000");
        assert_eq!(tick_label(2.0, 20.0), "2");
        assert_eq!(tick_label(0.5, 2.0), "0.5");
        assert_eq!(tick_label(0.30000000000000004, 1.0), "0.3");
        assert_eq!(tick_label(-1e-13, 2600.0), "0");
        assert_eq!(tick_label(0.05, 0.2), "0.05");
    }

    #[test]
    fn renders_png_and_svg() {
        let dir = temp_dir("plot");
        let (png, svg) = (dir.join("curves.png"), dir.join("curves.svg"));
        let sac = synthetic(30, 60.0, -800.0);
        let mlac = synthetic(30, 20.0, -700.0);
        let series = [
            Series {
                label: "SAC/RBF".into(),
                points: &sac,
                style: SeriesStyle::Band,
            },
            Series {
                label: "MLAC/LLR".into(),
                points: &mlac,
                style: SeriesStyle::Band,
            },
        ];
        plot_curves(
            &png,
            &svg,
            "Pendulum swing-up",
            &series,
            Some(("optimal", -650.0)),
        )
        .unwrap();

        let bytes = fs::read(&png).unwrap();
        assert_eq!(png_size(&bytes), PLOT_SIZE);
        let text = fs::read_to_string(&svg).unwrap();
        for needle in [
            "<svg",
            "Pendulum swing-up",
            "SAC/RBF",
            "MLAC/LLR",
            "optimal",
            X_LABEL,
            Y_LABEL,
        ] {
            assert!(text.contains(needle), "SVG lacks {needle:?}");
        }
        if let Ok(keep) = std::env::var("RIG_REPORT_SAMPLE") {
            fs::copy(&png, keep).unwrap();
        }
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn flat_and_line_series_render() {
        let dir = temp_dir("flat");
        let (png, svg) = (dir.join("flat.png"), dir.join("flat.svg"));
        let flat = curve(&[1, 2], &[3.0, 6.0], &[vec![-1.0, -1.0], vec![-1.0]]).unwrap();
        let one = curve(&[1], &[3.0], &[vec![5.0]]).unwrap();
        let series = [
            Series {
                label: "flat".into(),
                points: &flat,
                style: SeriesStyle::Band,
            },
            Series {
                label: "single point".into(),
                points: &one,
                style: SeriesStyle::Line,
            },
        ];
        plot_curves(&png, &svg, "flat", &series[..1], None).unwrap();
        plot_curves(&png, &svg, "one", &series[1..], Some(("same", 5.0))).unwrap();
        assert_eq!(png_size(&fs::read(&png).unwrap()), PLOT_SIZE);
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn degenerate_input_rejected() {
        let dir = temp_dir("bad");
        let (png, svg) = (dir.join("bad.png"), dir.join("bad.svg"));
        let err = plot_curves(&png, &svg, "t", &[], None).unwrap_err();
        assert!(err.to_string().contains("no series"), "{err}");

        let empty = Series {
            label: "e".into(),
            points: &[],
            style: SeriesStyle::Band,
        };
        let err = plot_curves(&png, &svg, "t", &[empty], None).unwrap_err();
        assert!(err.to_string().contains("no points"), "{err}");

        let band = |points| Series {
            label: "s".into(),
            points,
            style: SeriesStyle::Band,
        };
        let good = curve(&[1, 2], &[3.0, 6.0], &[vec![1.0], vec![2.0]]).unwrap();
        let mut nan = good.clone();
        nan[1].ci_high = f64::NAN;
        let err = plot_curves(&png, &svg, "t", &[band(&nan)], None).unwrap_err();
        assert!(err.to_string().contains("non-finite"), "{err}");

        let inf = Some(("inf", f64::INFINITY));
        assert!(plot_curves(&png, &svg, "t", &[band(&good)], inf).is_err());

        let backwards = [good[1].clone(), good[0].clone()];
        let err = plot_curves(&png, &svg, "t", &[band(&backwards)], None).unwrap_err();
        assert!(err.to_string().contains("time decreases"), "{err}");
        assert!(!png.exists() && !svg.exists());
        fs::remove_dir_all(dir).unwrap();
    }
}
