//! Learning curves: the mean over runs with its min–max and confidence bands, over
//! simulated time.

use std::ops::Range;
use std::path::Path;

use crate::report::error::{DrawError, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::super::curve::CurvePoint;
use super::{Drawing, Extent, KEY_WIDTH, colours, dashed_key, draw_legend, render, styled_chart};

/// Label of the x axis.
pub const X_LABEL: &str = "Time [min]";

/// Label of the y axis.
pub const Y_LABEL: &str = "Sum of rewards per trial";

/// Opacity of the min–max band.
const RANGE_ALPHA: f64 = 0.15;
/// Opacity of the 95 % confidence band.
const CI_ALPHA: f64 = 0.35;
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
/// Series get colours from [`PALETTE`](super::PALETTE) in order. `reference`, if
/// given, is drawn as a dashed horizontal line with its label in the legend (e.g. the
/// return of the optimal policy). The y range covers everything drawn, padded so that a
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
) -> Result<(), PlotError> {
    render(png, svg, &Plot::new(title, series, reference)?)
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
    ) -> Result<Self, PlotError> {
        let no = |why: String| Err(PlotError::data(title, why));
        if series.is_empty() {
            return no("no series to plot".into());
        }
        // Learning curves start at time zero, like the thesis's figures.
        let mut x = Extent::default();
        x.add(0.0);
        let mut y = Extent::default();
        for s in series {
            if s.points.is_empty() {
                return no(format!("series '{}' has no points", s.label));
            }
            for (i, p) in s.points.iter().enumerate() {
                let fields = [p.sim_time_s, p.mean, p.min, p.max, p.ci_low, p.ci_high];
                if fields.iter().any(|v| !v.is_finite()) {
                    return no(format!(
                        "series '{}', trial {}: non-finite value in {p:?}",
                        s.label, p.trial
                    ));
                }
                if i > 0 && p.sim_time_s < s.points[i - 1].sim_time_s {
                    return no(format!(
                        "series '{}': time decreases at trial {}",
                        s.label, p.trial
                    ));
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
            if !value.is_finite() {
                return no(format!("reference '{label}' is {value}"));
            }
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

impl Drawing for Plot<'_, '_> {
    /// Draws the plot onto `root` and presents it.
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError>
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
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, 16)?;
        root.present()?;
        Ok(())
    }
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

#[cfg(test)]
mod tests {
    use super::super::PLOT_SIZE;
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
